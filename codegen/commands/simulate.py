"""Simulate a laser-tracker measurement of a robot's TCP error on a cubic grid.

The controller drives the nominal kinematic model to every grid vertex in ONE KUKA Status, as a LIN
program does (--status S, default: the IK default configuration's Status at the first vertex, i.e.
basic area, A3 >= phi and the wrist closest to A4 = A5 = A6 = 0); the "true" robot (nominal DH
plus the parameter errors of its YAML, e.g. seed Table 1 for kr210-paper) lands where its own
forward kinematics puts it. Optional Gaussian noise: robot repeatability and tracker, per axis,
seeded. The result is a measurement CSV (id,x,y,z,a,b,c,x_meas,y_meas,z_meas; mm and deg) for
`accugrid correct` & co.

--poses PLAN.csv instead measures the poses of a plan at any orientation (columns x,y,z,a,b,c,
optional id and s, e.g. from `accugrid plan identify`): each in its Status (column s, else
--status, else the IK default per pose), with the joints the controller reports (a1..a6, KUKA
deg, 4 decimals) in the output, for `accugrid identify`.

--plot FILE draws seed Fig. 3: the X, Y, Z components of the error e = P - M over the plane of
seed Table 2 (X 1000..2000, Y -500..500, Z 1800 mm, A 0, B 90, C 0 deg). Lengths in mm, angles in
degrees.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from accugrid.codegen.atomic import check_targets, write_files
from accugrid.codegen.cli_options import add_abc, add_status, add_tool, robot_with_tool
from accugrid.codegen.plots import fig3_png
from accugrid.codegen.textsafe import comment_text, fixed
from accugrid.compensation.csvtable import read_table
from accugrid.compensation.plans import check_vertex_count
from accugrid.kinematics.configuration import status_turn
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.robot import Robot
from accugrid.kinematics.simulation import (
    grid_status,
    reached_positions,
    simulate_measurements,
    simulate_pose_measurements,
)

__all__ = [
    "FIG3_ABC",
    "FIG3_X",
    "FIG3_Y",
    "FIG3_Z",
    "NAME",
    "add_arguments",
    "fig3_field",
    "grid_points",
    "run",
]

NAME = "simulate"

FIG3_X = (1000.0, 2000.0)
FIG3_Y = (-500.0, 500.0)
FIG3_Z = 1800.0
FIG3_ABC = (0.0, 90.0, 0.0)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--robot",
        default="kr210-paper",
        help="built-in robot (kr210, kr210-paper) or robot YAML file (default: kr210-paper)",
    )
    parser.add_argument(
        "--region",
        nargs=6,
        type=float,
        metavar=("XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"),
        help="grid box in the robot frame, mm (needed with -o)",
    )
    parser.add_argument("--step", type=float, help="grid step, mm (needed with -o)")
    parser.add_argument(
        "--poses",
        metavar="PLAN.csv",
        help="measure the poses of a plan (x,y,z,a,b,c[,id][,s]) instead of a grid",
    )
    add_abc(parser, "TCP orientation at every vertex")
    add_tool(parser, "tool on the flange (flange_T_tool), mm and deg (default: the flange itself)")
    add_status(
        parser, "KUKA Status 0..7 kept for every vertex (default: the IK default's at the first)"
    )
    parser.add_argument(
        "--repeats", type=int, default=1, help="measurements per vertex (default: 1)"
    )
    parser.add_argument(
        "--noise-tracker",
        type=float,
        default=0.0,
        metavar="MM",
        help="laser-tracker noise, Gaussian sigma per axis, mm (default: 0)",
    )
    parser.add_argument(
        "--noise-repeat",
        type=float,
        default=0.0,
        metavar="MM",
        help="robot repeatability, Gaussian sigma per axis and visit, mm (default: 0)",
    )
    parser.add_argument(
        "--seed", type=int, default=0, help="random seed for the noise (default: 0)"
    )
    parser.add_argument("-o", "--output", metavar="CSV", help="measurement CSV to write")
    parser.add_argument("--plot", metavar="PNG", help="draw seed Fig. 3 into this PNG file")
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")


def run(args: argparse.Namespace) -> int:
    if not args.output and not args.plot:
        raise InputError("nothing to do: give -o CSV and/or --plot PNG")
    inputs = ([args.robot] if _is_file(args.robot) else []) + ([args.poses] if args.poses else [])
    check_targets([t for t in (args.output, args.plot) if t], inputs, args.force)
    robot = robot_with_tool(args.robot, args.tool)
    if robot.true_robot() is None:
        print(
            f"note: robot {robot.name} has no parameter errors; the simulated error is noise only"
        )
    outputs: dict[str, bytes | str] = {}
    if args.output and args.poses:
        outputs[args.output] = _pose_measurement_csv(robot, args)
    elif args.output:
        outputs[args.output] = _measurement_csv(robot, args)
    if args.plot:
        xs, ys, error = fig3_field(robot, status=args.status)
        for k, axis in enumerate("XYZ"):
            field = error[:, :, k]
            print(f"  Fig. 3 D_{axis}: min {field.min():.3f}  max {field.max():.3f} mm")
        outputs[args.plot] = fig3_png(robot.name, xs, ys, error, FIG3_Z, FIG3_ABC)
    write_files(outputs, inputs, force=args.force)
    for path in outputs:
        print(f"wrote {path}")
    return 0


def grid_points(region: list[float], step_mm: float) -> tuple[np.ndarray, list[str]]:
    """Vertices (N, 3) mm of the grid from each region minimum in ``step_mm`` up to the maximum
    (x outermost, z innermost), and notes for axes whose maximum is not on the step."""
    if step_mm is None or not step_mm > 0:
        raise InputError(f"--step must be positive, got {step_mm}")
    check_vertex_count(np.floor(np.ptp(np.reshape(region, (3, 2)), axis=1) / step_mm) + 1, step_mm)
    axes, notes = [], []
    for name, lo, hi in zip("XYZ", region[0::2], region[1::2], strict=True):
        if not lo < hi:
            raise InputError(f"--region: {name} minimum {lo:g} must be below maximum {hi:g}")
        count = int(np.floor((hi - lo) / step_mm + 1e-9)) + 1
        values = lo + step_mm * np.arange(count)
        if hi - values[-1] > 1e-6:
            notes.append(f"{name} stops at {values[-1]:g} (region maximum {hi:g} is off the step)")
        axes.append(values)
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.column_stack([m.ravel() for m in mesh]), notes


def _measurement_csv(robot: Robot, args: argparse.Namespace) -> str:
    if args.region is None or args.step is None:
        raise InputError("-o needs --region XMIN XMAX YMIN YMAX ZMIN ZMAX and --step MM")
    points, notes = grid_points(args.region, args.step)
    for note in notes:
        print(f"note: {note}")
    status = args.status if args.status is not None else grid_status(robot, points, args.abc)
    if status is not None:
        print(f"KUKA Status {status} (binary {status:03b}) for every vertex")
    commanded, measured = simulate_measurements(
        robot,
        points,
        args.abc,
        repeats=args.repeats,
        noise_tracker_mm=args.noise_tracker,
        noise_repeat_mm=args.noise_repeat,
        seed=args.seed,
        status=status,
    )
    error = points - reached_positions(robot, points, args.abc, status)
    _print_summary(robot, len(points), args.repeats, error, commanded - measured)

    region = " ".join(f"{v:g}" for v in args.region)
    header = comment_text(
        f"accugrid simulate: robot {robot.name}, region {region} mm, step {args.step:g} mm, "
        f"abc {' '.join(f'{v:g}' for v in args.abc)} deg, status {status}, repeats {args.repeats}, "
        f"noise tracker {args.noise_tracker:g} mm, repeat {args.noise_repeat:g} mm, "
        f"seed {args.seed}",
        limit=400,
    )
    lines = [f"# {header}", "id,x,y,z,a,b,c,x_meas,y_meas,z_meas"]
    abc = ",".join(fixed(v, 4) for v in args.abc)
    ids = np.repeat(np.arange(1, len(points) + 1), args.repeats)
    for ident, cmd, meas in zip(ids, commanded, measured, strict=True):
        cmd_text = ",".join(fixed(v, 4) for v in cmd)
        meas_text = ",".join(fixed(v, 4) for v in meas)
        lines.append(f"P{ident},{cmd_text},{abc},{meas_text}")
    return "\n".join(lines) + "\n"


def _pose_measurement_csv(robot: Robot, args: argparse.Namespace) -> str:
    """The measurement CSV of the plan's poses, with the controller's joints a1..a6 and s."""
    if args.region is not None or args.step is not None:
        raise InputError("--poses and --region/--step exclude each other")
    table = read_table(args.poses)
    table.require(["x", "y", "z", "a", "b", "c"])
    if not len(table):
        raise InputError("no poses in the plan", args.poses)
    xyzabc = table.floats(["x", "y", "z", "a", "b", "c"])
    ids = table.text("id") if table.has("id") else [f"P{i + 1}" for i in range(len(table))]
    status = args.status
    if table.has("s"):
        status = table.floats(["s"])[:, 0].astype(int)
    try:
        q, measured = simulate_pose_measurements(
            robot,
            pose_from_xyzabc(xyzabc),
            status,
            repeats=args.repeats,
            noise_tracker_mm=args.noise_tracker,
            noise_repeat_mm=args.noise_repeat,
            seed=args.seed,
        )
    except InputError as exc:
        raise InputError(exc.message, args.poses) from None
    status_of = status_turn(robot, q)[0]
    header = comment_text(
        f"accugrid simulate: robot {robot.name}, poses of {Path(args.poses).name}, repeats "
        f"{args.repeats}, noise tracker {args.noise_tracker:g} mm, repeat "
        f"{args.noise_repeat:g} mm, seed {args.seed}",
        limit=400,
    )
    lines = [f"# {header}", "id,x,y,z,a,b,c,s,a1,a2,a3,a4,a5,a6,x_meas,y_meas,z_meas"]
    rows = np.repeat(np.arange(len(table)), args.repeats)
    joints = np.degrees(q)
    for row, meas in zip(rows, measured, strict=True):
        pose_text = ",".join(fixed(v, 4) for v in xyzabc[row])
        joint_text = ",".join(fixed(v, 4) for v in joints[row])
        meas_text = ",".join(fixed(v, 4) for v in meas)
        ident = comment_text(ids[row], limit=40).replace(",", " ")
        lines.append(f"{ident},{pose_text},{status_of[row]},{joint_text},{meas_text}")
    print(f"{robot.name}: {len(table)} poses x {args.repeats} repeats = {len(rows)} rows")
    return "\n".join(lines) + "\n"


def _print_summary(
    robot: Robot, n_points: int, repeats: int, error: np.ndarray, measured_error: np.ndarray
) -> None:
    norm = np.linalg.norm(error, axis=1)
    print(
        f"{robot.name}: {n_points} grid points x {repeats} repeats = {n_points * repeats} rows; "
        "error e = P - M (mm) without noise:"
    )
    for k, axis in enumerate("XYZ"):
        print(
            f"  e{axis.lower()}: min {error[:, k].min():8.3f}  max {error[:, k].max():8.3f}  "
            f"mean {error[:, k].mean():8.3f}"
        )
    print(f"  |e|: mean {norm.mean():.3f}  max {norm.max():.3f}")
    noise = np.linalg.norm(measured_error - np.repeat(error, repeats, axis=0), axis=1)
    print(f"  noise in the measured rows: rms {np.sqrt(np.mean(noise**2)):.4f} mm")


def fig3_field(
    robot: Robot, samples: int = 51, status: int | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The seed Fig. 3 plane: X (s,), Y (s,) mm and the error e = P - M (s, s, 3) mm, in one
    KUKA Status (default: the IK default's at the plane's first point, X 1000 Y -500)."""
    xs = np.linspace(*FIG3_X, samples)
    ys = np.linspace(*FIG3_Y, samples)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    points = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, FIG3_Z)])
    error = points - reached_positions(robot, points, FIG3_ABC, status)
    return xs, ys, error.reshape(samples, samples, 3)


def _is_file(name: str) -> bool:
    from pathlib import Path

    return Path(name).is_file()
