"""Correct drilling points with a laser-tracker grid measurement (seed Eq. 12-14).

POINTS is a points CSV (x,y,z in mm in the ROBOT frame, the frame of the grid; optional id, a,b,c
or i,j,k and any other columns). Each point P gets the error e predicted from the 8 vertices of
its grid cell (inverse-distance weighting, seed Eq. 12-13, or trilinear) and the command
P' = P + e (Eq. 14; with --iterations K, P' = P + e(P') repeated K times).

The output CSV has every input column untouched, then x_cmd,y_cmd,z_cmd (the command, mm),
ex,ey,ez (the correction applied, P' - P, mm; 4 decimals) and flag (empty, or why a point
deserves a look: clamped to the grid, orientation far from the grid's).

Refused (exit 2, nothing written): any correction longer than --max-correction; unless
--allow-partial, any point the grid or model does not correct: outside the grid box (unless
--outside clamp), orientation more than --orientation-limit from the grid's (unless
--allow-orientation), another KUKA Status (column s or --status) than the grid's. The
orientation difference is the angle of the relative rotation for a,b,c points, the angle
between the drill axis and the grid tool's Z axis for i,j,k points.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from accugrid.app.cli_options import (
    COORDINATE_MAX,
    add_abc,
    add_policy,
    add_status,
    add_table_format,
    add_tool,
    number,
    policy_request,
)
from accugrid.app.jobs.correct import CorrectRequest, correct_points
from accugrid.compensation.grid import MAX_CORRECTION_MM
from accugrid.compensation.interpolation import MAX_POWER
from accugrid.compensation.measurements import REPEAT_TOL_MM
from accugrid.compensation.settings import CorrectionSettings
from accugrid.infra.atomic import check_targets, write_files

__all__ = ["NAME", "add_arguments", "run"]

NAME = "correct"


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
        "KUKA Status 0..7 of points without a column s; a grid corrects only points in the "
        "Status it was measured in (with --model default: the grid's, without --grid the IK "
        "default at the first point)",
    )
    add_abc(parser, "with --model: orientation of points without a,b,c, reference for i,j,k axes")
    add_tool(
        parser,
        "with --model: the tool whose tip is to land (the drill as taught), on the controller "
        "and the calibrated arm",
        "the SMR the model was measured with: its identification.controller_tool and "
        "identified TCP",
    )
    add_policy(parser, "points")
    parser.add_argument("-o", "--output", required=True, metavar="OUT", help="CSV to write")
    parser.add_argument(
        "--method",
        choices=["idw", "trilinear"],
        default="idw",
        help="interpolation over the cell's 8 vertices (default: idw, the seed's)",
    )
    parser.add_argument(
        "--power",
        type=number("", 0, MAX_POWER, above=True),
        default=1.0,
        metavar="P",
        help="inverse-distance power p, weights 1/s^p, 0 < p <= 16 (default: 1, the seed's)",
    )
    parser.add_argument(
        "--iterations",
        type=number("", 1, 100, whole=True),
        default=1,
        metavar="K",
        help="fixed-point iterations of P' = P + e(P') (default: 1 = seed Eq. 14)",
    )
    parser.add_argument(
        "--max-correction",
        type=number("mm", 0, COORDINATE_MAX, above=True),
        default=MAX_CORRECTION_MM,
        metavar="MM",
        help=f"refuse the job if any correction is longer than this, mm "
        f"(default: {MAX_CORRECTION_MM:g})",
    )
    parser.add_argument(
        "--repeat-tol",
        type=number("mm", 0, COORDINATE_MAX),
        default=REPEAT_TOL_MM,
        metavar="MM",
        help="largest distance of a repeated measurement from its mean, mm "
        f"(default: {REPEAT_TOL_MM:g})",
    )
    parser.add_argument(
        "--report-html",
        metavar="FILE",
        help="also write the self-contained HTML report (inputs with SHA-256, a map of the "
        "corrections, the positions flagged or not corrected with the reasons)",
    )
    add_table_format(parser)
    parser.add_argument("--force", action="store_true", help="overwrite an existing output")


def run(args: argparse.Namespace) -> int:
    settings = CorrectionSettings(
        method=args.method,
        power=args.power,
        iterations=args.iterations,
        max_correction_mm=args.max_correction,
    )
    request = CorrectRequest(
        points=args.points,
        output=args.output,
        grid=args.grid,
        model=args.model,
        settings=settings,
        policy=policy_request(args),
        repeat_tol_mm=args.repeat_tol,
        status=args.status,
        abc=tuple(args.abc),
        tool=None if args.tool is None else tuple(args.tool),
        report_html=args.report_html,
    )
    model_file = args.model if args.model and Path(args.model).is_file() else None
    targets = [args.output] + ([args.report_html] if args.report_html else [])
    check_targets(targets, [args.points, args.grid, model_file], args.force)
    if request.model is not None:
        from accugrid.app.jobs.correct_model import correct_by_model  # only when asked: slower

        job = correct_by_model(request)
    else:
        job = correct_points(request)
    write_files(job.files, job.inputs, args.force)
    for line in job.warnings:
        print(f"accugrid correct: warning: {line}", file=sys.stderr)
    for line in job.lines:
        print(line)
    return 0
