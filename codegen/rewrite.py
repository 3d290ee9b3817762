"""What a pre-flight rewrite is (``accugrid rewrite``), shared by the KRL and G-code rewriters
(``codegen.krl.rewrite``, ``codegen.gcode.rewrite``): options, report rows, the correction of
robot-frame points, the report CSV and the header.

Each Cartesian position that can be placed in the robot frame is corrected with the grid model
(P' = P + e, in the robot frame, converted back to the program's frame) and only its X, Y, Z
numbers are replaced in the text; every other byte is kept (``codegen.program_text``). What cannot
be placed is reported with the reason, never guessed. Positions outside the grid box stay as they
are (an error with ``strict``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accugrid.codegen.header import grid_lines, input_line
from accugrid.codegen.header import header_lines as make_header
from accugrid.codegen.program import GRID_ORIENTATION_TOL_DEG
from accugrid.codegen.program_text import MAX_BYTES
from accugrid.codegen.textsafe import fixed
from accugrid.compensation import GridModel
from accugrid.compensation.corrector import Corrector
from accugrid.compensation.settings import CorrectionSettings
from accugrid.compensation.study import DEFAULT_TOLERANCE_MM
from accugrid.kinematics.digest import file_sha256
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix, matrix_to_abc
from accugrid.kinematics.robot import Robot

__all__ = [
    "ORIENTATION_LIMIT_DEG",
    "REPORT_COLUMNS",
    "Options",
    "Result",
    "Row",
    "correct_points",
    "header_lines",
    "warning_lines",
    "outside_reason",
    "report_csv",
    "rotations_of",
    "strict_check",
]

REPORT_COLUMNS = (
    "file,line,name,status,reason,x,y,z,x_new,y_new,z_new,dx,dy,dz,correction_mm,residual_mm"
)
NAN3 = (math.nan, math.nan, math.nan)
ORIENTATION_LIMIT_DEG = 15.0  # as ``accugrid correct --orientation-limit``


@dataclass
class Options:
    """How to rewrite. Frames are (4, 4) mm poses."""

    model: GridModel
    base_data: dict[int, np.ndarray]  # BASE_DATA[n] -> robot_T_base
    robot_T_program: np.ndarray  # G-code program frame
    correction: CorrectionSettings = CorrectionSettings()
    decimals: int | None = None  # None: the file's precision (see ``precision``)
    strict: bool = False
    base_override: int | None = None
    tool_number: int | None = None  # the cell's TOOL_DATA number (the TCP the grid holds for)
    trust_calls: bool = False
    ignore_external_axes: bool = False
    max_bytes: int = MAX_BYTES
    orientation_tol: float = GRID_ORIENTATION_TOL_DEG  # deg: flag beyond (as ``correct``)
    orientation_limit: float = ORIENTATION_LIMIT_DEG  # deg: skip beyond
    allow_orientation: bool = False  # correct (and flag) beyond the limit instead
    tolerance_mm: float = DEFAULT_TOLERANCE_MM  # warn when rounding leaves more than a tenth
    corrector: Corrector | None = None  # with a calibrated model: ``model`` is its residual grid
    model_file: str | None = None  # the calibrated robot YAML (header)
    reference_abc: tuple[float, float, float] | None = None  # robot-frame A,B,C deg the model
    # assumes where a position has none (3-axis G-code): the cell's configuration.reference

    @property
    def calibrated(self) -> Robot | None:
        """The calibrated model the corrector uses, None for the grid alone."""
        return None if self.corrector is None else self.corrector.calibrated


@dataclass(slots=True)
class Row:
    """One position (or unresolved motion target) in the report."""

    file: str
    line: int
    name: str
    status: str  # "corrected", "outside", "skipped"
    reason: str = ""
    old: tuple[float, float, float] = NAN3  # position as written (program/base frame, mm)
    new: tuple[float, float, float] = NAN3  # as rewritten (corrected rows)
    residual_mm: float = math.nan
    rounding_mm: float = math.nan  # how far rounding to the written decimals leaves it (mm)


@dataclass
class Result:
    """Rewritten texts by input path (latin-1 str), the report rows and the largest correction."""

    texts: dict[str, str]
    rows: list[Row]

    @property
    def corrected(self) -> list[Row]:
        return [r for r in self.rows if r.status == "corrected"]

    def largest(self) -> tuple[float, Row | None]:
        best, where = 0.0, None
        for row in self.corrected:
            d = math.dist(row.new, row.old)
            if d > best:
                best, where = d, row
        return best, where


def correct_points(
    points_robot: np.ndarray,
    rows: list[Row],
    opts: Options,
    rotations: np.ndarray | None = None,
    mark: bool = True,
) -> np.ndarray:
    """Correct robot-frame points (N, 3) mm with one ``GridModel.check``; (N, 3) commands, NaN
    rows where a point is not corrected.

    ``rows`` (N,): the report row of each point (an error names its file and line).
    ``rotations`` (N, 3, 3): each point's orientation, robot frame (NaN rows: none). With
    ``mark``, rows outside the grid get status "outside", rows beyond ``orientation_limit``
    (``accugrid correct``'s rule) stay "skipped" with the angle as the reason (unless
    ``allow_orientation``), rows beyond ``orientation_tol`` a ``flag:`` reason. InputError at the
    row when a correction to be written is longer than the safety limit. With ``opts.calibrated``
    the points with an orientation are corrected by ``opts.corrector`` (model plus residual grid)
    (the model holds at any orientation: flagged, never skipped); the others stay NaN."""
    out = np.full_like(points_robot, np.nan)
    if not len(points_robot):
        return out
    found = opts.model.check(points_robot, opts.correction, rotations=rotations)
    use = np.ones(len(points_robot), bool)
    use[found.outside] = False
    if mark:
        for i in found.outside.tolist():
            rows[i].status, rows[i].reason = "outside", outside_reason(points_robot[i])
        if found.angle is not None:
            skip = _orientation(found.angle, rows, opts)
            if opts.calibrated is None:
                use &= ~skip
    command, length = found.command, found.length
    if opts.calibrated is not None:
        command, length = _by_model(points_robot, rotations, rows, use, opts)
        use &= ~np.isnan(command[:, 0])
    limit = opts.correction.max_correction_mm
    too_long = [] if limit is None else np.flatnonzero(use & (length > limit)).tolist()
    if too_long:
        i = max(too_long, key=lambda k: length[k])
        raise InputError(
            f"{rows[i].name}: correction of {length[i]:.3f} mm exceeds the safety limit of "
            f"{opts.correction.max_correction_mm:g} mm; refusing the whole job (check the grid)",
            rows[i].file,
            rows[i].line,
        )
    out[use] = command[use]
    return out


def _by_model(
    points: np.ndarray, rotations: np.ndarray | None, rows: list[Row], use: np.ndarray, opts
) -> tuple[np.ndarray, np.ndarray]:
    """Model commands (N, 3) mm robot frame (NaN where not corrected) and their lengths (N,) mm
    for the ``use`` rows with an orientation; InputError at the row the model cannot correct."""
    command = np.full_like(points, np.nan)
    if rotations is None:
        rotations = np.full((len(points), 3, 3), np.nan)
    oriented = ~np.isnan(rotations[:, 0, 0])
    if opts.reference_abc is not None:
        rotations = np.where(
            oriented[:, None, None], rotations, abc_to_matrix(np.array(opts.reference_abc))
        )
        oriented[:] = True
    for i in np.flatnonzero(use & ~oriented).tolist():
        rows[i].reason = "no orientation (A, B, C) here: the model needs one; left as is"
    todo = np.flatnonzero(use & oriented)
    if todo.size:
        result = opts.corrector.correct(points[todo], matrix_to_abc(rotations[todo]).reshape(-1, 3))
        if not result.ok.all():
            j = int(result.failed[0])
            row = rows[int(todo[j])]
            raise InputError(
                f"{row.name}: not corrected by model {opts.calibrated.name}: {result.reason[j]}"
                + (f"; {result.failed.size - 1} more" if result.failed.size > 1 else ""),
                row.file,
                row.line,
            )
        command[todo] = result.command
    return command, opts.corrector.too_long(points, command)[0]


def _orientation(angle: np.ndarray, rows: list[Row], opts: Options) -> np.ndarray:
    """Rows (N,) beyond the orientation limit (reasons set), flags for those beyond the tol."""
    grid = ", ".join(fixed(v) for v in opts.model.orientation_abc)
    skip = np.zeros(len(rows), bool)
    for i in np.flatnonzero(angle > opts.orientation_tol).tolist():
        a = float(angle[i])
        if a > opts.orientation_limit and not opts.allow_orientation:
            skip[i] = True
            rows[i].reason = (
                f"orientation {a:.1f} deg from the grid's ({grid}), more than "
                f"--orientation-limit {opts.orientation_limit:g}: the grid does not hold there"
            )
        else:
            rows[i].reason = f"flag: orientation {a:.1f} deg from the grid's ({grid})"
    return skip


def rotations_of(frames: np.ndarray, abc: np.ndarray) -> np.ndarray:
    """Robot-frame orientations (N, 3, 3) of A, B, C (N, 3) deg written in frames (N, 3, 3) or
    one (3, 3); NaN rows where a position gives no orientation."""
    return frames @ abc_to_matrix(abc)


def warning_lines(result: Result, opts: Options) -> list[str]:
    """What the user must know although nothing failed: rounding that eats the tolerance,
    positions flagged for their orientation."""
    out = []
    rounded = [r for r in result.corrected if r.rounding_mm > opts.tolerance_mm / 10]
    if rounded:
        worst = max(rounded, key=lambda r: r.rounding_mm)
        out.append(
            f"rounding to the written decimals leaves {len(rounded)} position(s) more than a "
            f"tenth of the tolerance ({opts.tolerance_mm:g} mm) off, up to "
            f"{worst.rounding_mm:.3f} mm ({Path(worst.file).name} line {worst.line}): give "
            "more --decimals"
        )
    flagged = [r for r in result.corrected if r.reason.startswith("flag: orientation")]
    if flagged:
        out.append(
            f"{len(flagged)} corrected position(s) more than --orientation-tol "
            f"{opts.orientation_tol:g} deg from the grid's orientation (see the report), first "
            f"{Path(flagged[0].file).name} line {flagged[0].line}"
        )
    return out


def outside_reason(robot_xyz: np.ndarray) -> str:
    x, y, z = (fixed(v) for v in robot_xyz)
    return f"outside the grid (robot frame {x}, {y}, {z} mm): left as is"


def strict_check(rows: list[Row], opts: Options) -> None:
    if opts.strict:
        outside = [r for r in rows if r.status == "outside"]
        if outside:
            r = outside[0]
            raise InputError(
                f"{len(outside)} position(s) outside the grid (--strict); first: {r.name}: "
                f"{r.reason}",
                r.file,
                r.line,
            )


def header_lines(result: Result, program: str, cell: str, opts: Options) -> list[str]:
    """DESIGN.md header: accugrid version, input and grid SHA-256, grid step, largest correction.

    File names only (no directories, no dates), so the same inputs give the same bytes."""
    largest, where = result.largest()
    model = opts.model
    at = "" if where is None else f" at {where.name} line {where.line}"
    grid = Path(model.source_path).name if model.source_path else "arrays"
    inputs = [
        input_line("program", program, file_sha256(program)),
        input_line("cell", cell, file_sha256(cell)),
        *grid_lines(grid, model.source_sha256, model.step),
    ]
    if opts.model_file is not None:
        inputs.insert(2, input_line("model", opts.model_file, file_sha256(opts.model_file)))
    closing = [f"positions corrected {len(result.corrected)}"]
    return make_header("rewrite", inputs, (), largest, at, closing)


def report_csv(rows: list[Row], decimals: int = 4) -> str:
    """The report as CSV text (DESIGN.md style: header row, mm, ``decimals`` places)."""
    corrected = ",".join([f"%.{decimals}f"] * 11)  # x..z, x_new..z_new, dx..dz, length, residual
    old_only = ",".join([f"%.{decimals}f"] * 3) + ",,,,,,,,"
    names: dict[str, str] = {}
    out = [REPORT_COLUMNS]
    for r in rows:
        file = names.get(r.file) or names.setdefault(r.file, _csv(Path(r.file).name))
        head = f"{file},{r.line},{_csv(r.name)},{r.status},{_csv(r.reason)},"
        if r.status == "corrected":
            (x, y, z), (u, v, w) = r.old, r.new
            dx, dy, dz = u - x, v - y, w - z
            length = math.sqrt(dx * dx + dy * dy + dz * dz)
            numbers = corrected % (x, y, z, u, v, w, dx, dy, dz, length, r.residual_mm)
        elif r.old[0] == r.old[0] and r.old[1] == r.old[1] and r.old[2] == r.old[2]:
            numbers = old_only % r.old
        else:
            numbers = ",,,,,,,,,,"
        out.append(head + numbers.replace("-0.0000,", "0.0000,").replace("nan", ""))
    return "\n".join(out) + "\n"


def _csv(text: str) -> str:
    if "," not in text and '"' not in text and "\n" not in text and "\r" not in text:
        return text
    text = text.replace("\r", " ").replace("\n", " ")
    if any(c in text for c in ',"'):
        return '"' + text.replace('"', '""') + '"'
    return text
