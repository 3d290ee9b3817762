"""`accugrid validate MEAS --model CAL [--grid G]`: the check after correction, as one call.

MEAS is a measurement CSV taken after correction at new points: x,y,z the targets (the nominal
positions the corrected program aimed at, robot frame, mm), x_meas,y_meas,z_meas where the
tracker measured the TCP there (robot frame, mm); optional id, a,b,c, s. Statistics and verdict:
``compensation.validation`` (deviation d = M - P). The model (and the residual grid, when the
correction used one: read as a grid, the poses outside its box counted) are named with their
SHA-256; the model's validated error decides whether the file can be from the model's base
frame and tool (``mean_offset``): a mean deviation too long for them fails the validation, and
the report says what the offset suggests.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accugrid.app.reports.html import Figure, Section, Table, report_html
from accugrid.app.reports.plots import rows_png, validation_hist_png
from accugrid.compensation.measurements import read_measurements
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM
from accugrid.compensation.validation import (
    MeanOffset,
    ValidationResult,
    mean_offset,
    validate_positions,
)
from accugrid.infra.atomic import JobFiles
from accugrid.infra.csvtable import read_table
from accugrid.infra.digest import sha256_hex
from accugrid.infra.errors import InputError, printable
from accugrid.infra.units import check_scale, mm_text
from accugrid.infra.yamlfile import load_yaml
from accugrid.kinematics.model import reach_mm
from accugrid.kinematics.robot import load_robot
from accugrid.kinematics.validity import Validity

__all__ = ["ValidateJob", "ValidateRequest", "validate_files"]

_WORST = 10  # rows named in the report when every row is within the tolerance
_PRINTED = 3  # rows named in the printed summary


@dataclass(frozen=True)
class ValidateRequest:
    """The validation file, the calibrated model YAML, the residual grid (or None), the
    tolerance per axis (mm), the HTML report and the per-row CSV report to write (or None)."""

    measurements: str
    model: str
    grid: str | None = None
    tolerance_mm: float = DEFAULT_TOLERANCE_MM
    report_html: str | None = None
    report_csv: str | None = None


@dataclass(frozen=True)
class ValidateJob:
    """The files to write (the reports), the lines to print, the result and what its mean
    offset says; ``passed``: every row within the tolerance and no sign of another base frame or
    tool."""

    job: JobFiles
    result: ValidationResult
    offset: MeanOffset

    @property
    def passed(self) -> bool:
        return _passed(self.result, self.offset)


def _passed(result: ValidationResult, offset: MeanOffset) -> bool:
    """Every row within the tolerance and no sign of another base frame or tool."""
    return result.passed and not offset.other_frame


def _validated_error(path: str) -> np.ndarray | None:
    """The model's validated error per axis (3,) mm (None: not recorded); InputError unless the
    file is a calibrated model (it has an identification section)."""
    doc = load_yaml(path)
    if not doc.has("identification"):
        raise InputError("not a calibrated model (no 'identification'; accugrid identify)", path)
    validity = Validity.from_doc(doc)
    return None if validity is None else validity.validated_max_mm


def validate_files(request: ValidateRequest) -> ValidateJob:
    """Read, check and summarise the validation; the report's text when asked for."""
    validated = _validated_error(request.model)
    meas = read_measurements(request.measurements)
    reach = reach_mm(load_robot(request.model))
    check_scale(meas.commanded, reach, "commanded position", meas.path, meas.lines)
    name = printable(Path(request.measurements).name)
    table = read_table(request.measurements)  # the ids (the reader of positions drops them)
    ids = table.text("id") if table.has("id") else [""] * len(table)
    labels = [
        f"{name}:{meas.lines[r]}" + (f" {printable(ids[r], 40)}" if ids[r] else "")
        for r in range(len(meas.commanded))
    ]
    result = validate_positions(meas.commanded, meas.measured, labels, request.tolerance_mm)
    offset = mean_offset(result, validated, meas.abc)
    lines = _summary(result, validated, offset)
    grid_note = None
    if request.grid:  # read as a grid (a wrong file is refused); the rows outside its box told
        from accugrid.compensation.grid import GridModel

        grid = GridModel.from_measurements(request.grid)
        outside = int((~grid.contains(np.unique(result.target, axis=0))).sum())
        grid_note = (
            f"residual grid {mm_text(grid.origin)} .. {mm_text(grid.upper)} mm, step "
            f"{mm_text(grid.step)} mm: {outside} of {len(result.ap_mm)} poses outside its box"
        )
        lines.insert(-1, grid_note)
    budget_note = _budget_coverage(request, meas, result)
    lines.insert(-1, budget_note)
    files: dict[str, str] = {}
    if request.report_csv:
        files[request.report_csv] = rows_csv(result, meas.lines, ids)
        lines.append(f"wrote {request.report_csv}")
    if request.report_html:
        outputs = [(path, sha256_hex(text.encode("utf-8"))) for path, text in files.items()]
        files[request.report_html] = _report(
            request, result, validated, offset, grid_note, outputs, budget_note
        )
        lines.append(f"wrote {request.report_html}")
    inputs = [request.measurements, request.model, request.grid]
    return ValidateJob(JobFiles(files, inputs, lines), result, offset)


def _budget_coverage(request: ValidateRequest, meas, result: ValidationResult) -> str:
    """One line: the share of rows whose deviation lies within the 95 % bound the error budget
    (``compensation.budget``) predicts at their target, by the model (and residual grid) at
    the rows' orientation and Status with the SMR the model was measured with, as ``correct``
    computes it; whether that share says the bounds are calibrated (``coverage_range`` of the
    distinct targets checked)."""
    from accugrid.codegen.correction import read_model
    from accugrid.compensation.budget import Budget, coverage, coverage_range
    from accugrid.compensation.policy import Policy
    from accugrid.compensation.settings import CorrectionSettings
    from accugrid.kinematics.frames import abc_to_matrix

    model = read_model(request.model)
    if model.budget is None:
        return (
            "error budget: the model records none (identified without folds, or by an older "
            "version): its coverage is not checked"
        )
    if meas.abc is None:
        return "error budget: the rows have no orientation (a,b,c): its coverage is not checked"
    policy = Policy.build(
        CorrectionSettings(outside="clamp"),
        request.grid,
        model.robot,
        None,
        model.smr_tools,
        points=meas.commanded,
        abc_deg=meas.abc,
        validity=model.validity,
        budget=Budget(model.budget),
        allow_orientation=True,
    )
    status = -1 if meas.status is None else meas.status
    verdict = policy.decide(meas.commanded, abc_to_matrix(meas.abc), status=status)
    u95 = verdict.numbers["u95"]
    share, count = coverage(result.deviation, u95)
    if not count:
        return "error budget: no row's target could be corrected: its coverage is not checked"
    targets = len(np.unique(meas.commanded[np.isfinite(u95)], axis=0))
    lo, hi = coverage_range(targets)
    if share < lo:
        verdict_text = "not calibrated: the bounds are too narrow"
    elif share > hi:
        verdict_text = "not calibrated: the bounds are wider than the errors need"
    else:
        verdict_text = "calibrated"
    return (
        f"error budget: {100 * share:.1f} % of {count} rows within their 95 % bound u95 "
        f"(median {np.nanmedian(u95):.3f} mm, largest {np.nanmax(u95):.3f} mm): {verdict_text} "
        f"({100 * lo:.0f}-{100 * hi:.0f} % expected at {targets} targets)"
    )


# the per-row CSV report (``--report``): mm, d = measured - target
ROWS_CSV_COLUMNS = "line,id,pose,x,y,z,x_meas,y_meas,z_meas,dx,dy,dz,distance,result"


def rows_csv(result: ValidationResult, lines: np.ndarray, ids: list[str]) -> str:
    """Every row of the validation in file order: its line in the file (``lines`` (N,)), id
    (``ids`` (N)), pose (1-based), target, measured, deviation d and |d| (mm, 4 decimals), and
    ``beyond`` or ``within`` the tolerance."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(ROWS_CSV_COLUMNS.split(","))
    numbers = np.column_stack(
        [result.target, result.measured, result.deviation, result.distance_mm]
    )
    for r in range(len(numbers)):
        writer.writerow(
            [int(lines[r]), ids[r], int(result.pose[r]) + 1]
            + [f"{v:.4f}" for v in numbers[r]]
            + ["beyond" if result.outside[r] else "within"]
        )
    return out.getvalue()


def _axis_rows(result: ValidationResult) -> list[list[str]]:
    """Rows X, Y, Z, |d|: min, max, max |d|, mean, std, mm (3 decimals)."""
    s, n = result.axis_stats, result.distance_stats
    rows = [
        [axis]
        + [f"{s[key][k]:+.3f}" for key in ("min", "max")]
        + [f"{s['max_abs'][k]:.3f}"]
        + [f"{s['mean'][k]:+.3f}", f"{s['std'][k]:.3f}"]
        for k, axis in enumerate("XYZ")
    ]
    rows.append(["3D |d|", "", "", f"{n['max']:.3f}", f"{n['mean']:.3f}", f"{n['std']:.3f}"])
    return rows


def _iso_line(result: ValidationResult) -> str:
    """ISO 9283 AP (worst pose) and RP (worst pose with repeats), one line."""
    worst = int(np.argmax(result.ap_mm))
    text = (
        f"ISO 9283 positional accuracy AP: max {result.ap_mm[worst]:.3f} mm (pose of "
        f"{result.labels[int(np.flatnonzero(result.pose == worst)[0])]}), mean "
        f"{result.ap_mm.mean():.3f} mm over {len(result.ap_mm)} poses"
    )
    repeated = np.isfinite(result.rp_mm)
    if repeated.any():
        counts = sorted(set(result.repeats[repeated].tolist()))
        return text + (
            f"; repeatability RP: max {np.nanmax(result.rp_mm):.3f} mm over {int(repeated.sum())} "
            f"poses with {'/'.join(map(str, counts))} repeats"
        )
    return text + "; repeatability RP: no repeated poses"


def _summary(
    result: ValidationResult, validated: np.ndarray | None, offset: MeanOffset
) -> list[str]:
    """The lines printed: statistics, ISO 9283, the mean offset, worst rows, verdict."""
    lines = [
        f"{len(result.deviation)} rows at {len(result.ap_mm)} poses; deviation d = measured - "
        "target, mm:",
        "  axis        min      max   max|d|     mean      std",
    ]
    lines += [
        f"  {r[0]:<6} {r[1]:>8} {r[2]:>8} {r[3]:>8} {r[4]:>8} {r[5]:>8}" for r in _axis_rows(result)
    ]
    lines.append(_iso_line(result))
    if validated is not None:
        shown = " ".join(f"{v:.3f}" for v in validated)
        lines.append(f"model's validated error (max per axis): {shown} mm")
    lines.append(offset.words())
    worst = result.worst(_PRINTED)
    lines.append(
        "worst rows: "
        + "; ".join(
            f"{result.labels[i]} ({' '.join(f'{v:+.3f}' for v in result.deviation[i])})"
            for i in worst
        )
    )
    lines.append(_verdict_line(result, offset))
    return lines


def _verdict_line(result: ValidationResult, offset: MeanOffset) -> str:
    """PASS or FAIL: the rows beyond the tolerance, and another frame or tool."""
    outside = int(result.outside.sum())
    verdict = "PASS" if _passed(result, offset) else "FAIL"
    text = (
        f"{verdict}: {outside} of {len(result.deviation)} rows beyond "
        f"±{result.tolerance_mm:g} mm on an axis"
    )
    if offset.other_frame:
        text += "; the mean deviation is too long for the model's base frame and tool"
    return text


def _report(
    request: ValidateRequest,
    result: ValidationResult,
    validated,
    offset: MeanOffset,
    grid_note: str | None,
    outputs: list[tuple[str, str]],
    budget_note: str = "",
) -> str:
    """The HTML report of the validation; ``outputs`` (path, SHA-256) of the files beside it,
    ``budget_note`` the error budget's coverage (``_budget_coverage``)."""
    tol = result.tolerance_mm
    stats = Table(
        ["axis", "min (mm)", "max (mm)", "max |d| (mm)", "mean (mm)", "std (mm)"],
        _axis_rows(result),
        "Deviation d = measured - target, every row",
    )
    beyond = np.flatnonzero(result.outside)
    listed = result.worst(len(result.labels))[: max(len(beyond), _WORST)]
    rows_table = Table(
        ["where (file:line id)", "pose", "dx (mm)", "dy (mm)", "dz (mm)", "|d| (mm)", ""],
        [
            [result.labels[i], str(int(result.pose[i]) + 1)]
            + [f"{v:+.3f}" for v in result.deviation[i]]
            + [f"{result.distance_mm[i]:.3f}", "beyond" if result.outside[i] else "within"]
            for i in listed
        ],
        f"Every row beyond ±{tol:g} mm ({len(beyond)}), largest axis deviation first"
        if len(beyond)
        else f"No row beyond ±{tol:g} mm; the {len(listed)} with the largest axis deviation",
    )
    iso_rows = []
    order = np.argsort(-result.ap_mm, kind="stable")[:_WORST]
    for p in order:
        first = int(np.flatnonzero(result.pose == p)[0])
        rp = result.rp_mm[p]
        iso_rows.append(
            [result.labels[first], str(int(result.repeats[p]))]
            + [f"{v:+.3f}" for v in result.ap_xyz[p]]
            + [f"{result.ap_mm[p]:.3f}", "-" if np.isnan(rp) else f"{rp:.3f}"]
        )
    iso = Table(
        [
            "pose (first row, id)",
            "repeats",
            "APx (mm)",
            "APy (mm)",
            "APz (mm)",
            "AP (mm)",
            "RP (mm)",
        ],
        iso_rows,
        f"ISO 9283 per pose, the {len(iso_rows)} largest AP",
    )
    notes = [
        "Each row: a target x,y,z (the position the corrected program aimed at, robot frame) "
        "and the position the laser tracker measured there after correction.",
        _iso_line(result),
        "AP: distance from the barycentre of a pose's measured positions to its target; "
        "RP = mean + 3 std of the distances of its measured positions from that barycentre "
        "(ISO 9283), for poses measured at least twice.",
    ]
    if validated is not None:
        notes.append(
            "The model's validated error (identification, max per axis): "
            + " ".join(f"{v:.3f}" for v in validated)
            + " mm."
        )
    if grid_note:
        notes.append(grid_note[0].upper() + grid_note[1:] + ".")
    if budget_note:
        notes.append(budget_note[0].upper() + budget_note[1:] + ".")
    offset_text = offset.words()
    facts = [
        ("rows / poses", f"{len(result.deviation)} / {len(result.ap_mm)}"),
        ("rows beyond tolerance", str(len(beyond))),
        ("mean offset", offset_text[0].upper() + offset_text[1:] + "."),
        (
            "criterion",
            f"PASS when every row is within ±{tol:g} mm on X, Y and Z and the mean deviation is "
            f"within {offset.limit_mm:.3f} mm (longer: another base frame or tool than the "
            "model's)",
        ),
    ]
    sections = [
        Section("Results", notes, [stats, iso, rows_table]),
        Section(
            "Figures",
            figures=[
                Figure(
                    validation_hist_png(result.deviation, tol),
                    f"Deviation per axis, every row; dashed: the tolerance ±{tol:g} mm.",
                ),
                Figure(
                    rows_png(
                        result.deviation,
                        tol,
                        "measured - target (mm)",
                        "row of the validation file",
                    ),
                    "Deviation of every row in file order; dashed: the tolerance.",
                ),
            ],
        ),
    ]
    return report_html(
        "Validation after correction",
        "PASS" if _passed(result, offset) else "FAIL",
        f"±{tol:g} mm per axis",
        [
            ("measurements after correction", request.measurements),
            ("calibrated model", request.model),
            ("residual grid", request.grid),
        ],
        sections,
        facts,
        outputs=outputs,
    )
