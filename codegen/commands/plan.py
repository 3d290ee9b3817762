"""Write a measurement plan: the positions a laser-tracker operator measures, in order.

  grid        vertices of a regular grid over a region, serpentine (boustrophedon) order: every
              move goes to a neighbouring vertex, so the path is as short as a grid allows; the
              path length is printed next to the naive raster order's.
  cube        one cube's vertices C1..C8 and test points P1..P9 (GB/T 12642-2001 / ISO 9283:1998
              test points plus the seed's P6..P9, seed Sec. 4.3), --repeats times.
  experiment  the seed's step experiment (Sec. 4.2, 5): for every centre and step, the cube's 8
              vertices and 9 test points, --repeats rounds each (default: seed Table 3 centres
              D-H, steps 20..500 mm every 60, 5 repeats, A B C = 0 90 0).
  identify    --count poses for `accugrid identify`: from --candidates random positions in
              --region at orientations within --tilt deg of --abc, reachable in the Status with
              |A5| >= 10 deg, the D-optimal set (greedy, most observable DH errors and TCP),
              visited in nearest-neighbour order; a,b,c per row and column s (the Status).

Outputs in DIR: NAME.csv (id,x,y,z,a,b,c[,centre,step,label,repeat],x_meas,y_meas,z_meas with
the measured columns empty for the operator) and the KUKA KRL program NAME.src/NAME.dat that
visits every row with LIN at the fixed orientation (first motion a complete PTP) and waits at
each for the tracker: WAIT SEC (--wait-sec) or WAIT FOR $IN[n] (--wait-input). Positions are in
the robot frame ($BASE = $NULLFRAME, i.e. $ROBROOT = $WORLD) unless --base-number names a
BASE_DATA that equals the robot frame. Every position is checked with the robot's IK (--robot,
--tool) in one KUKA Status for the whole plan (--status; default: the IK default at the first
position), since LIN moves keep the first PTP's configuration; the IK also gives each E6POS its T.
Lengths in mm, angles in deg, speeds in m/s.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from accugrid.codegen.atomic import check_targets, write_files
from accugrid.codegen.cli_options import add_abc, add_status, add_tool, robot_with_tool
from accugrid.codegen.header import header_lines
from accugrid.codegen.krl.emit import MeasureSettings, render_measurement
from accugrid.codegen.textsafe import fixed, krl_identifier
from accugrid.compensation.plans import (
    SEED_CENTRES,
    SEED_REGION,
    SEED_REPEATS,
    Plan,
    cube_plan,
    experiment_plan,
    grid_plan,
    identification_plan,
)
from accugrid.kinematics.configuration import solve_in_one_status
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.frames import pose_from_xyzabc

__all__ = [
    "MAX_WAIT_SEC",
    "NAME",
    "add_arguments",
    "add_experiment_arguments",
    "build_plan",
    "parse_centres",
    "parse_steps",
    "reach",
    "render_krl",
    "run",
]

NAME = "plan"

MAX_WAIT_SEC = 600.0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="kind", metavar="KIND", required=True)
    grid = sub.add_parser("grid", help="grid vertices over a region, serpentine order")
    _add_region(grid)
    grid.add_argument(
        "--step",
        type=float,
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
    grid.add_argument("--repeats", type=int, default=1, help="rounds over the grid (default: 1)")
    cube = sub.add_parser("cube", help="one cube's vertices C1..C8 and test points P1..P9")
    cube.add_argument(
        "--centre", nargs=3, type=float, required=True, metavar=("X", "Y", "Z"), help="mm"
    )
    cube.add_argument("--step", type=float, required=True, metavar="MM", help="cube edge, mm")
    cube.add_argument(
        "--repeats", type=int, default=SEED_REPEATS, help=f"rounds (default: {SEED_REPEATS})"
    )
    exp = sub.add_parser("experiment", help="the seed's step experiment (Sec. 4.2, 5)")
    add_experiment_arguments(exp)
    ident = sub.add_parser("identify", help="D-optimal poses for a kinematic identification")
    _add_region(ident)
    ident.add_argument(
        "--count", type=int, required=True, metavar="N", help="number of poses to measure"
    )
    ident.add_argument(
        "--tilt",
        type=float,
        default=30.0,
        metavar="DEG",
        help="largest rotation from --abc, deg (default: 30)",
    )
    ident.add_argument(
        "--candidates",
        type=int,
        default=2000,
        help="random candidate poses to choose from (default: 2000)",
    )
    ident.add_argument("--repeats", type=int, default=1, help="rounds over the poses (default: 1)")
    ident.add_argument("--seed", type=int, default=0, help="seed of the candidates (default: 0)")
    for p in (grid, cube, exp, ident):
        _common(p)


def _add_region(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--region",
        nargs=6,
        type=float,
        metavar=("XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"),
        default=[SEED_REGION[0][0], SEED_REGION[1][0], SEED_REGION[0][1], SEED_REGION[1][1]]
        + [SEED_REGION[0][2], SEED_REGION[1][2]],
        help="box in the robot frame, mm (default: the seed's 1000 x 1200 x 1000 mm region "
        "placed at X 1200..2200, Y -600..600, Z 1100..2100)",
    )


def add_experiment_arguments(parser: argparse.ArgumentParser) -> None:
    """--centre/--steps/--repeats as shared by `plan experiment` and `study`."""
    parser.add_argument(
        "--centre",
        nargs=4,
        action="append",
        metavar=("NAME", "X", "Y", "Z"),
        help="a cube centre, mm; repeat for more (default: seed Table 3, D 1700 0 1500, "
        "E 2000 -350 1800, F 1400 350 1900, G 1400 -350 1400, H 2000 350 1400)",
    )
    parser.add_argument(
        "--steps",
        default="20:500:60",
        help="cube steps in mm: FIRST:LAST:INCREMENT or a comma list (default: 20:500:60)",
    )
    parser.add_argument(
        "--repeats",
        type=int,
        default=SEED_REPEATS,
        help=f"measurements of every point (default: {SEED_REPEATS})",
    )


def _common(parser: argparse.ArgumentParser) -> None:
    add_abc(parser, "fixed TCP orientation")
    parser.add_argument(
        "--robot",
        default="kr210",
        help="robot for the reach check and S/T: built-in name or YAML (default: kr210)",
    )
    add_tool(
        parser,
        "measured point (SMR) on the flange, flange_T_tool in mm and deg "
        "(default: the flange centre)",
    )
    add_status(
        parser,
        "KUKA Status (0..7) for every position (default: the IK default configuration "
        "at the first position)",
    )
    parser.add_argument(
        "--tool-number", type=int, default=1, help="TOOL_DATA index in the program (default: 1)"
    )
    parser.add_argument(
        "--base-number",
        type=int,
        default=0,
        help="BASE_DATA index in the program; 0 = $NULLFRAME, the robot frame (default: 0)",
    )
    parser.add_argument(
        "--ptp-percent",
        type=int,
        default=20,
        metavar="P",
        help="speed of the first PTP, percent of maximum (default: 20)",
    )
    parser.add_argument(
        "--vel",
        type=float,
        default=0.25,
        metavar="M_S",
        help="LIN speed $VEL.CP, m/s (default: 0.25)",
    )
    wait = parser.add_mutually_exclusive_group()
    wait.add_argument(
        "--wait-sec",
        type=float,
        default=3.0,
        metavar="S",
        help="dwell at each position for the tracker, s (default: 3)",
    )
    wait.add_argument(
        "--wait-input",
        type=int,
        metavar="N",
        help="instead of a dwell, wait at each position until $IN[N] is TRUE",
    )
    parser.add_argument("--name", help="program and file name (default: measure_KIND)")
    parser.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")
    parser.add_argument(
        "--templates",
        type=Path,
        help="copy of the templates folder (or of its krl/) with measure.src.j2 and "
        "measure.dat.j2 (default: built-in)",
    )


def parse_steps(text: str) -> np.ndarray:
    """Steps in mm from "FIRST:LAST:INCREMENT" (inclusive) or "S1,S2,..."."""
    try:
        if ":" in text:
            first, last, inc = (float(v) for v in text.split(":"))
            if inc <= 0 or last < first:
                raise ValueError
            steps = np.arange(first, last + 1e-9 * max(1.0, abs(last)), inc)
        else:
            steps = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise InputError(
            f"--steps {text!r}: use FIRST:LAST:INCREMENT (increment > 0) or a comma list of mm"
        ) from None
    if not np.all(np.isfinite(steps)) or np.any(steps <= 0):
        raise InputError(f"--steps {text!r}: steps must be finite and > 0 mm")
    return steps


def parse_centres(items: list[list[str]] | None) -> dict[str, tuple[float, float, float]]:
    """--centre NAME X Y Z options (None: the seed's D-H)."""
    if not items:
        return dict(SEED_CENTRES)
    centres: dict[str, tuple[float, float, float]] = {}
    for name, *xyz in items:
        try:
            point = tuple(float(v) for v in xyz)
        except ValueError:
            raise InputError(f"--centre {name}: X Y Z must be numbers (mm), got {xyz}") from None
        if name in centres:
            raise InputError(f"--centre {name} given twice")
        centres[name] = point
    return centres


def build_plan(args: argparse.Namespace) -> tuple[Plan, list[str]]:
    """The plan of the chosen kind and lines describing it."""
    if args.kind == "grid":
        r = args.region
        lo, hi = (r[0], r[2], r[4]), (r[1], r[3], r[5])
        plan = grid_plan(lo, hi, args.step, args.abc)
        naive = grid_plan(lo, hi, args.step, args.abc, order="naive")
        if args.order == "naive":
            plan = naive
        if int(args.repeats) < 1:
            raise InputError(f"--repeats must be >= 1, got {args.repeats}")
        steps = np.unique(np.round(np.diff(np.unique(plan.points[:, 0])), 6))
        info = [
            f"grid plan: {len(plan.points)} vertices, {args.order} order",
            f"path {plan.path_length():.1f} mm (serpentine "
            f"{grid_plan(lo, hi, args.step, args.abc).path_length():.1f} mm, naive raster "
            f"{naive.path_length():.1f} mm)",
        ]
        if len(steps) and abs(steps[0] - args.step) > 1e-6:
            info.append(f"note: step shrunk to partition the region exactly, X {steps[0]:.3f} mm")
        if args.repeats > 1:
            plan = Plan(
                np.tile(plan.points, (args.repeats, 1)),
                plan.abc,
                [f"{i}_R{r + 1}" for r in range(args.repeats) for i in plan.ids],
            )
        return plan, info
    if args.kind == "identify":
        return _identification_plan(args)
    if args.kind == "cube":
        plan = cube_plan(args.centre, args.step, args.repeats, args.abc)
        return plan, [f"cube plan: 8 vertices + 9 test points x {args.repeats} repeats"]
    centres = parse_centres(args.centre)
    steps = parse_steps(args.steps)
    plan = experiment_plan(centres, steps, args.repeats, args.abc)
    info = [
        f"experiment plan: {len(centres)} centres x {len(steps)} steps x 17 points x "
        f"{args.repeats} repeats = {len(plan.points)} rows",
        f"steps {', '.join(f'{s:g}' for s in steps)} mm, path {plan.path_length():.1f} mm",
    ]
    return plan, info


def _identification_plan(args: argparse.Namespace) -> tuple[Plan, list[str]]:
    r = args.region
    lo, hi = (r[0], r[2], r[4]), (r[1], r[3], r[5])
    robot = robot_with_tool(args.robot, args.tool)
    centre = pose_from_xyzabc(np.concatenate([np.add(lo, hi) / 2, args.abc]))
    status = solve_in_one_status(robot, centre, args.status)[1]  # default: IK at the centre
    if status is None:
        raise InputError(
            f"the region's centre is not reachable at A B C {' '.join(map(fixed, args.abc))} "
            "deg: give --status"
        )
    plan, o1, usable = identification_plan(
        robot,
        lo,
        hi,
        args.count,
        args.tilt,
        args.abc,
        status,
        candidates=args.candidates,
        repeats=args.repeats,
        seed=args.seed,
    )
    info = [
        f"identification plan: {args.count} poses x {args.repeats} repeats chosen D-optimally "
        f"from {usable} of {args.candidates} candidates (Status {status}, tilt up to "
        f"{args.tilt:g} deg, |A5| >= 10 deg); observability O1 {o1:.4f}",
        f"path {plan.path_length():.1f} mm",
    ]
    return plan, info


def reach(plan: Plan, args: argparse.Namespace) -> tuple[np.ndarray, np.ndarray, str, int]:
    """KUKA S and T (N,) of every position in one Status (--status, or the IK default at the
    first position): LIN moves keep the configuration of the first PTP, so the whole plan must
    be reachable in it. InputError naming the first position that is not."""
    robot = robot_with_tool(args.robot, args.tool)
    poses = pose_from_xyzabc(np.column_stack([plan.points, plan.abc_rows()]))
    sol, status = solve_in_one_status(robot, poses, args.status)
    if not sol.ok.all():
        bad = np.flatnonzero(~sol.ok)
        i = int(bad[0])
        x, y, z = plan.points[i]
        raise InputError(
            f"{len(bad)} of {len(plan.points)} plan positions cannot be reached by {robot.name}"
            f"{'' if status is None else f' in Status {status}'}; first: {plan.ids[i]} "
            f"X {x:.3f} Y {y:.3f} Z {z:.3f} ({sol.reason[i]})"
        )
    return sol.status, sol.turn, robot.name, int(status)


def render_krl(
    plan: Plan,
    status: np.ndarray,
    turn: np.ndarray,
    name: str,
    header: list[str],
    args: argparse.Namespace,
) -> tuple[str, str]:
    """(.src, .dat) texts of the measurement program (``krl.emit.render_measurement``) after
    checking the program options."""
    if args.wait_input is not None and not 1 <= args.wait_input <= 4096:
        raise InputError(f"--wait-input must be an input number 1..4096, got {args.wait_input}")
    if not 0 <= args.wait_sec <= MAX_WAIT_SEC:
        raise InputError(f"--wait-sec must be 0..{MAX_WAIT_SEC:g} s, got {args.wait_sec:g}")
    if not 1 <= args.ptp_percent <= 100:
        raise InputError(f"--ptp-percent must be 1..100, got {args.ptp_percent}")
    if not 0 < args.vel <= 2.0:
        raise InputError(f"--vel must be in (0, 2] m/s, got {args.vel:g}")
    for option in ("tool_number", "base_number"):
        value = getattr(args, option)
        low = 1 if option == "tool_number" else 0
        if not low <= value <= 32:
            raise InputError(f"--{option.replace('_', '-')} must be {low}..32, got {value}")
    settings = MeasureSettings(
        tool=args.tool_number,
        base=args.base_number,
        ptp_percent=args.ptp_percent,
        vel_cp=args.vel,
        wait_sec=args.wait_sec,
        wait_input=args.wait_input,
        ptp_only=args.kind == "identify",  # reorienting between poses: PTP, not LIN
    )
    return render_measurement(
        plan.points,
        plan.abc_rows(),
        plan.ids,
        status,
        turn,
        name,
        header,
        settings,
        args.templates,
    )


def _orientation_text(plan: Plan) -> str:
    if np.ndim(plan.abc) == 1:
        return f"orientation A B C {' '.join(fixed(v) for v in plan.abc)} deg"
    return "orientation A B C per position (see the .dat)"


def run(args: argparse.Namespace) -> int:
    plan, info = build_plan(args)
    name = krl_identifier(args.name or f"measure_{args.kind}", prefix="M")
    out = Path(args.output)
    targets = {out / f"{name.lower()}.{ext}": None for ext in ("csv", "src", "dat")}
    check_targets(targets, force=args.force)
    status, turn, robot_name, config = reach(plan, args)
    if args.wait_input is not None:
        wait = f"WAIT FOR $IN[{args.wait_input}]"
    else:
        wait = f"WAIT SEC {fixed(args.wait_sec)}"
    details = [
        "inputs none, positions generated from the command-line settings",
        *info,
        _orientation_text(plan) + f", robot {robot_name}, Status {config}",
    ]
    moves = "each by PTP" if args.kind == "identify" else "first by PTP, then LIN"
    closing = [f"{len(plan.points)} positions, {moves}, each followed by {wait}"]
    header = header_lines(
        f"plan {args.kind}",
        details=details,
        where=", measurement positions are not corrected",
        closing=closing,
    )
    src, dat = render_krl(plan, status, turn, name, header, args)
    paths = list(targets)
    write_files({paths[0]: plan.csv_text(), paths[1]: src, paths[2]: dat}, force=args.force)
    for line in info:
        print(line)
    print(f"wrote {', '.join(str(p) for p in paths)}")
    return 0
