"""``accugrid correct`` (``correct_points``): the corrected-points CSV (DESIGN.md "Corrected
points") and the checks both jobs (grid here, model in ``correct_model``) share: every input
column untouched, then x_cmd,y_cmd,z_cmd (the command, mm), ex,ey,ez (the correction applied,
P' - P, mm; 4 decimals) and flag (why a point deserves a look); the job is refused whole when a
correction exceeds the safety limit."""

from __future__ import annotations

import csv
import io
import re
from collections import defaultdict
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accugrid.codegen.atomic import JobFiles
from accugrid.codegen.header import csv_comment, grid_lines, header_lines, input_line
from accugrid.codegen.linebytes import SLOT, image_bytes, line_image, number_cells
from accugrid.codegen.points import Points, read_points
from accugrid.codegen.textsafe import fixed_texts
from accugrid.compensation.grid import GridModel
from accugrid.compensation.measurements import REPEAT_TOL_MM
from accugrid.compensation.settings import CorrectionSettings
from accugrid.kinematics.digest import file_sha256
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix
from accugrid.kinematics.units import mm_text

__all__ = [
    "ADDED",
    "BLOCK",
    "DECIMALS",
    "CorrectRequest",
    "Flags",
    "check_added_columns",
    "check_orientation",
    "check_outside",
    "correct_points",
    "corrected_csv",
    "corrected_file",
    "refuse_too_long",
]

Flags = dict[int, list[str]]
"""Why points deserve a look: the reasons of each flagged point, by its row index (others absent;
a ``defaultdict(list)``, so ``flags[i].append(reason)`` flags point i)."""

ADDED = ["x_cmd", "y_cmd", "z_cmd", "ex", "ey", "ez", "flag"]
DECIMALS = 4
_LISTED = 5  # how many points a message names


def check_added_columns(points: Points) -> None:
    """InputError when the points CSV already has a column that correct writes."""
    clash = [name for name in ADDED if points.table.has(name)]
    if clash:
        raise InputError(
            f"column(s) {', '.join(clash)} would be written by accugrid correct; rename them",
            points.path,
            1,
        )


def refuse_too_long(points: Points, length: np.ndarray, limit_mm: float) -> int | None:
    """Index of the longest correction (None without points); InputError naming that point when
    it exceeds ``limit_mm`` (the whole job is refused)."""
    worst = int(np.argmax(length)) if len(points) else None
    if worst is not None and length[worst] > limit_mm:
        raise InputError(
            f"{points.label(worst)}: correction of {length[worst]:.3f} mm exceeds the safety "
            f"limit of {limit_mm:g} mm; refusing the whole job (check the grid or model)",
            *points.table.where(worst),
        )
    return worst


def check_outside(
    points: Points, model: GridModel, outside: np.ndarray, rule: str, flags: Flags
) -> None:
    """Points outside the grid box (indices ``outside``): InputError for rule "error", else a
    "clamped" flag each."""
    if not outside.size:
        return
    if rule == "error":
        named = "; ".join(points.label(int(i)) for i in outside[:_LISTED])
        more = f" and {outside.size - _LISTED} more" if outside.size > _LISTED else ""
        raise InputError(
            f"{outside.size} point(s) outside the grid box {mm_text(model.origin)}.."
            f"{mm_text(model.upper)} mm (robot frame): {named}{more} (--outside clamp uses the "
            "nearest cell)",
            *points.table.where(int(outside[0])),
        )
    for i in outside:
        flags[int(i)].append("outside grid: clamped")


def check_orientation(
    points: Points,
    model: GridModel,
    angle: np.ndarray | None,
    request: CorrectRequest,
    flags: Flags,
    what: str,
) -> None:
    """Angles (N,) deg from the grid's orientation: InputError beyond the request's
    orientation limit (unless it allows any), a flag beyond its tolerance; ``what`` names the
    grid."""
    if angle is None:
        return
    beyond = np.flatnonzero(angle > request.orientation_limit_deg)
    if beyond.size and not request.allow_orientation:
        i = int(beyond[0])
        raise InputError(
            f"{beyond.size} point(s) more than {request.orientation_limit_deg:g} deg from the "
            f"{what}'s orientation {mm_text(model.orientation_abc)} deg, first {points.label(i)} "
            f"at {angle[i]:.1f} deg: the grid does not hold there (--allow-orientation to go on)",
            *points.table.where(i),
        )
    for i in np.flatnonzero(angle > request.orientation_tol_deg):
        flags[int(i)].append(f"orientation {angle[i]:.1f} deg from {what}")


def _plain_lines(rows: np.ndarray, numbers: np.ndarray, flags: list[str]) -> bytes:
    """CSV lines, UTF-8: each row as read (``rows`` (n, r) uint8 NUL-padded), its numbers
    (n, k) as ``fixed`` text with ``DECIMALS`` places, its flag (n) (nothing ``csv.writer``
    would quote), LF; one line image (``codegen.linebytes``)."""
    n, k = numbers.shape
    cells = number_cells(numbers, DECIMALS)  # (n, k, w)
    notes = np.array([f.encode() for f in flags], dtype=bytes)  # UTF-8, NUL-padded
    template = SLOT + f",{SLOT}" * (k + 1) + "\n"
    columns = [rows, *(cells[:, j] for j in range(k)), notes.view(np.uint8).reshape(n, -1)]
    return image_bytes(line_image(template, columns))


def corrected_csv(
    points: Points,
    command: np.ndarray,
    correction: np.ndarray,
    flags: Flags,
    header: list[str],
) -> Iterator[str | bytes]:
    """The corrected CSV text in pieces (comment header and column names, then blocks of
    ``BLOCK`` rows), for writing a million points without holding the text whole."""
    out = io.StringIO()
    out.write(csv_comment(header))
    csv.writer(out, lineterminator="\n").writerow([*points.table.header, *ADDED])
    yield out.getvalue()
    flag = [""] * len(points)
    for i, reasons in flags.items():
        flag[i] = "; ".join(reasons)
    numbers = np.column_stack([command, correction])
    plain = points.table.row_bytes(0, 0) is not None and not _NEEDS_QUOTES.search(
        "".join(flag[i] for i in flags)
    )
    for lo in range(0, len(points), BLOCK):
        hi = min(lo + BLOCK, len(points))
        if plain:  # the block's lines built as bytes by numpy from the rows as read
            yield _plain_lines(points.table.row_bytes(lo, hi), numbers[lo:hi], flag[lo:hi])
            continue
        out = io.StringIO()
        writer = csv.writer(out, lineterminator="\n")
        texts = fixed_texts(numbers[lo:hi], DECIMALS).tolist()
        for row, text, note in zip(points.table.rows[lo:hi], texts, flag[lo:hi], strict=True):
            writer.writerow([*row, *text, note])
        yield out.getvalue()


BLOCK = 65536  # rows formatted at a time
_NEEDS_QUOTES = re.compile(r'[,"\r\n]')  # what csv.writer would quote


def corrected_file(
    request: CorrectRequest,
    points: Points,
    command: np.ndarray,
    flags: Flags,
    sources: list[str],
    details: list[str],
    lines: list[str],
) -> JobFiles:
    """Refuse the job when a correction exceeds the safety limit, else the corrected CSV
    (header: the points file, ``sources`` and ``details`` lines) to write, with ``lines`` and
    the summary every correct job ends with (largest correction, flagged points) to print."""
    correction = command - points.xyz
    length = np.sqrt(np.einsum("ij,ij->i", correction, correction))
    worst = refuse_too_long(points, length, request.settings.max_correction_mm)
    where = "" if worst is None else f" at hole {points.ids[worst]}"
    largest = 0.0 if worst is None else float(length[worst])
    inputs = [input_line("points", request.points, file_sha256(request.points)), *sources]
    header = header_lines("correct", inputs, details, largest, where, [f"points {len(points)}"])
    text = corrected_csv(points, command, correction, flags, header)
    if worst is not None:
        lines.append(
            f"largest correction {length[worst]:.4f} mm at {points.label(worst)}; "
            f"mean {length.mean():.4f} mm"
        )
    flagged = sorted(i for i, reasons in flags.items() if reasons)
    lines.append(f"flagged    {len(flagged)} point(s)")
    lines += [f"  {points.label(i)}: {'; '.join(flags[i])}" for i in flagged[:_LISTED]]
    if len(flagged) > _LISTED:
        lines.append(f"  ... and {len(flagged) - _LISTED} more (see the flag column)")
    lines.append(f"wrote {request.output}")
    model = request.model if request.model and Path(request.model).is_file() else None
    return JobFiles({request.output: text}, [request.points, request.grid, model], lines)


@dataclass(frozen=True)
class CorrectRequest:
    """One ``accugrid correct`` job: POINTS (robot frame) to OUTPUT, by a grid measurement
    and/or a calibrated model (paths), with the correction ``settings``. Orientation: flag
    beyond ``orientation_tol_deg``, refuse beyond ``orientation_limit_deg`` (grid only) unless
    ``allow_orientation``; ``repeat_tol_mm`` merges repeated grid vertices. With a model:
    ``status`` (KUKA, None: the default rule), ``abc`` (KUKA deg, orientation of points without
    one, reference for i,j,k), ``tool`` (the controller's x, y, z, a, b, c; None: the file's)."""

    points: str
    output: str
    grid: str | None
    model: str | None
    settings: CorrectionSettings
    orientation_tol_deg: float = 5.0
    orientation_limit_deg: float = 15.0
    allow_orientation: bool = False
    repeat_tol_mm: float = REPEAT_TOL_MM
    status: int | None = None
    abc: tuple[float, float, float] = (0.0, 90.0, 0.0)
    tool: tuple[float, ...] | None = None


def correct_points(request: CorrectRequest) -> JobFiles:
    """The whole ``accugrid correct`` job: the corrected-points CSV and the printed summary.
    InputError (nothing to write) on bad input, points outside the grid (outside "error"), a
    correction beyond the safety limit, or an orientation beyond the limit."""
    if not 0 <= request.orientation_tol_deg <= request.orientation_limit_deg:
        raise InputError("need 0 <= --orientation-tol <= --orientation-limit (deg)")
    if request.model is not None:
        from accugrid.codegen.correct_model import correct_by_model  # only when asked: slower

        return correct_by_model(request)
    if request.grid is None:
        raise InputError("give --grid MEAS, --model CAL.yaml or both")
    settings = request.settings
    model = GridModel.from_measurements(request.grid, repeat_tol_mm=request.repeat_tol_mm)
    points = read_points(request.points)
    check_added_columns(points)
    rotations = None if points.abc is None else abc_to_matrix(points.abc).reshape(-1, 3, 3)
    found = model.check(points.xyz, settings, rotations=rotations, axes=points.axis)
    flags: Flags = defaultdict(list)
    check_outside(points, model, found.outside, settings.outside, flags)
    check_orientation(points, model, found.angle, request, flags, "grid")
    sources = grid_lines(Path(request.grid).name, model.source_sha256, model.step)
    method, power, its = settings.method, settings.power, settings.iterations
    details = [f"method {method}, power {power:g}, iterations {its}"]
    iterations = f"{its} iteration{'s' if its != 1 else ''}"
    power_text = f" power {power:g}" if method == "idw" else ""
    lines = [
        model.describe(),
        f"corrected  {len(points)} point(s), {method}{power_text}, {iterations}",
    ]
    return corrected_file(request, points, found.command, flags, sources, details, lines)
