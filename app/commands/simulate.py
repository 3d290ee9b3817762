"""Simulate a laser-tracker measurement of a robot's TCP error on a cubic grid.

The controller drives the nominal kinematic model to every grid vertex in ONE KUKA Status, as a LIN
program does (--status S, default: the IK default configuration's Status at the first vertex, i.e.
basic area, A3 >= phi and the wrist closest to A4 = A5 = A6 = 0); the "true" robot (nominal DH
plus the parameter errors of its YAML, e.g. seed Table 1 for kr210-paper) lands where its own
forward kinematics puts it. Optional Gaussian noise: robot repeatability and tracker, per axis,
seeded. The result is a measurement CSV (id,x,y,z,a,b,c,s,x_meas,y_meas,z_meas; mm and deg, s
the KUKA Status the grid holds in) for
`accugrid correct` & co.

--poses PLAN.csv instead measures the poses of a plan at any orientation (columns x,y,z,a,b,c,
optional id and s, e.g. from `accugrid plan identify`): each in its Status (column s, else
--status, else the IK default per pose), with the joints the controller reports (a1..a6, KUKA
deg, 4 decimals) in the output, for `accugrid identify`. A corrected points CSV (from `accugrid
correct`, with x_cmd,y_cmd,z_cmd) is measured at its commands and the rows keep its x,y,z, the
targets: the measurement after correction that `accugrid validate` checks.

--datums NOMINAL.csv --part X Y Z A B C instead measures the datums of a part (tooling balls:
id,x,y,z in the part's CAD frame) standing at robot_T_base = the --part frame, with the tracker's
noise, --repeats rows per datum: the DATUMS.csv that `accugrid fit-part` reads (id,x,y,z in the
robot frame).

--plot FILE draws seed Fig. 3: the X, Y, Z components of the error e = P - M over the plane of
seed Table 2 (X 1000..2000, Y -500..500, Z 1800 mm, A 0, B 90, C 0 deg). Lengths in mm, angles in
degrees.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from accugrid.app.cli_options import (
    COORDINATE_MAX,
    MAX_REPEATS,
    add_abc,
    add_robot,
    add_status,
    add_table_format,
    add_tool,
    number,
    robot_with_tool,
)
from accugrid.app.jobs.simulate import SimulateRequest, simulate_files
from accugrid.infra.atomic import check_targets, write_files

__all__ = ["NAME", "add_arguments", "run"]

NAME = "simulate"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_robot(parser, "simulated robot (its true robot, with errors, is the real arm)")
    parser.add_argument(
        "--region",
        nargs=6,
        type=number("mm", -COORDINATE_MAX, COORDINATE_MAX),
        metavar=("XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"),
        help="grid box in the robot frame, mm (needed with -o)",
    )
    parser.add_argument(
        "--step",
        type=number("mm", 0, COORDINATE_MAX, above=True),
        help="grid step, mm (needed with -o)",
    )
    parser.add_argument(
        "--poses",
        metavar="PLAN.csv",
        help="measure the poses of a plan (x,y,z,a,b,c[,id][,s]) instead of a grid; a corrected "
        "points CSV is measured at its x_cmd,y_cmd,z_cmd (a,b,c, or i,j,k oriented from --abc)",
    )
    parser.add_argument(
        "--smr",
        nargs=3,
        type=number("mm", -COORDINATE_MAX, COORDINATE_MAX),
        metavar=("X", "Y", "Z"),
        help="with --poses: the SMR really sits at this point of the flange, mm (a tool off its "
        "taught --tool, for identify-tool; default: at the --tool's TCP)",
    )
    parser.add_argument(
        "--smr-axis",
        nargs=3,
        type=number("mm", -COORDINATE_MAX, COORDINATE_MAX),
        metavar=("X", "Y", "Z"),
        help="with --smr: on the plan's rows whose column point is axis, the SMR sits here, mm "
        "(a point on the drill axis)",
    )
    parser.add_argument(
        "--datums",
        metavar="NOMINAL.csv",
        help="measure the datums of a part (id,x,y,z in its CAD frame, mm) standing at --part "
        "instead of a grid: the datums file of accugrid fit-part",
    )
    parser.add_argument(
        "--part",
        nargs=6,
        type=number("mm or deg", -COORDINATE_MAX, COORDINATE_MAX),
        metavar=("X", "Y", "Z", "A", "B", "C"),
        help="with --datums: where the part really stands, robot_T_base: x, y, z mm, "
        "KUKA A, B, C deg",
    )
    add_abc(parser, "TCP orientation at every vertex")
    add_tool(parser, "tool on the flange")
    add_status(
        parser, "KUKA Status 0..7 kept for every vertex (default: the IK default's at the first)"
    )
    parser.add_argument(
        "--repeats",
        type=number("", 1, MAX_REPEATS, whole=True),
        default=1,
        help="measurements per vertex (default: 1)",
    )
    parser.add_argument(
        "--noise-tracker",
        type=number("mm", 0, 1000),
        default=0.0,
        metavar="MM",
        help="laser-tracker noise, Gaussian sigma per axis, mm (default: 0)",
    )
    parser.add_argument(
        "--noise-repeat",
        type=number("mm", 0, 1000),
        default=0.0,
        metavar="MM",
        help="robot repeatability, Gaussian sigma per axis and visit, mm (default: 0)",
    )
    parser.add_argument(
        "--seed",
        type=number("", 0, 2**32 - 1, whole=True),
        default=0,
        help="random seed for the noise (default: 0)",
    )
    parser.add_argument("-o", "--output", metavar="CSV", help="measurement CSV to write")
    parser.add_argument("--plot", metavar="PNG", help="draw seed Fig. 3 into this PNG file")
    add_table_format(parser)
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")


def run(args: argparse.Namespace) -> int:
    robot_file = args.robot if Path(args.robot).is_file() else None
    inputs = [robot_file, args.poses, args.datums]
    check_targets([t for t in (args.output, args.plot) if t], inputs, args.force)
    request = SimulateRequest(
        robot=robot_with_tool(args.robot, args.tool),
        output=args.output,
        plot=args.plot,
        region=None if args.region is None else tuple(args.region),
        step_mm=args.step,
        poses=args.poses,
        abc=tuple(args.abc),
        status=args.status,
        repeats=args.repeats,
        noise_tracker_mm=args.noise_tracker,
        noise_repeat_mm=args.noise_repeat,
        seed=args.seed,
        smr=None if args.smr is None else tuple(args.smr),
        smr_axis=None if args.smr_axis is None else tuple(args.smr_axis),
        datums=args.datums,
        part=None if args.part is None else tuple(args.part),
    )
    job = simulate_files(request)
    write_files(job.files, inputs, force=args.force)
    for line in job.lines:
        print(line)
    return 0
