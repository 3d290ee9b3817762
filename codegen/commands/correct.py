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

With --model CAL.yaml the points are corrected by a calibrated robot model at any orientation
(--grid then optional: the residual after the model; see codegen/correct_model.py).
"""

from __future__ import annotations

import argparse
import csv
import io

import numpy as np

from accugrid.codegen.atomic import check_targets, write_files
from accugrid.codegen.cli_options import add_abc, add_status
from accugrid.codegen.points import Points, read_points
from accugrid.codegen.textsafe import comment_text, fixed
from accugrid.compensation.grid import MAX_CORRECTION_MM, GridModel
from accugrid.compensation.measurements import REPEAT_TOL_MM
from accugrid.compensation.orientation import rotation_angle_deg
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix

NAME = "correct"
HELP = "corrected points CSV: P' = P + e, e interpolated from a measured error grid"

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


def run(args: argparse.Namespace) -> int:
    if args.model is not None:
        from accugrid.codegen.correct_model import run_model

        return run_model(args)
    if args.grid is None:
        raise InputError("give --grid MEAS, --model CAL.yaml or both")
    if not args.max_correction > 0:
        raise InputError(f"--max-correction must be > 0 mm, got {args.max_correction}")
    if not 0 <= args.orientation_tol <= args.orientation_limit:
        raise InputError("need 0 <= --orientation-tol <= --orientation-limit (deg)")
    check_targets([args.output], [args.points, args.grid], args.force)
    model = GridModel.from_measurements(args.grid, repeat_tol_mm=args.repeat_tol)
    points = read_points(args.points)
    check_added_columns(points)
    flags: list[list[str]] = [[] for _ in range(len(points))]
    _check_outside(points, model, args.outside, flags)
    _check_orientation(points, model, args, flags)
    command = model.correct(
        points.xyz,
        iterations=args.iterations,
        method=args.method,
        power=args.power,
        outside=args.outside,
        max_correction_mm=None,
    )
    correction, length, worst = check_max_correction(points, command, args.max_correction)
    header = (
        f"accugrid correct: grid {args.grid} sha256 {model.source_sha256}, method "
        f"{args.method}, power {args.power:g}, iterations {args.iterations}"
    )
    text = _corrected_csv(points, command, correction, flags, header)
    write_files({args.output: text}, [args.points, args.grid], force=args.force)
    _print_summary(model, points, args, length, worst, flags)
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


def check_max_correction(
    points: Points, command: np.ndarray, limit_mm: float
) -> tuple[np.ndarray, np.ndarray, int | None]:
    """(correction P' - P (N, 3), its length (N,), index of the longest or None); InputError
    naming the point when the longest exceeds ``limit_mm``."""
    correction = command - points.xyz
    length = np.linalg.norm(correction, axis=1)
    worst = int(np.argmax(length)) if len(points) else None
    if worst is not None and length[worst] > limit_mm:
        raise InputError(
            f"{points.label(worst)}: correction of {length[worst]:.3f} mm exceeds the safety "
            f"limit of {limit_mm:g} mm; refusing the whole job (check the grid or model)",
            *points.table.where(worst),
        )
    return correction, length, worst


def _check_outside(points: Points, model: GridModel, rule: str, flags: list[list[str]]) -> None:
    outside = np.flatnonzero(~model.contains(points.xyz))
    if not outside.size:
        return
    if rule == "error":
        named = "; ".join(points.label(int(i)) for i in outside[:_LISTED])
        more = f" and {outside.size - _LISTED} more" if outside.size > _LISTED else ""
        raise InputError(
            f"{outside.size} point(s) outside the grid box {_fmt(model.origin)}.."
            f"{_fmt(model.upper)} mm (robot frame): {named}{more} (--outside clamp uses the "
            "nearest cell)",
            *points.table.where(int(outside[0])),
        )
    for i in outside:
        flags[i].append("outside grid: clamped")


def orientation_difference_deg(points: Points, model: GridModel) -> np.ndarray | None:
    """(N,) deg between each point's orientation and the grid's, or None if either lacks one."""
    if model.orientation_abc is None or points.orientation is None or not len(points):
        return None
    if points.abc is not None:
        return rotation_angle_deg(points.abc, model.orientation_abc)
    tool_z = abc_to_matrix(model.orientation_abc)[:, 2]
    return np.degrees(np.arccos(np.clip(points.axis @ tool_z, -1.0, 1.0)))


def _check_orientation(
    points: Points, model: GridModel, args: argparse.Namespace, flags: list[list[str]]
) -> None:
    angle = orientation_difference_deg(points, model)
    if angle is None:
        return
    beyond = np.flatnonzero(angle > args.orientation_limit)
    if beyond.size and not args.allow_orientation:
        i = int(beyond[0])
        raise InputError(
            f"{beyond.size} point(s) more than {args.orientation_limit:g} deg from the grid's "
            f"orientation {_fmt(model.orientation_abc)} deg, first {points.label(i)} at "
            f"{angle[i]:.1f} deg: the grid does not hold there (--allow-orientation to go on)",
            *points.table.where(i),
        )
    for i in np.flatnonzero(angle > args.orientation_tol):
        flags[i].append(f"orientation {angle[i]:.1f} deg from grid")


def _corrected_csv(
    points: Points,
    command: np.ndarray,
    correction: np.ndarray,
    flags: list[list[str]],
    header: str,
) -> str:
    out = io.StringIO()
    out.write(f"# {comment_text(header, limit=400)}\n")
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow([*points.table.header, *ADDED])
    for r, row in enumerate(points.table.rows):
        numbers = [fixed(v, DECIMALS) for v in (*command[r], *correction[r])]
        writer.writerow([*row, *numbers, "; ".join(flags[r])])
    return out.getvalue()


def _print_summary(
    model: GridModel,
    points: Points,
    args: argparse.Namespace,
    length: np.ndarray,
    worst: int | None,
    flags: list[list[str]],
) -> None:
    print(model.describe())
    iterations = f"{args.iterations} iteration{'s' if args.iterations != 1 else ''}"
    power = f" power {args.power:g}" if args.method == "idw" else ""
    print(f"corrected  {len(points)} point(s), {args.method}{power}, {iterations}")
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
    print(f"wrote {args.output}")


def _fmt(v: np.ndarray) -> str:
    return "(" + ", ".join(f"{x:.3f}" for x in np.asarray(v, dtype=float)) + ")"
