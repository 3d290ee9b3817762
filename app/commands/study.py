"""The statistical grid-step study of the seed (Sec. 4.2-4.4, Sec. 5): choose the largest grid
step whose compensated error meets the tolerance, then validate it (Tables 4-5, Fig. 12).

For every step, each centre's cube is modelled from its 8 vertices (IDW, seed Eq. 12-13), its 9
test points (GB/T 12642 / ISO 9283 positions plus the seed's P6-P9) are corrected (Eq. 14), and
the remaining error r = target - reached is summarised over all centres per axis: max, min and
standard deviation (Table 4; max/min are the mean over the repeats of each repeat's max/min,
the seed's rule). Cubic curves of max and min against the step give each axis's threshold step
(where a curve leaves +-tolerance, Fig. 12). The chosen step is the largest tested step within
every threshold whose measured max/min lie in the band and whose standard deviation is
"relatively small": std <= --std-fraction x tolerance on every axis. Table 5: a grid at that step
over the whole --region, errors before/after correction at --validation-points random points.

Inputs: --robot ROBOT (simulated: a built-in or YAML robot with parameter errors; tracker and
repeatability noise, seeded) or --measured FILE (the `accugrid plan experiment` CSV with
x_meas,y_meas,z_meas filled in; its test points measured without correction, so r is
(P - M) - e_pred(P), the first-order effect of the correction). With --measured, Table 5 needs
--validate GRID POINTS: the measurement CSV of the grid at the chosen step and a CSV of random
points (x,y,z,x_meas,y_meas,z_meas) measured without correction.

Outputs in DIR: table4.csv, table5.csv, fig12.png, table5_hist.png, report.md. Lengths in mm,
angles in degrees.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from accugrid.app.cli_options import (
    COORDINATE_MAX,
    MAX_COUNT,
    add_abc,
    add_deprecated,
    add_experiment_arguments,
    add_robot,
    add_status,
    add_table_format,
    add_tool,
    number,
    parse_centres,
    parse_steps,
    robot_with_tool,
)
from accugrid.app.jobs.study import OUTPUTS, StudyRequest, study_files
from accugrid.app.progress import progress
from accugrid.compensation.plans import SEED_REGION
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM
from accugrid.compensation.study import DEFAULT_STD_FRACTION, REPEAT_RULES
from accugrid.infra.atomic import check_targets, write_files

__all__ = ["NAME", "add_arguments", "run"]

NAME = "study"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    source = parser.add_mutually_exclusive_group()
    add_robot(source, "simulated robot, unless --measured")
    add_deprecated(source, "--simulate", "--robot", "robot")
    source.add_argument(
        "--measured", metavar="FILE", help="filled-in `accugrid plan experiment` CSV"
    )
    add_experiment_arguments(parser)
    add_abc(parser, "simulated TCP orientation")
    add_tool(parser, "simulated tool")
    parser.add_argument(
        "--noise-tracker",
        type=number("mm", 0, 1000),
        default=0.02,
        metavar="MM",
        help="simulated tracker noise, Gaussian sigma per axis, mm (default: 0.02)",
    )
    parser.add_argument(
        "--noise-repeat",
        type=number("mm", 0, 1000),
        default=0.03,
        metavar="MM",
        help="simulated robot repeatability, Gaussian sigma per axis, mm (default: 0.03)",
    )
    parser.add_argument(
        "--seed",
        type=number("", 0, 2**32 - 1, whole=True),
        default=0,
        help="random seed (default: 0)",
    )
    add_status(
        parser,
        "KUKA Status 0..7 the simulated robot keeps for every point, as a program of LIN "
        "moves does (default: the IK default configuration at the first centre)",
    )
    r = SEED_REGION
    parser.add_argument(
        "--region",
        nargs=6,
        type=number("mm", -COORDINATE_MAX, COORDINATE_MAX),
        metavar=("XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"),
        default=[r[0][0], r[1][0], r[0][1], r[1][1], r[0][2], r[1][2]],
        help="validation region in the robot frame, mm (default: the seed's 1000 x 1200 x 1000 "
        "mm region placed at X 1200..2200, Y -600..600, Z 1100..2100)",
    )
    parser.add_argument(
        "--tolerance",
        type=number("mm", 0, COORDINATE_MAX, above=True),
        default=DEFAULT_TOLERANCE_MM,
        metavar="MM",
        help=f"accuracy requirement +-MM per axis, mm (default: {DEFAULT_TOLERANCE_MM})",
    )
    parser.add_argument(
        "--std-fraction",
        type=number("", 0, 1e6, above=True),
        default=DEFAULT_STD_FRACTION,
        metavar="F",
        help="'relatively small' standard deviation: std <= F x tolerance on every axis "
        f"(default: {DEFAULT_STD_FRACTION})",
    )
    parser.add_argument(
        "--repeat-rule",
        choices=REPEAT_RULES,
        default=REPEAT_RULES[0],
        help="how repeats enter max/min: the seed's mean of per-repeat extremes (default) or "
        "extremes of per-point means",
    )
    parser.add_argument(
        "--validation-points",
        type=number("", 1, MAX_COUNT, whole=True),
        default=200,
        metavar="N",
        help="random points for Table 5 in simulation (default: 200)",
    )
    parser.add_argument(
        "--validation-step",
        type=number("mm", 0, COORDINATE_MAX, above=True),
        metavar="MM",
        help="in simulation, validate a grid at this step, mm, instead of the chosen one "
        "(e.g. 200 to compare with the seed's Table 5)",
    )
    parser.add_argument(
        "--validate",
        nargs=2,
        metavar=("GRID", "POINTS"),
        help="with --measured: grid measurement CSV at the chosen step and measured random points",
    )
    parser.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    add_table_format(parser)
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")


def run(args: argparse.Namespace) -> int:
    out = Path(args.output)
    inputs = [p for p in [args.measured, *(args.validate or [])] if p]
    check_targets([out / name for name in OUTPUTS], inputs=inputs, force=args.force)
    simulated = args.measured is None
    request = StudyRequest(
        robot=robot_with_tool(args.robot, args.tool) if simulated else None,
        measured=args.measured,
        centres=parse_centres(args.centre) if simulated else None,
        steps=parse_steps(args.steps) if simulated else None,
        repeats=args.repeats,
        abc=tuple(args.abc),
        status=args.status,
        noise_tracker_mm=args.noise_tracker,
        noise_repeat_mm=args.noise_repeat,
        seed=args.seed,
        region=tuple(args.region),
        tolerance_mm=args.tolerance,
        std_fraction=args.std_fraction,
        repeat_rule=args.repeat_rule,
        validation_points=args.validation_points,
        validation_step_mm=args.validation_step,
        validate=None if args.validate is None else tuple(args.validate),
    )
    job = study_files(request, out, progress)
    write_files(job.files, inputs=job.inputs, force=args.force)
    for line in job.lines:
        print(line)
    return 0
