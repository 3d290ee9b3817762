"""The measurement-plan job (``accugrid plan``): the positions a laser-tracker operator
measures, in order, as a CSV skeleton (``Plan.csv_text``) and the robot program that visits them
(the measurement program of a dialect's plug-in, ``codegen.plugin.MeasurementWriter``; by
default the first registered dialect that writes one), every position checked with the robot's
IK in one KUKA Status (``compensation.plans.reach_in_one_status``). Lengths mm, angles deg,
speeds m/s.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accugrid.codegen.dialects import measuring, plugin_of
from accugrid.codegen.header import header_lines
from accugrid.codegen.plugin import MeasurementWriter, MeasureSettings
from accugrid.compensation.plans import (
    SEED_REPEATS,
    Plan,
    cube_plan,
    experiment_plan,
    grid_plan,
    identification_plan,
    reach_in_one_status,
)
from accugrid.infra.atomic import JobFiles
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import fixed
from accugrid.kinematics.configuration import solve_in_one_status
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.robot import Robot

__all__ = ["KINDS", "MAX_WAIT_SEC", "PlanRequest", "plan_files", "plan_targets"]

KINDS = ("grid", "cube", "experiment", "identify")
MAX_WAIT_SEC = 600.0


@dataclass(frozen=True)
class PlanRequest:
    """One plan of ``kind`` for ``robot`` (its tool: the measured point, e.g. the SMR) at the
    TCP orientation ``abc`` (KUKA deg) in one KUKA ``status`` (None: the IK default at the first
    position; ``identify``: at the region's centre).

    grid: ``region`` (xmin, xmax, ymin, ymax, zmin, zmax mm), ``step_mm``, ``order``
    ("serpentine" or "naive"), ``repeats`` rounds; cube: ``centre`` (3,) mm, ``step_mm``,
    ``repeats``; experiment: ``centres`` (name -> (3,) mm), ``steps`` (mm), ``repeats``;
    identify: ``region``, ``count`` poses within ``tilt_deg`` of ``abc`` among ``candidates``
    random ones (``seed``), ``repeats`` rounds, ``design`` "library" (for the structure search's
    candidates, ``compliance`` and ``harmonics`` as (axis, order) pairs pinned) or "dh"
    (D-optimal for the model given by ``compliance``, ``harmonics``, ``gravity``);
    tool: ``count`` orientations of ``robot``'s tool (as taught) about ``centre`` within
    ``tilt_deg`` of ``abc``, inside the joint ranges of the calibrated ``model`` file
    (``seed``), ``repeats`` rounds, with ``axis_point`` the same again for a point on the axis.
    Program: in ``dialect`` (a registered dialect that writes measurement programs; None: the
    first, ``codegen.dialects.measuring``), ``name``
    (default measure_KIND), TOOL_DATA ``tool_number``, BASE_DATA ``base_number`` (0: the robot
    frame), first-PTP ``ptp_percent``, LIN ``vel_m_s``, and after each position ``wait_input``
    ($IN number) or ``wait_sec`` s; ``templates``: a folder with the dialect's measurement
    templates (KRL: measure.src.j2 and measure.dat.j2; None: built-in)."""

    kind: str
    robot: Robot
    abc: tuple[float, float, float]
    status: int | None = None
    region: tuple[float, ...] | None = None
    step_mm: float | None = None
    order: str = "serpentine"
    repeats: int = SEED_REPEATS
    centre: tuple[float, float, float] | None = None
    centres: dict[str, tuple[float, float, float]] | None = None
    steps: np.ndarray | None = None
    count: int = 0
    tilt_deg: float = 30.0
    candidates: int = 2000
    seed: int = 0
    compliance: bool = False
    harmonics: tuple[tuple[int, int], ...] = ()
    gravity: tuple = ()  # mass-free gravity groups (kinematics.candidates.GravityTerm)
    design: str = "library"  # identify: "library" or "dh" (compensation.plans)
    name: str | None = None
    tool_number: int = 1
    base_number: int = 0
    ptp_percent: int = 20
    vel_m_s: float = 0.25
    wait_sec: float = 3.0
    wait_input: int | None = None
    templates: Path | None = None
    dialect: str | None = None
    model: str | None = None  # tool: the calibrated robot file whose joint ranges bound the poses
    axis_point: bool = False  # tool: the poses again for an SMR on the drill axis (point axis)


def _program(dialect: str | None, kind: str, name: str | None) -> tuple[MeasurementWriter, str]:
    """The measurement program of ``dialect`` (None: the first that writes one; InputError when
    it writes none) and its name: ``name`` (default measure_KIND) made one the dialect
    accepts."""
    writer = plugin_of(dialect or measuring()[0]).measurement()
    return writer, writer.name(name or f"measure_{kind}")


def plan_targets(
    output: str | Path, kind: str, name: str | None, dialect: str | None = None
) -> list[Path]:
    """The files of the job in folder ``output``: the plan CSV (named as the program's first
    file), then the measurement program's (KRL: NAME.csv, NAME.src, NAME.dat, lower case)."""
    writer, name = _program(dialect, kind, name)
    files = writer.targets(Path(output), name)
    return [files[0].with_suffix(".csv"), *files]


def plan_files(request: PlanRequest, output: str | Path) -> JobFiles:
    """The plan CSV and its measurement program in folder ``output``, and the lines to print
    (the plan's description, what was written). InputError on bad settings or a position the
    robot cannot reach in the plan's Status."""
    plan, info = _build(request)
    writer, name = _program(request.dialect, request.kind, request.name)
    csv = plan_targets(output, request.kind, request.name, request.dialect)[0]
    configuration, config = reach_in_one_status(plan, request.robot, request.status)
    settings = MeasureSettings(
        tool=request.tool_number,
        base=request.base_number,
        ptp_percent=request.ptp_percent,
        speed_m_s=request.vel_m_s,
        wait_sec=request.wait_sec,
        wait_input=request.wait_input,
        ptp_only=request.kind in ("identify", "tool"),  # reorienting between poses: PTP, not LIN
    )
    details = [
        "inputs none, positions generated from the command-line settings",
        *info,
        _orientation_text(plan, writer.listing) + f", robot {request.robot.name}, Status {config}",
    ]
    closing = [f"{len(plan.points)} positions, {writer.motion(settings)}"]
    header = header_lines(
        f"plan {request.kind}",
        details=details,
        where=", measurement positions are not corrected",
        closing=closing,
    )
    _check_program(request)
    program = writer.render(
        plan, configuration, name, header, settings, request.templates, Path(output)
    )
    files = {csv: plan.csv_text(), **program.files}
    lines = [*info, f"wrote {', '.join(str(p) for p in files)}"]
    return JobFiles(files, [], lines, main=program.main)  # what runs replaced last


def _build(r: PlanRequest) -> tuple[Plan, list[str]]:
    """The plan of the chosen kind and lines describing it."""
    if r.kind == "grid":
        box = r.region
        lo, hi = (box[0], box[2], box[4]), (box[1], box[3], box[5])
        plan = grid_plan(lo, hi, r.step_mm, r.abc)
        naive = grid_plan(lo, hi, r.step_mm, r.abc, order="naive")
        if r.order == "naive":
            plan = naive
        if int(r.repeats) < 1:
            raise InputError(f"--repeats must be >= 1, got {r.repeats}")
        steps = np.unique(np.round(np.diff(np.unique(plan.points[:, 0])), 6))
        info = [
            f"grid plan: {len(plan.points)} vertices, {r.order} order",
            f"path {plan.path_length():.1f} mm (serpentine "
            f"{grid_plan(lo, hi, r.step_mm, r.abc).path_length():.1f} mm, naive raster "
            f"{naive.path_length():.1f} mm)",
        ]
        if len(steps) and abs(steps[0] - r.step_mm) > 1e-6:
            info.append(f"note: step shrunk to partition the region exactly, X {steps[0]:.3f} mm")
        if r.repeats > 1:
            plan = Plan(
                np.tile(plan.points, (r.repeats, 1)),
                plan.abc,
                [f"{i}_R{k + 1}" for k in range(r.repeats) for i in plan.ids],
            )
        return plan, info
    if r.kind == "identify":
        return _identification_plan(r)
    if r.kind == "tool":
        return _tool_plan(r)
    if r.kind == "cube":
        plan = cube_plan(r.centre, r.step_mm, r.repeats, r.abc)
        return plan, [f"cube plan: 8 vertices + 9 test points x {r.repeats} repeats"]
    centres, steps = r.centres, r.steps
    plan = experiment_plan(centres, steps, r.repeats, r.abc)
    info = [
        f"experiment plan: {len(centres)} centres x {len(steps)} steps x 17 points x "
        f"{r.repeats} repeats = {len(plan.points)} rows",
        f"steps {', '.join(f'{s:g}' for s in steps)} mm, path {plan.path_length():.1f} mm",
    ]
    return plan, info


def _identification_plan(r: PlanRequest) -> tuple[Plan, list[str]]:
    """The D-optimal identification plan in the region, in one Status (given, or the IK
    default's at the region's centre), and lines describing it."""
    box = r.region
    lo, hi = (box[0], box[2], box[4]), (box[1], box[3], box[5])
    robot = r.robot
    centre = pose_from_xyzabc(np.concatenate([np.add(lo, hi) / 2, r.abc]))
    status = solve_in_one_status(robot, centre, r.status)[1]  # default: IK at the centre
    if status is None:
        raise InputError(
            f"the region's centre is not reachable at A B C {' '.join(map(fixed, r.abc))} "
            "deg: give --status"
        )
    plan, o1, usable = identification_plan(
        robot,
        lo,
        hi,
        r.count,
        r.tilt_deg,
        r.abc,
        status,
        candidates=r.candidates,
        repeats=r.repeats,
        seed=r.seed,
        compliance=r.compliance,
        harmonics=r.harmonics,
        gravity=r.gravity,
        design=r.design,
    )
    model = "DH errors, TCP" + (", compliance" if r.compliance else "")
    model += f", {len(r.harmonics)} harmonics" if r.harmonics else ""
    model += "".join(f", {g.name}" for g in r.gravity)
    how = "D-optimally"
    if r.design == "library":
        from accugrid.kinematics.structure import DEFAULT_MAX_ORDER

        orders = f"harmonic orders 1..{DEFAULT_MAX_ORDER} per axis"
        model += f" + candidates: {orders}, gravity per loaded axis"
        how = "Bayesian D-optimally"
    info = [
        f"identification plan ({model}): {r.count} poses x {r.repeats} repeats chosen {how} "
        f"from {usable} of {r.candidates} candidates (Status {status}, tilt up to "
        f"{r.tilt_deg:g} deg, |A5| >= 10 deg); observability O1 {o1:.4f}",
        f"path {plan.path_length():.1f} mm",
    ]
    info.append(_candidates_line(robot, plan, status, r))
    return plan, info


def _tool_plan(r: PlanRequest) -> tuple[Plan, list[str]]:
    """Orientations of the taught tool about one point for ``accugrid identify-tool``, in the
    Status (given, or the IK default's at ``abc``) and the joint ranges the arm was calibrated
    in, and lines describing them."""
    from accugrid.infra.yamlfile import load_yaml
    from accugrid.kinematics.frames import matrix_to_abc
    from accugrid.kinematics.tool_calibration import (
        DISTINCT_DEG,
        frame_sensitivity,
        plan_tool_poses,
    )
    from accugrid.kinematics.validity import Validity

    validity = Validity.from_doc(load_yaml(r.model))
    if validity is None:
        raise InputError("has no identification.validity (accugrid identify writes it)", r.model)
    centre = (
        np.asarray(r.centre, dtype=float)
        if r.centre is not None
        else (validity.lower + validity.upper) / 2
    )
    middle = pose_from_xyzabc(np.concatenate([centre, r.abc]))
    status = solve_in_one_status(r.robot, middle, r.status)[1]
    if status is None:
        raise InputError(
            f"the tool cannot reach {np.round(centre, 1).tolist()} mm at A B C "
            f"{' '.join(map(fixed, r.abc))} deg: give another --centre, --abc or --status"
        )
    poses, q = plan_tool_poses(
        r.robot,
        r.robot.flange_T_tool,
        centre,
        r.count,
        r.tilt_deg,
        r.candidates,
        r.seed,
        status,
        validity.joints_deg,
        r.abc,
    )
    flange = r.robot.with_tool(np.eye(4)).fk(q)[:, :3, :3]
    points = np.tile(poses[:, :3, 3], (r.repeats, 1))
    abc = np.tile(matrix_to_abc(poses[:, :3, :3]), (r.repeats, 1))
    ids = [f"T{i + 1}_R{k + 1}" for k in range(r.repeats) for i in range(len(poses))]
    words = ["tip"] * len(ids)
    if r.axis_point:
        points, abc = np.vstack([points, points]), np.vstack([abc, abc])
        ids += [f"{name}_AXIS" for name in ids]
        words += ["axis"] * len(words)
    plan = Plan(points, abc, ids, {"point": words})
    info = [
        f"tool plan: {r.count} orientations x {r.repeats} repeats about X {centre[0]:.1f} "
        f"Y {centre[1]:.1f} Z {centre[2]:.1f} (Status {status}, tilt up to {r.tilt_deg:g} deg "
        f"from A B C {' '.join(map(fixed, r.abc))}, "
        f"{DISTINCT_DEG:g} deg apart or more, inside the calibrated joint ranges); a frame "
        f"offset enters the TCP by {frame_sensitivity(flange):.2f} of itself"
        + ("; then the same poses with the SMR on the drill axis" if r.axis_point else ""),
        "log the joints a1..a6 at each pose (or keep a,b,c and give identify-tool the --tool)",
    ]
    return plan, info


def _candidates_line(robot, plan: Plan, status: int, r: PlanRequest) -> str:
    """What the planned poses can tell ``identify``'s search: the harmonic orders resolved per
    axis, the candidate groups they cannot separate from the DH errors and TCP, and the share of
    the candidates' prior variance they remove (``pose_design.library_share``)."""
    from accugrid.kinematics.pose_design import library_share
    from accugrid.kinematics.structure import DEFAULT_MAX_ORDER, observability

    poses = pose_from_xyzabc(np.column_stack([plan.points, plan.abc_rows()]))
    first = np.unique(np.column_stack([plan.points, plan.abc_rows()]), axis=0, return_index=True)[1]
    q = robot.ik(poses[np.sort(first)], status=status).q
    caps, hidden = observability(robot, q)
    resolved = " ".join(f"A{a + 1}:{caps[a]}" for a in range(6))
    orders: dict[str, list[str]] = {}
    for name, _ in hidden:  # 'A6 k3' -> {'A6': ['3']}, a gravity group as it is
        axis, _, order = name.partition(" k")
        orders.setdefault(axis if order else name, []).append(order)
    text = "; ".join(f"{key} orders {','.join(ks)}" if ks[0] else key for key, ks in orders.items())
    text = text or "none"
    share = library_share(robot, q, DEFAULT_MAX_ORDER, r.harmonics, r.compliance)
    return (
        f"candidates for identify's structure search: harmonic orders up to {resolved}; "
        f"not separable from the DH errors and TCP by these poses: {text}; these poses remove "
        f"{100 * share:.0f} % of the candidate terms' prior variance (mean; each term's prior "
        "3 times the noise)"
    )


def _check_program(r: PlanRequest) -> None:
    """InputError naming the option of a program setting out of its range."""
    if r.wait_input is not None and not 1 <= r.wait_input <= 4096:
        raise InputError(f"--wait-input must be an input number 1..4096, got {r.wait_input}")
    if not 0 <= r.wait_sec <= MAX_WAIT_SEC:
        raise InputError(f"--wait-sec must be 0..{MAX_WAIT_SEC:g} s, got {r.wait_sec:g}")
    if not 1 <= r.ptp_percent <= 100:
        raise InputError(f"--ptp-percent must be 1..100, got {r.ptp_percent}")
    if not 0 < r.vel_m_s <= 2.0:
        raise InputError(f"--speed must be in (0, 2000] mm/s, got {1000 * r.vel_m_s:g}")
    for option in ("tool_number", "base_number"):
        value = getattr(r, option)
        low = 1 if option == "tool_number" else 0
        if not low <= value <= 32:
            raise InputError(f"--{option.replace('_', '-')} must be {low}..32, got {value}")


def _orientation_text(plan: Plan, listing: str) -> str:
    """The plan's orientation, or where the program (``listing``) lists one per position."""
    if np.ndim(plan.abc) == 1:
        return f"orientation A B C {' '.join(fixed(v) for v in plan.abc)} deg"
    return f"orientation A B C per position (see {listing})"
