"""``accugrid plan``: measurement plans (``jobs.plan``) and the measurement program of the
``--dialect``, its paragraph of the help from the dialect's plug-in (``DialectHelp.measure``).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from types import SimpleNamespace

from accugrid.app.cli_options import (
    COORDINATE_MAX,
    MAX_CANDIDATES,
    MAX_POSES,
    MAX_REPEATS,
    add_abc,
    add_deprecated,
    add_experiment_arguments,
    add_harmonics,
    add_robot,
    add_status,
    add_tilt,
    add_tool,
    harmonics_of,
    number,
    parse_centres,
    parse_steps,
    robot_with_tool,
)
from accugrid.app.jobs.plan import PlanRequest, plan_files, plan_targets
from accugrid.codegen.dialects import measuring, plugin_of
from accugrid.compensation.plans import SEED_REGION, SEED_REPEATS
from accugrid.infra.atomic import check_targets, write_files
from accugrid.infra.errors import InputError

__all__ = ["command"]

NAME = "plan"
_DESCRIPTION = """\
Write a measurement plan: the positions a laser-tracker operator measures, in order.

  grid        vertices of a regular grid over a region, serpentine (boustrophedon) order: every
              move goes to a neighbouring vertex, so the path is as short as a grid allows; the
              path length is printed next to the naive raster order's.
  cube        one cube's vertices C1..C8 and test points P1..P9 (GB/T 12642-2001 / ISO 9283:1998
              test points plus the seed's P6..P9, seed Sec. 4.3), --repeats times.
  experiment  the seed's step experiment (Sec. 4.2, 5): for every centre and step, the cube's 8
              vertices and 9 test points, --repeats times each (default: seed Table 3 centres
              D-H, steps 20..500 mm every 60, 5 repeats, A B C = 0 90 0).
  identify    --count poses for `accugrid identify`: from --candidates random positions in
              --region at orientations within --tilt deg of --abc, reachable in the Status with
              |A5| >= 10 deg, the set that best tells apart the terms identify's structure
              search chooses from (--design library, the default: Bayesian D-optimal for DH
              errors, TCP, reducer harmonics of orders 1..16 per axis and the gravity groups;
              --design dh: D-optimal for DH errors and TCP, with --compliance/--harmonics those
              too), visited in nearest-neighbour order; a,b,c per row and column s (the Status).
              --augment CAL.yaml: D-optimal for the structure a calibrated file was fitted
              with (a second session for that model); it also prints which candidates of
              identify's structure search the poses cannot separate.
  tool        --count orientations (default 8) for `accugrid identify-tool` of the --tool as
              taught, about one point (--centre; default: the centre of --model's calibrated
              region) with the drill axis within --tilt deg of --abc's, turned about itself,
              inside the joint ranges --model was calibrated in, spread so that an offset of
              the robot frame hardly enters the TCP; column point (tip; --axis-point: the same
              poses again as axis rows for an SMR on the drill axis).

Outputs in DIR: NAME.csv (id,x,y,z,a,b,c[,centre,step,label,repeat],x_meas,y_meas,z_meas with
the measured columns empty for the operator) and the measurement program in the language of
--dialect, which visits every row and waits at each for the tracker:

{programs}
Every position is checked with the robot's IK (--robot, --tool) in one KUKA Status for the whole
plan (--status; default: the IK default at the first position), since linear moves keep the
first joint move's configuration. Lengths in mm, angles in deg, speeds in mm/s.
"""


def command(name: str) -> SimpleNamespace:
    """The command: ``NAME``, ``__doc__`` (its description, with the measurement program of
    every dialect that writes one), ``add_arguments`` and ``run``."""
    programs = "\n".join(plugin_of(dialect).help.measure for dialect in measuring())
    return SimpleNamespace(
        NAME=name,
        __doc__=_DESCRIPTION.format(programs=programs),
        add_arguments=add_arguments,
        run=run,
    )


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="kind", metavar="KIND", required=True)
    grid = sub.add_parser("grid", help="grid vertices over a region, serpentine order")
    _add_region(grid)
    grid.add_argument(
        "--step",
        type=number("mm", 0, COORDINATE_MAX, above=True),
        required=True,
        metavar="MM",
        help="grid step, mm; a side that is not a whole number of steps gets the next "
        "smaller step that is",
    )
    grid.add_argument(
        "--order",
        choices=["serpentine", "naive"],
        default="serpentine",
        help="visiting order (default: serpentine)",
    )
    grid.add_argument(
        "--repeats",
        type=number("", 1, MAX_REPEATS, whole=True),
        default=1,
        help="passes over the grid (default: 1)",
    )
    cube = sub.add_parser("cube", help="one cube's vertices C1..C8 and test points P1..P9")
    cube.add_argument(
        "--centre",
        nargs=3,
        type=number("mm", -COORDINATE_MAX, COORDINATE_MAX),
        required=True,
        metavar=("X", "Y", "Z"),
        help="mm",
    )
    cube.add_argument(
        "--step",
        type=number("mm", 0, COORDINATE_MAX, above=True),
        required=True,
        metavar="MM",
        help="cube edge, mm",
    )
    cube.add_argument(
        "--repeats",
        type=number("", 1, MAX_REPEATS, whole=True),
        default=SEED_REPEATS,
        help=f"passes over the cube (default: {SEED_REPEATS})",
    )
    exp = sub.add_parser("experiment", help="the seed's step experiment (Sec. 4.2, 5)")
    add_experiment_arguments(exp)
    ident = sub.add_parser("identify", help="poses for a kinematic identification")
    _add_region(ident)
    ident.add_argument(
        "--count",
        type=number("poses", 1, MAX_POSES, whole=True),
        required=True,
        metavar="N",
        help=f"number of poses to measure (at most {MAX_POSES})",
    )
    add_tilt(ident, "largest rotation from --abc")
    ident.add_argument(
        "--candidates",
        type=number("candidate poses", 1, MAX_CANDIDATES, whole=True),
        default=2000,
        help=f"random candidate poses to choose from (default: 2000, at most {MAX_CANDIDATES})",
    )
    ident.add_argument(
        "--repeats",
        type=number("", 1, MAX_REPEATS, whole=True),
        default=1,
        help="passes over the poses (default: 1)",
    )
    ident.add_argument(
        "--seed",
        type=number("", 0, 2**32 - 1, whole=True),
        default=0,
        help="seed of the candidates (default: 0)",
    )
    ident.add_argument(
        "--compliance",
        action="store_true",
        help="choose the poses for `identify --compliance` too (the robot's gravity model)",
    )
    add_harmonics(ident, "choose the poses for `identify --harmonics` with these terms too")
    ident.add_argument(
        "--design",
        choices=["library", "dh"],
        default="library",
        help="library: poses that tell apart the joint-error terms identify's structure search "
        "chooses from (Bayesian D-optimal, default); dh: D-optimal for DH errors and TCP (and "
        "--compliance, --harmonics) only",
    )
    ident.add_argument(
        "--augment",
        metavar="CAL.yaml",
        help="choose the poses D-optimal for the structure a calibrated robot file was fitted "
        "with (its harmonics, compliance and gravity groups; --design does not apply): a "
        "second, short session for that model",
    )
    tool = sub.add_parser("tool", help="orientations for `accugrid identify-tool`")
    tool.add_argument(
        "--model",
        required=True,
        metavar="CAL.yaml",
        help="the calibrated arm (accugrid identify): the poses stay in its joint ranges",
    )
    tool.add_argument(
        "--centre",
        nargs=3,
        type=number("mm", -COORDINATE_MAX, COORDINATE_MAX),
        metavar=("X", "Y", "Z"),
        help="where the tool's point stays, robot frame, mm (default: the centre of the "
        "model's calibrated region)",
    )
    tool.add_argument(
        "--count",
        type=number("orientations", 6, MAX_POSES, whole=True),
        default=8,
        metavar="N",
        help="orientations to measure (at least 6; default: 8)",
    )
    add_tilt(tool, "largest tilt of the drill axis from --abc")
    tool.add_argument(
        "--repeats",
        type=number("", 1, MAX_REPEATS, whole=True),
        default=3,
        help="passes over the orientations (default: 3)",
    )
    tool.add_argument(
        "--candidates",
        type=number("candidate orientations", 1, MAX_CANDIDATES, whole=True),
        default=400,
        help="random candidate orientations to choose from (default: 400)",
    )
    tool.add_argument(
        "--seed",
        type=number("", 0, 2**32 - 1, whole=True),
        default=0,
        help="seed of the candidates (default: 0)",
    )
    tool.add_argument(
        "--axis-point",
        action="store_true",
        help="the poses again for an SMR on the drill axis (rows with point axis): measures "
        "the drill axis too",
    )
    for p in (grid, cube, exp, ident, tool):
        _common(p)


def _add_region(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--region",
        nargs=6,
        type=number("mm", -COORDINATE_MAX, COORDINATE_MAX),
        metavar=("XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"),
        default=[SEED_REGION[0][0], SEED_REGION[1][0], SEED_REGION[0][1], SEED_REGION[1][1]]
        + [SEED_REGION[0][2], SEED_REGION[1][2]],
        help="box in the robot frame, mm (default: the seed's 1000 x 1200 x 1000 mm region "
        "placed at X 1200..2200, Y -600..600, Z 1100..2100)",
    )


def _common(parser: argparse.ArgumentParser) -> None:
    add_abc(parser, "fixed TCP orientation")
    add_robot(parser, "robot for the reach check and S/T (its nominal model)")
    add_tool(parser, "measured point (SMR) on the flange")
    add_status(
        parser,
        "KUKA Status 0..7 for every position (default: the IK default configuration "
        "at the first position)",
    )
    parser.add_argument(
        "--tool-number",
        type=number("", 1, 32, whole=True),
        default=1,
        help="tool number in the program (default: 1)",
    )
    parser.add_argument(
        "--base-number",
        type=number("", 0, 32, whole=True),
        default=0,
        help="base number in the program; 0 = the robot frame (default: 0)",
    )
    parser.add_argument(
        "--ptp-percent",
        type=number("%", 1, 100, whole=True),
        default=20,
        metavar="P",
        help="speed of the first joint move, %% of maximum (default: 20)",
    )
    parser.add_argument(
        "--speed",
        type=number("mm/s", 0, 2000, above=True),
        default=250.0,
        metavar="MM_S",
        help="linear speed between positions, mm/s (default: 250)",
    )
    add_deprecated(
        parser,
        "--vel",
        "--speed",
        "speed",
        convert=lambda m_s: 1000.0 * m_s,
        type=number("m/s", 0, 2, above=True),
        metavar="M_S",
    )
    wait = parser.add_mutually_exclusive_group()
    wait.add_argument(
        "--wait-sec",
        type=number("s", 0, 1e6),
        default=3.0,
        metavar="S",
        help="dwell at each position for the tracker, s (default: 3)",
    )
    wait.add_argument(
        "--wait-input",
        type=number("", 1, 4096, whole=True),
        metavar="N",
        help="instead of a dwell, wait at each position until digital input N is on",
    )
    parser.add_argument("--name", help="program and file name (default: measure_KIND)")
    parser.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")
    parser.add_argument(
        "--templates",
        type=Path,
        help="copy of the templates folder (or of its folder of the --dialect) with the "
        "measurement program's templates (default: built-in)",
    )
    dialects = measuring()
    parser.add_argument(
        "--dialect",
        choices=dialects,
        default=dialects[0],
        help="language of the measurement program (default: %(default)s)",
    )


def run(args: argparse.Namespace) -> int:
    check_targets(plan_targets(args.output, args.kind, args.name, args.dialect), force=args.force)
    kind = args.kind
    if kind == "tool" and args.tool is None:
        raise InputError("plan tool needs --tool X Y Z A B C: the tool as taught")
    robot = robot_with_tool(args.model if kind == "tool" else args.robot, args.tool)
    compliance = kind == "identify" and args.compliance
    harmonics = harmonics_of(args) if kind == "identify" else ()
    gravity = ()
    design = args.design if kind == "identify" else "dh"
    if kind == "identify" and args.augment:
        design = "dh"
        from accugrid.kinematics.calibrated import chosen_structure

        chosen = chosen_structure(args.augment, robot)
        compliance = compliance or chosen[0]
        harmonics = tuple(dict.fromkeys(harmonics + chosen[1]))
        gravity = chosen[2]
    request = PlanRequest(
        kind=kind,
        robot=robot,
        abc=tuple(args.abc),
        status=args.status,
        region=tuple(args.region) if kind in ("grid", "identify") else None,
        step_mm=args.step if kind in ("grid", "cube") else None,
        order=args.order if kind == "grid" else "serpentine",
        repeats=args.repeats,
        centre=tuple(args.centre) if kind in ("cube", "tool") and args.centre else None,
        centres=parse_centres(args.centre) if kind == "experiment" else None,
        steps=parse_steps(args.steps) if kind == "experiment" else None,
        count=args.count if kind in ("identify", "tool") else 0,
        tilt_deg=args.tilt if kind in ("identify", "tool") else 0.0,
        candidates=args.candidates if kind in ("identify", "tool") else 0,
        seed=args.seed if kind in ("identify", "tool") else 0,
        compliance=compliance,
        harmonics=harmonics,
        gravity=gravity,
        design=design,
        name=args.name,
        tool_number=args.tool_number,
        base_number=args.base_number,
        ptp_percent=args.ptp_percent,
        vel_m_s=args.speed / 1000.0,
        wait_sec=args.wait_sec,
        wait_input=args.wait_input,
        templates=args.templates,
        dialect=args.dialect,
        model=args.model if kind == "tool" else None,
        axis_point=kind == "tool" and args.axis_point,
    )
    job = plan_files(request, args.output)
    write_files(job.files, force=args.force, main=job.main)
    for line in job.lines:
        print(line)
    return 0
