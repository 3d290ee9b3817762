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

from accugrid.codegen import __version__
from accugrid.codegen.header import file_sha256
from accugrid.codegen.program_text import MAX_BYTES
from accugrid.codegen.textsafe import fixed
from accugrid.compensation import GridModel
from accugrid.compensation.settings import CorrectionSettings
from accugrid.kinematics.errors import InputError

__all__ = [
    "REPORT_COLUMNS",
    "Options",
    "Result",
    "Row",
    "correct_points",
    "header_lines",
    "outside_reason",
    "report_csv",
    "strict_check",
]

REPORT_COLUMNS = (
    "file,line,name,status,reason,x,y,z,x_new,y_new,z_new,dx,dy,dz,correction_mm,residual_mm"
)
NAN3 = (math.nan, math.nan, math.nan)


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
    trust_calls: bool = False
    ignore_external_axes: bool = False
    max_bytes: int = MAX_BYTES


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


def correct_points(points_robot: np.ndarray, opts: Options) -> tuple[np.ndarray, np.ndarray]:
    """(inside (N,) bool, corrected robot-frame points (N,3); NaN rows outside)."""
    out = np.full_like(points_robot, np.nan)
    if not len(points_robot):
        return np.zeros(0, bool), out
    inside = opts.model.contains(points_robot)
    if inside.any():
        out[inside] = opts.model.correct(points_robot[inside], opts.correction)
    return inside, out


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
    step = " x ".join(fixed(s) for s in model.step)
    at = "" if where is None else f" at {where.name} line {where.line}"
    grid = Path(model.source_path).name if model.source_path else "arrays"
    return [
        f"accugrid {__version__} rewrite",
        f"program {Path(program).name} sha256 {file_sha256(program)}",
        f"cell {Path(cell).name} sha256 {file_sha256(cell)}",
        f"grid {grid} sha256 {model.source_sha256}",
        f"grid step {step} mm",
        f"largest correction {fixed(largest)} mm{at}",
        f"positions corrected {len(result.corrected)}",
    ]


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
