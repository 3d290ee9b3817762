"""`accugrid identify` as one call: a measurement CSV in, the calibrated robot files and the
report text out (``kinematics.identification`` does the fit, ``kinematics.calibrated`` the YAML).

Lengths in mm, angles in rad where named, else deg; the measurement CSV of docs/formats.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accugrid import __version__
from accugrid.compensation.budget import budget_section
from accugrid.compensation.measurements import check_joint_limits, read_measurements
from accugrid.infra.errors import InputError, printable
from accugrid.infra.inputfile import read_input_bytes
from accugrid.infra.units import check_scale
from accugrid.kinematics.calibrated import calibrated_yaml, identification_summary
from accugrid.kinematics.frames import xyzabc_from_pose
from accugrid.kinematics.identification import (
    LAST_LINK,
    Identification,
    PoseSet,
    Terms,
    identify,
)
from accugrid.kinematics.model import reach_mm
from accugrid.kinematics.robot import VALIDATED_MAX_KEYS, Robot
from accugrid.kinematics.structure import (
    RANGE_BLOCKS,
    STRUCTURE_WORD,
    Selection,
    identify_structure,
)
from accugrid.kinematics.support import Structure, support_section
from accugrid.kinematics.validity import validity_section

__all__ = [
    "MAX_ROWS",
    "STRUCTURES",
    "Calibration",
    "IdentifyOptions",
    "calibrate",
    "controller_text",
]

MAX_ROWS = 100_000  # measurement rows identify takes (a tracker session has hundreds)
_METHOD = {word: method for method, word in STRUCTURE_WORD.items()}  # --structure -> method
STRUCTURES = (*_METHOD, "dh")  # --structure: chosen by ARD or the forward search; DH + TCP only


@dataclass(frozen=True)
class IdentifyOptions:
    """What to identify besides the DH errors and TCP, and how to validate it."""

    status: int | None = None  # KUKA Status of rows without logged joints or column s
    base_frame: bool = False  # the tracker-to-robot frame
    compliance: bool = False  # A2/A3 compliance under gravity
    harmonics: Terms = ()  # (axis 1..6, order) reducer harmonics, pinned
    folds: int = 5  # k-fold cross-validation (0: none; auto: the search's and nested folds)
    structure: str = "auto"  # STRUCTURES
    max_order: int | None = None  # highest harmonic order searched (None: from the poses)


@dataclass(frozen=True)
class Calibration:
    """The identification, the output texts by path and the report printed for the user."""

    result: Identification
    files: dict[str, str]
    report: str
    selection: Selection | None = None
    controller: str = ""  # controller_text: the logged joints' mismatch, or what to log


def _data_lines(path: str | Path) -> int:
    """The lines of a CSV file that are neither blank nor comments, less its header row."""
    lines = read_input_bytes(path).splitlines()
    return sum(1 for line in lines if line.strip() and not line.lstrip().startswith(b"#")) - 1


def calibrate(
    measurements: str | Path,
    robot: Robot,
    options: IdentifyOptions,
    output: str,
    urdf: str | None = None,
) -> Calibration:
    """Identify ``robot`` (nominal model with the measurement tool) from the measurement CSV and
    render the calibrated robot YAML for ``output`` (and its URDF for ``urdf``)."""
    if options.folds < 0 or options.folds == 1:
        raise InputError(f"--folds must be 0 (none) or at least 2, got {options.folds}")
    rows = _data_lines(measurements)  # before the reader, which takes long over 1e6 rows
    if rows > MAX_ROWS:
        raise InputError(
            f"{rows} measurement rows; identify takes at most {MAX_ROWS} (its time and memory "
            "grow with the rows, 1e5 rows take about a minute); measure fewer poses or fewer "
            "repeats",
            measurements,
        )
    if options.structure not in STRUCTURES:
        raise InputError(
            f"--structure {options.structure!r}: one of {', '.join(STRUCTURES)} (auto: the "
            "joint-error terms chosen by sparse Bayesian learning; search: by forward "
            "selection; dh: DH errors and TCP only)"
        )
    auto = options.structure in _METHOD
    if auto and options.folds == 0:
        raise InputError("--folds 0: choosing the structure needs folds; add --structure dh")
    if not auto and options.max_order is not None:
        raise InputError("--max-order chooses the harmonics searched by --structure auto or search")
    meas = read_measurements(measurements)
    check_scale(meas.commanded, reach_mm(robot), "commanded position", meas.path, meas.lines)
    check_joint_limits(meas, robot.joint_limits_deg, robot.name)
    status = meas.status if meas.status is not None else options.status
    data = meas.pose_set(robot, status)
    selection = None
    if auto:
        result, selection = identify_structure(
            robot,
            data,
            base_frame=options.base_frame,
            compliance=options.compliance,
            harmonics=options.harmonics,
            max_order=options.max_order,
            folds=options.folds,
            method=_METHOD[options.structure],
        )
    else:
        result = identify(
            robot,
            data,
            base_frame=options.base_frame,
            compliance=options.compliance,
            folds=options.folds,
            harmonics=options.harmonics,
        )
    source = printable(Path(measurements).name)  # a non-UTF-8 byte: escaped text
    summary = identification_summary(result, robot, source, meas.sha256, selection, data.controller)
    validated = _validated_max(summary)  # the same claim the file's reader takes
    summary["validity"] = validity_section(data.commanded, data.rotations, data.q, validated)
    structure = _structure(options, result, selection)
    support = _support(robot, data, options, result, structure)
    if support is not None:
        summary["support"] = support
    held_out = _held_out_rms(result, selection)
    if held_out is not None:
        summary["budget"] = budget_section(
            result.robot, data.q, data.group, structure, result.residuals, held_out
        )
    header = f"accugrid {__version__} identify: {robot.name} calibrated from {source}"
    files = {output: calibrated_yaml(result.robot, summary, header)}
    report = _report(output, robot, result)
    controller = controller_text(robot, data)
    if controller:
        report += "\n" + controller
    if selection is not None:
        report += "\n" + _structure_report(selection)
    if support is not None:
        leverage, distance = support["loo_leverage_max"], support["loo_distance_max_mm"]
        report += (
            f"\n  support: targets of a prediction leverage above {leverage:.4g} or farther than "
            f"{distance:.1f} mm (TCP motion) in joint space from every pose (the largest among "
            "these poses, left out in turn) are flagged and corrected by the DH-only fit of the "
            "same poses, recorded beside the model (--strict refuses them)"
        )
    if urdf:
        from accugrid.kinematics.urdf_export import urdf_text

        files[urdf] = urdf_text(result.robot)
        joint_terms = result.robot.joint_errors is not None
        extra = " (geometric part only: URDF has no joint errors)" if joint_terms else ""
        report += f"\nwrote {urdf}{extra}"
    return Calibration(result, files, report, selection, controller)


def controller_text(robot: Robot, data: PoseSet) -> str:
    """One line on the controller's own kinematics: how far the commanded positions lie from the
    nominal model's FK of the logged joints (where some row misses beyond its printed
    decimals), or, without logged joints, what to log; "" when the joints agree."""
    mismatch = data.controller
    if mismatch is None:
        return (
            "  joints not logged: identified at the nominal IK of the commanded poses; a "
            "controller with its own calibration (factory or absolute-accuracy option) moves "
            "its TCP by tenths of a mm from that model, which then enters the identified "
            "errors: log the controller's actual joint angles as columns a1..a6"
        )
    if not mismatch.rows:
        return ""
    return (
        f"  controller: its commanded positions differ from the nominal {robot.name}'s FK of "
        f"the logged joints by {mismatch.mean_mm:.4f} mm mean, {mismatch.max_mm:.4f} max "
        f"({mismatch.rows} of {len(data)} rows beyond their printed decimals): the "
        "controller's own calibration; identified from the logged joints (what the robot did)"
    )


def _structure(
    options: IdentifyOptions, result: Identification, selection: Selection | None
) -> Structure:
    """The parameters the model was identified with (``kinematics.support.Structure``)."""
    structure = Structure(
        options.base_frame,
        options.compliance,
        tuple(options.harmonics if selection is None else selection.harmonics),
        () if selection is None else tuple(selection.gravity),
    )
    if structure.names != result.names:
        raise ValueError("the structure's parameters differ from the identification's")
    return structure


def _held_out_rms(result: Identification, selection: Selection | None) -> np.ndarray | None:
    """(3,) mm: the k-fold held-out RMS of the chosen model (the last kept step of the
    structure's cross-validation curve, which starts with DH + TCP, else the identification's own
    folds); None without folds."""
    if selection is not None:
        return selection.curve[selection.kept].rms_mm
    if result.cross_validation is not None:
        return result.cross_validation.rms_mm
    return None


def _support(
    robot: Robot,
    data: PoseSet,
    options: IdentifyOptions,
    result: Identification,
    structure: Structure,
) -> dict | None:
    """``identification.support`` (``kinematics.support``) of a model with joint-error terms:
    its leverage map and the DH-only fit of the same poses, the fallback where it has no
    support; None for a DH + TCP model (its own fallback)."""
    if not (structure.compliance or structure.harmonics or structure.gravity):
        return None
    dh = identify(robot, data, base_frame=options.base_frame, folds=options.folds)
    return support_section(result.robot, data.q, data.group, structure, dh)


def _validated_max(summary: dict) -> np.ndarray:
    """(3,) mm: the validated error the identification summary claims, found at the first of
    ``robot.VALIDATED_MAX_KEYS`` it holds (the reader of the written file takes the same)."""
    for key in VALIDATED_MAX_KEYS:
        section = summary
        for name in key:
            section = section.get(name) if isinstance(section, dict) else None
        if section is not None:
            return np.array([section[axis] for axis in "xyz"], dtype=float)
    raise ValueError("the identification summary holds no residual")


def _per_axis(label: str, rms: np.ndarray, peak: np.ndarray) -> str:
    cells = "  ".join(
        f"{axis} rms {r:.4f} max {m:.4f}" for axis, r, m in zip("XYZ", rms, peak, strict=True)
    )
    return f"  {label}: {cells}"


def _report(path: str, robot: Robot, result: Identification) -> str:
    """The lines ``accugrid identify`` prints: fit quality, validation, parameters."""
    lines = [
        f"{path}: {robot.name} calibrated from {result.poses} poses ({result.rows} rows); "
        f"{result.rank} of {len(result.x)} parameters identifiable, condition number "
        f"{result.condition_number:.1f}, observability O1 {result.o1:.4f}"
    ]
    if result.unidentifiable_text:
        lines.append("  unidentifiable (held at 0): " + "; ".join(result.unidentifiable_text))
    lines.append(_per_axis("residual (measured - model), mm", result.rms_mm, result.max_mm))
    if result.cross_validation is not None:
        cv = result.cross_validation
        lines.append(
            _per_axis(f"{cv.folds}-fold cross-validation, held-out poses, mm", cv.rms_mm, cv.max_mm)
        )
    if result.outliers:
        shown = ", ".join(result.outliers[:10]) + (" ..." if len(result.outliers) > 10 else "")
        lines.append(
            f"  {len(result.outliers)} outlier rows (beyond 3 x {result.sigma_mm:.4f} mm): {shown}"
        )
    if result.tracker_T_robot is not None:
        x, y, z, a, b, c = xyzabc_from_pose(result.tracker_T_robot)
        lines.append(
            f"  tracker_T_robot x {x:.3f} y {y:.3f} z {z:.3f} mm, a {a:.4f} b {b:.4f} c {c:.4f} deg"
        )
    lines.append("  identified parameters (value +- std):")
    cells = [
        f"{name} {value:+.4g} +- {std:.2g} {unit}"
        for name, value, std, unit, ok in zip(
            result.names, result.x, result.std, result.units, result.identifiable, strict=True
        )
        if ok
    ]
    lines += ["    " + " | ".join(cells[i : i + 4]) for i in range(0, len(cells), 4)]
    held = set(result.names[LAST_LINK])
    tied = [
        n
        for n, ok in zip(result.names, result.identifiable, strict=True)
        if not ok and n not in held
    ]
    if tied:
        lines.append(
            "  determined only in the combinations above (minimum-norm values in the file): "
            + ", ".join(tied)
        )
    return "\n".join(lines)


def _structure_report(selection: Selection) -> str:
    """The lines on the chosen structure: terms, the cross-validation curve, what was left out,
    the nested estimate of the accuracy."""
    chosen = ", ".join(selection.chosen) or "none (DH errors and TCP only)"
    how = {
        "ard": "sparse Bayesian learning (each group's evidence over the poses' means)",
        "search": f"forward selection by {selection.folds}-fold cross-validation over the poses",
    }[selection.method]
    lines = [
        f"  structure chosen by {how} from {selection.candidates} candidate groups (harmonic "
        f"orders 1..{selection.max_order}: {selection.max_order_rule}; gravity of every "
        f"axis gravity loads, without masses): {chosen}"
    ]
    if selection.pinned:
        lines.append("  pinned (always kept): " + ", ".join(selection.pinned))
    lines.append("  cross-validation curve (held-out measured - model, mm; * = chosen model):")
    for i, step in enumerate(selection.curve):
        label = "DH + TCP" + (" + pinned" if selection.pinned else "") if i == 0 else step.added
        mark = "*" if i == selection.kept else " "
        rms = " ".join(f"{v:.4f}" for v in step.rms_mm)
        peak = " ".join(f"{v:.4f}" for v in step.max_mm)
        lines.append(
            f"   {mark}{'' if i == 0 else '+ '}{label} ({step.parameters} parameters): "
            f"RMS X Y Z {rms}  max {peak}"
        )
    if selection.left_out:
        shown = "; ".join(f"{name} ({why})" for name, why in selection.left_out[:6])
        more = len(selection.left_out) - 6
        lines.append(f"  left out: {shown}" + (f"; and {more} more" if more > 0 else ""))
    nested = selection.nested
    if nested is not None:
        rms = " ".join(f"{v:.4f}" for v in nested.rms_mm)
        peak = " ".join(f"{v:.4f}" for v in nested.max_mm)
        line = (
            f"  expected accuracy (nested {nested.folds}-fold cross-validation, the selection "
            f"repeated inside each fold), held-out measured - model: RMS X Y Z {rms}  max {peak}"
        )
        if nested.model_rms_mm is not None:
            model = " ".join(f"{v:.4f}" for v in nested.model_rms_mm)
            line += f"; the model alone (row noise {nested.noise_mm:.4f} mm removed): RMS {model}"
        lines.append(line)
    carry = selection.carry_over
    if carry is not None:
        rms = " ".join(f"{v:.4f}" for v in carry.rms_mm)
        dh = " ".join(f"{v:.4f}" for v in carry.dh_rms_mm)
        lines.append(
            f"  held out by joint range (each joint's range in {RANGE_BLOCKS} blocks, each "
            f"predicted from the rest): RMS X Y Z {rms}; DH + TCP only {dh}"
            + (
                ""
                if carry.holds
                else ": the chosen terms do not hold beyond the joint combinations of these "
                "poses; measure poses that cover the targets' joint space (targets without "
                "support get the DH-only fit)"
            )
        )
    return "\n".join(lines)
