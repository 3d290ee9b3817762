"""Correct drilling points with a laser-tracker grid measurement (seed Eq. 12-14).

POINTS is a points CSV (x,y,z in mm in the ROBOT frame, the frame of the grid; optional id, a,b,c
or i,j,k and any other columns). Each point P gets the error e predicted from the 8 vertices of
its grid cell (inverse-distance weighting, seed Eq. 12-13, or trilinear) and the command
P' = P + e (Eq. 14; with --iterations K, P' = P + e(P') repeated K times).

The output CSV has every input column untouched, then x_cmd,y_cmd,z_cmd (the command, mm),
ex,ey,ez (the correction applied, P' - P, mm; 4 decimals) and flag (empty, or why a point
deserves a look: clamped to the grid, orientation far from the grid's).

Refused (exit 2, nothing written): points outside the grid box (unless --outside clamp), any
correction longer than --max-correction, a point whose orientation differs from the grid's by
more than --orientation-limit (unless --allow-orientation). The orientation difference is the
angle of the relative rotation for a,b,c points, the angle between the drill axis and the grid
tool's Z axis for i,j,k points.
"""

from __future__ import annotations

import argparse
import csv
import io
from pathlib import Path

import numpy as np

from accugrid.codegen.atomic import check_targets, write_files
from accugrid.codegen.cli_options import add_abc, add_status, add_tool
from accugrid.codegen.header import csv_comment, grid_lines, header_lines, input_line
from accugrid.codegen.points import Points, read_points
from accugrid.codegen.textsafe import fixed
from accugrid.compensation.grid import MAX_CORRECTION_MM, GridModel
from accugrid.compensation.measurements import REPEAT_TOL_MM
from accugrid.compensation.settings import CorrectionSettings
from accugrid.kinematics.digest import file_sha256
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix
from accugrid.kinematics.units import mm_text

__all__ = ["ADDED", "DECIMALS", "NAME", "add_arguments", "run", "settings_from"]

NAME = "correct"

ADDED = ["x_cmd", "y_cmd", "z_cmd", "ex", "ey", "ez", "flag"]
DECIMALS = 4
_LISTED = 5  # how many points a message names


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("points", metavar="POINTS", help="points CSV, robot frame (mm, deg)")
    parser.add_argument(
        "--grid",
        metavar="MEAS",
        help="measurement CSV (with --model: the residual grid after the model)",
    )
    parser.add_argument(
        "--model",
        metavar="CAL",
        help="calibrated robot YAML (accugrid identify): correct by the model, any orientation",
    )
    add_status(
        parser,
        "with --model: the KUKA Status the program runs in (default: the IK default at the "
        "first point)",
    )
    add_abc(parser, "with --model: orientation of points without a,b,c, reference for i,j,k axes")
    add_tool(
        parser,
        "with --model: the controller's TOOL_DATA, mm and deg (default: the model file's "
        "identification.controller_tool, else its identified TCP)",
    )
    parser.add_argument("-o", "--output", required=True, metavar="OUT", help="CSV to write")
    parser.add_argument(
        "--method",
        choices=["idw", "trilinear"],
        default="idw",
        help="interpolation over the cell's 8 vertices (default: idw, the seed's)",
    )
    parser.add_argument(
        "--power",
        type=float,
        default=1.0,
        metavar="P",
        help="inverse-distance power p, weights 1/s^p, 0 < p <= 16 (default: 1, the seed's)",
    )
    parser.add_argument(
        "--iterations",
        type=int,
        default=1,
        metavar="K",
        help="fixed-point iterations of P' = P + e(P') (default: 1 = seed Eq. 14)",
    )
    parser.add_argument(
        "--outside",
        choices=["error", "clamp"],
        default="error",
        help="points outside the grid box: refuse (default) or use the nearest cell and flag",
    )
    parser.add_argument(
        "--max-correction",
        type=float,
        default=MAX_CORRECTION_MM,
        metavar="MM",
        help=f"refuse the job if any correction is longer than this, mm "
        f"(default: {MAX_CORRECTION_MM:g})",
    )
    parser.add_argument(
        "--orientation-tol",
        type=float,
        default=5.0,
        metavar="DEG",
        help="flag points whose orientation differs from the grid's by more, deg (default: 5)",
    )
    parser.add_argument(
        "--orientation-limit",
        type=float,
        default=15.0,
        metavar="DEG",
        help="refuse points whose orientation differs from the grid's by more, deg (default: 15)",
    )
    parser.add_argument(
        "--allow-orientation",
        action="store_true",
        help="correct (and flag) points beyond --orientation-limit instead of refusing",
    )
    parser.add_argument(
        "--repeat-tol",
        type=float,
        default=REPEAT_TOL_MM,
        metavar="MM",
        help="largest distance of a repeated measurement from its mean, mm "
        f"(default: {REPEAT_TOL_MM:g})",
    )
    parser.add_argument("--force", action="store_true", help="overwrite an existing output")


def settings_from(args: argparse.Namespace) -> CorrectionSettings:
    """The correction settings the options ask for."""
    if not args.max_correction > 0:
        raise InputError(f"--max-correction must be > 0 mm, got {args.max_correction}")
    return CorrectionSettings(
        method=args.method,
        power=args.power,
        iterations=args.iterations,
        outside=args.outside,
        max_correction_mm=args.max_correction,
    )


def run(args: argparse.Namespace) -> int:
    settings = settings_from(args)
    if not 0 <= args.orientation_tol <= args.orientation_limit:
        raise InputError("need 0 <= --orientation-tol <= --orientation-limit (deg)")
    if args.model is not None:
        from accugrid.codegen.correct_model import run_model

        return run_model(args, settings)
    if args.grid is None:
        raise InputError("give --grid MEAS, --model CAL.yaml or both")
    check_targets([args.output], [args.points, args.grid], args.force)
    model = GridModel.from_measurements(args.grid, repeat_tol_mm=args.repeat_tol)
    points = read_points(args.points)
    check_added_columns(points)
    rotations = None if points.abc is None else abc_to_matrix(points.abc).reshape(-1, 3, 3)
    found = model.check(points.xyz, settings, rotations=rotations, axes=points.axis)
    flags: list[list[str]] = [[] for _ in range(len(points))]
    check_outside(points, model, found.outside, settings.outside, flags)
    check_orientation(points, model, found.angle, args, flags, "grid")
    sources = grid_lines(Path(args.grid).name, model.source_sha256, model.step)
    details = [f"method {args.method}, power {args.power:g}, iterations {args.iterations}"]
    inputs = [args.points, args.grid]
    length, worst = write_corrected(args, points, found.command, flags, sources, details, inputs)
    print(model.describe())
    iterations = f"{args.iterations} iteration{'s' if args.iterations != 1 else ''}"
    power = f" power {args.power:g}" if args.method == "idw" else ""
    print(f"corrected  {len(points)} point(s), {args.method}{power}, {iterations}")
    print_corrections(points, length, worst, flags, args.output)
    return 0


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
) -> str:
    out = io.StringIO()
    out.write(csv_comment(header))
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow([*points.table.header, *ADDED])
    for r, row in enumerate(points.table.rows):
        numbers = [fixed(v, DECIMALS) for v in (*command[r], *correction[r])]
        writer.writerow([*row, *numbers, "; ".join(flags[r])])
    return out.getvalue()


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
