"""Which correction, from how many measured points: grid only (IDW, trilinear), model only and
model + residual grid, held out on a simulated robot (--robot; compensation.comparison).

For each budget N of measured points (--budgets): the grid over --region with at most N vertices at
the grid orientation (--abc), corrected P' = P + e(P) by IDW and by trilinear interpolation; the
model identified (DH errors, TCP, A2/A3 compliance when the robot has a gravity model) from the N
poses `plan identify --design dh` chooses (D-optimal among --candidates random poses tilted up to
--tilt deg); the model plus a 27-vertex residual grid at the grid orientation (trilinear); the model
plus its residual at the poses interpolated in joint space (A1-A3, thin-plate spline; its 5-fold
cross-validation over the poses is printed); with --harmonics a model that also identifies those
reducer harmonics, alone and with the residual grid. Every measurement is a simulated tracker
session (one KUKA Status, --repeats per point, seeded noise per budget). Scored on --targets
held-out targets at the grid orientation and --targets tilted up to --target-tilt deg: where the arm
lands when commanded P' (noise-free), max |P - M| and std per axis, mm.

Output: the table on stdout, DIR/comparison.csv (one row per budget, target set and method) and
DIR/comparison_max.png and DIR/comparison_std.png (the tolerance, or the std limit, as a line).
Lengths in mm, angles in degrees.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from accugrid.app.cli_options import (
    COORDINATE_MAX,
    MAX_CANDIDATES,
    MAX_COUNT,
    MAX_POSES,
    MAX_REPEATS,
    add_abc,
    add_deprecated,
    add_harmonics,
    add_robot,
    add_status,
    add_tilt,
    add_tool,
    harmonics_of,
    number,
    robot_with_tool,
)
from accugrid.app.reports.comparison import csv_text, html_report, report_text
from accugrid.compensation.comparison import compare_methods
from accugrid.compensation.plans import SEED_REGION
from accugrid.infra.atomic import check_targets, write_files
from accugrid.infra.errors import InputError

__all__ = ["NAME", "add_arguments", "run"]

NAME = "compare"

DEFAULT_BUDGETS = (27, 60, 125, 252)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_robot(parser, "simulated robot (its true robot, with errors, is the real arm)")
    add_deprecated(parser, "--simulate", "--robot", "robot")
    parser.add_argument(
        "--region",
        nargs=6,
        type=number("mm", -COORDINATE_MAX, COORDINATE_MAX),
        default=[v for pair in zip(*SEED_REGION, strict=True) for v in pair],
        metavar=("XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"),
        help="measured region in the robot frame, mm (default: the seed's 1200 2200 -600 600 "
        "1100 2100)",
    )
    parser.add_argument(
        "--budgets",
        nargs="+",
        type=number("poses", 1, MAX_POSES, whole=True),
        default=list(DEFAULT_BUDGETS),
        metavar="N",
        help="measured-point budgets (distinct poses or vertices; default: 27 60 125 252; "
        f"at most {MAX_POSES})",
    )
    add_abc(parser, "grid orientation (grids, residual grid, untilted targets)")
    add_tool(parser, "tool on the flange (the controller's TOOL_DATA)")
    add_status(parser, "KUKA Status 0..7 of every pose (default: the IK default's at the centre)")
    add_tilt(parser, "identification poses tilted up to this from --abc")
    parser.add_argument(
        "--target-tilt",
        type=number("deg", 0, 180),
        default=25.0,
        metavar="DEG",
        help="tilted held-out targets up to this from --abc, deg (default: 25)",
    )
    parser.add_argument(
        "--targets",
        type=number("", 1, MAX_COUNT, whole=True),
        default=200,
        metavar="N",
        help="held-out targets per set (default: 200)",
    )
    parser.add_argument(
        "--candidates",
        type=number("candidate poses", 1, MAX_CANDIDATES, whole=True),
        default=1500,
        metavar="N",
        help="random candidate poses the model's poses are chosen from "
        f"(default: 1500, at most {MAX_CANDIDATES})",
    )
    parser.add_argument(
        "--repeats",
        type=number("", 1, MAX_REPEATS, whole=True),
        default=3,
        help="measurements per point (default: 3)",
    )
    parser.add_argument(
        "--noise-tracker",
        type=number("mm", 0, 1000),
        default=0.02,
        metavar="MM",
        help="tracker noise, Gaussian sigma per axis, mm (default: 0.02)",
    )
    parser.add_argument(
        "--noise-repeat",
        type=number("mm", 0, 1000),
        default=0.03,
        metavar="MM",
        help="robot repeatability, sigma per axis and visit, mm (default: 0.03)",
    )
    add_harmonics(
        parser,
        "also compare a model with these reducer harmonics identified (budgets of at least "
        "its parameter count)",
    )
    parser.add_argument(
        "--seed",
        type=number("", 0, 2**32 - 1, whole=True),
        default=0,
        help="random seed (default: 0)",
    )
    parser.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="DIR",
        help="folder for comparison.csv, comparison_max.png and comparison_std.png",
    )
    parser.add_argument(
        "--report-html",
        metavar="FILE",
        help="also write the self-contained HTML report (settings, table, both figures)",
    )
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")


def run(args: argparse.Namespace) -> int:
    out = Path(args.output)
    from accugrid.app.reports.plots import COMPARISON_STATS, comparison_png

    paths = [str(out / "comparison.csv")]
    paths += [str(out / f"comparison_{stat}.png") for stat in COMPARISON_STATS]
    inputs = [args.robot] if Path(args.robot).is_file() else []
    check_targets(paths + ([args.report_html] if args.report_html else []), inputs, args.force)
    if not args.budgets or min(args.budgets) < 8:
        raise InputError("--budgets: every budget must be at least 8 points")
    if args.targets < 1 or args.repeats < 1:
        raise InputError("--targets and --repeats must be at least 1")
    if not 0.0 <= args.target_tilt <= 90.0:
        raise InputError(f"--target-tilt must be 0..90 deg, got {args.target_tilt:g}")
    robot = robot_with_tool(args.robot, args.tool)
    if robot.true_robot() is None:
        raise InputError(f"robot {robot.name} has no errors: nothing to compare")
    lo, hi = args.region[0::2], args.region[1::2]
    result = compare_methods(
        robot,
        lo,
        hi,
        sorted(set(args.budgets)),
        abc_deg=args.abc,
        status=args.status,
        tilt_deg=args.tilt,
        target_tilt_deg=args.target_tilt,
        n_targets=args.targets,
        candidates=args.candidates,
        repeats=args.repeats,
        noise_tracker_mm=args.noise_tracker,
        noise_repeat_mm=args.noise_repeat,
        seed=args.seed,
        harmonics=harmonics_of(args),
    )
    out.mkdir(parents=True, exist_ok=True)
    files = {paths[0]: csv_text(result)}
    for path, stat in zip(paths[1:], COMPARISON_STATS, strict=True):
        files[path] = comparison_png(result, stat)
    if args.report_html:
        pngs = dict(zip(COMPARISON_STATS, list(files.values())[1:], strict=True))
        files[args.report_html] = html_report(result, pngs, [("robot", args.robot)])
        paths.append(args.report_html)
    write_files(files, inputs, force=args.force)
    print(report_text(result))
    for path in paths:
        print(f"wrote {path}")
    return 0
