"""The corrected-points CSV (DESIGN.md "Corrected points") and the checks both ``accugrid correct``
jobs (grid and model) share: every input column untouched, then x_cmd,y_cmd,z_cmd (the command,
mm), ex,ey,ez (the correction applied, P' - P, mm; 4 decimals) and flag (why a point deserves a
look); the job is refused whole when a correction exceeds the safety limit."""

from __future__ import annotations

import argparse
import csv
import io
import re
from collections.abc import Iterator

import numpy as np

from accugrid.codegen.atomic import write_files
from accugrid.codegen.header import csv_comment, header_lines, input_line
from accugrid.codegen.points import Points
from accugrid.codegen.textsafe import fixed_format, fixed_ready, fixed_texts
from accugrid.compensation.grid import GridModel
from accugrid.kinematics.digest import file_sha256
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.units import mm_text

__all__ = [
    "ADDED",
    "BLOCK",
    "DECIMALS",
    "check_added_columns",
    "check_orientation",
    "check_outside",
    "corrected_csv",
    "print_corrections",
    "refuse_too_long",
    "write_corrected",
]

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
    points: Points, model: GridModel, outside: np.ndarray, rule: str, flags: list[list[str]]
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
        flags[i].append("outside grid: clamped")


def check_orientation(
    points: Points,
    model: GridModel,
    angle: np.ndarray | None,
    args: argparse.Namespace,
    flags: list[list[str]],
    what: str,
) -> None:
    """Angles (N,) deg from the grid's orientation: InputError beyond --orientation-limit
    (unless --allow-orientation), a flag beyond --orientation-tol; ``what`` names the grid."""
    if angle is None:
        return
    beyond = np.flatnonzero(angle > args.orientation_limit)
    if beyond.size and not args.allow_orientation:
        i = int(beyond[0])
        raise InputError(
            f"{beyond.size} point(s) more than {args.orientation_limit:g} deg from the {what}'s "
            f"orientation {mm_text(model.orientation_abc)} deg, first {points.label(i)} at "
            f"{angle[i]:.1f} deg: the grid does not hold there (--allow-orientation to go on)",
            *points.table.where(i),
        )
    for i in np.flatnonzero(angle > args.orientation_tol):
        flags[i].append(f"orientation {angle[i]:.1f} deg from {what}")


def corrected_csv(
    points: Points,
    command: np.ndarray,
    correction: np.ndarray,
    flags: list[list[str]],
    header: list[str],
) -> Iterator[str]:
    """The corrected CSV text in pieces (comment header and column names, then blocks of
    ``BLOCK`` rows), for writing a million points without holding the text whole."""
    out = io.StringIO()
    out.write(csv_comment(header))
    csv.writer(out, lineterminator="\n").writerow([*points.table.header, *ADDED])
    yield out.getvalue()
    flag = ["; ".join(f) for f in flags]
    numbers = np.column_stack([command, correction])
    plain = points.table.plain_rows(0, 0) is not None and not _NEEDS_QUOTES.search("".join(flag))
    number = fixed_format(DECIMALS)
    line = f"%s,{number},{number},{number},{number},{number},{number},%s\n"
    for lo in range(0, len(points), BLOCK):
        hi = min(lo + BLOCK, len(points))
        if plain:  # every row of the block in one %-template pass over the rows as read
            table = np.empty((hi - lo, 8), dtype=object)
            table[:, 0] = points.table.plain_rows(lo, hi)
            table[:, 1:7] = fixed_ready(numbers[lo:hi], DECIMALS)
            table[:, 7] = flag[lo:hi]
            yield (line * (hi - lo)) % tuple(table.ravel().tolist())
            continue
        out = io.StringIO()
        writer = csv.writer(out, lineterminator="\n")
        texts = fixed_texts(numbers[lo:hi], DECIMALS).tolist()
        for row, text, note in zip(points.table.rows[lo:hi], texts, flag[lo:hi], strict=True):
            writer.writerow([*row, *text, note])
        yield out.getvalue()


BLOCK = 65536  # rows formatted at a time
_NEEDS_QUOTES = re.compile(r'[,"\r\n]')  # what csv.writer would quote


def write_corrected(
    args: argparse.Namespace,
    points: Points,
    command: np.ndarray,
    flags: list[list[str]],
    sources: list[str],
    details: list[str],
    inputs: list,
) -> tuple[np.ndarray, int | None]:
    """Refuse the job when a correction exceeds --max-correction, else write the corrected CSV
    (header: the points file, ``sources`` and ``details`` lines) atomically; returns the
    correction lengths (N,) mm and the index of the longest (None without points)."""
    correction = command - points.xyz
    length = np.sqrt(np.einsum("ij,ij->i", correction, correction))
    worst = refuse_too_long(points, length, args.max_correction)
    where = "" if worst is None else f" at hole {points.ids[worst]}"
    largest = 0.0 if worst is None else float(length[worst])
    lines = [input_line("points", args.points, file_sha256(args.points)), *sources]
    header = header_lines("correct", lines, details, largest, where, [f"points {len(points)}"])
    text = corrected_csv(points, command, correction, flags, header)
    write_files({args.output: text}, inputs, force=args.force)
    return length, worst


def print_corrections(
    points: Points, length: np.ndarray, worst: int | None, flags: list[list[str]], output
) -> None:
    """The summary lines every correct job ends with: largest correction, flagged points."""
    if worst is not None:
        print(
            f"largest correction {length[worst]:.4f} mm at {points.label(worst)}; "
            f"mean {length.mean():.4f} mm"
        )
    flagged = [i for i, f in enumerate(flags) if f]
    print(f"flagged    {len(flagged)} point(s)")
    for i in flagged[:_LISTED]:
        print(f"  {points.label(i)}: {'; '.join(flags[i])}")
    if len(flagged) > _LISTED:
        print(f"  ... and {len(flagged) - _LISTED} more (see the flag column)")
    print(f"wrote {output}")
