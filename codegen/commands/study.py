"""The statistical grid-step study of the seed (Sec. 4.2-4.4, Sec. 5): choose the largest grid
step whose compensated error meets the tolerance, then validate it (Tables 4-5, Fig. 12).

For every step, each centre's cube is modelled from its 8 vertices (IDW, seed Eq. 12-13), its 9
test points (GB/T 12642 / ISO 9283 positions plus the seed's P6-P9) are corrected (Eq. 14), and
the remaining error r = target - reached is summarised over all centres per axis: max, min and
standard deviation (Table 4; max/min are the mean over repeat rounds of each round's max/min,
the seed's rule). Cubic curves of max and min against the step give each axis's threshold step
(where a curve leaves +-tolerance, Fig. 12). The chosen step is the largest tested step within
every threshold whose measured max/min lie in the band and whose standard deviation is
"relatively small": std <= --std-fraction x tolerance on every axis. Table 5: a grid at that step
over the whole --region, errors before/after correction at --validation-points random points.

Inputs: --simulate ROBOT (a built-in or YAML robot with parameter errors; tracker and
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
import time
from pathlib import Path

import numpy as np

from accugrid.codegen.atomic import check_targets, write_files
from accugrid.codegen.cli_options import (
    add_abc,
    add_experiment_arguments,
    add_status,
    add_tool,
    parse_centres,
    parse_steps,
    robot_with_tool,
)
from accugrid.codegen.plots import fig12_png, hist_png
from accugrid.codegen.progress import progress
from accugrid.codegen.study_report import csv_text, md_table, table4, table5, text_table
from accugrid.compensation.plans import SEED_REGION
from accugrid.compensation.study import (
    DEFAULT_STD_FRACTION,
    DEFAULT_TOLERANCE_MM,
    REPEAT_RULES,
    analyse,
    check_reach,
    measured_residuals,
    measured_validation,
    read_experiment,
    simulate_study,
    simulate_validation,
    simulated_measure,
)
from accugrid.kinematics.errors import InputError

__all__ = ["NAME", "OUTPUTS", "add_arguments", "run"]

NAME = "study"

OUTPUTS = ("table4.csv", "table5.csv", "fig12.png", "table5_hist.png", "report.md")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument(
        "--simulate",
        metavar="ROBOT",
        help="simulate ROBOT (built-in name or YAML), e.g. kr210-paper",
    )
    source.add_argument(
        "--measured", metavar="FILE", help="filled-in `accugrid plan experiment` CSV"
    )
    add_experiment_arguments(parser)
    add_abc(parser, "simulated TCP orientation")
    add_tool(parser, "simulated tool, flange_T_tool in mm and deg (default: the flange)")
    parser.add_argument(
        "--noise-tracker",
        type=float,
        default=0.02,
        metavar="MM",
        help="simulated tracker noise, Gaussian sigma per axis, mm (default: 0.02)",
    )
    parser.add_argument(
        "--noise-repeat",
        type=float,
        default=0.03,
        metavar="MM",
        help="simulated robot repeatability, Gaussian sigma per axis, mm (default: 0.03)",
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    add_status(
        parser,
        "KUKA Status (0..7) the simulated robot keeps for every point, as a program of LIN "
        "moves does (default: the IK default configuration at the first centre)",
    )
    r = SEED_REGION
    parser.add_argument(
        "--region",
        nargs=6,
        type=float,
        metavar=("XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"),
        default=[r[0][0], r[1][0], r[0][1], r[1][1], r[0][2], r[1][2]],
        help="validation region in the robot frame, mm (default: the seed's 1000 x 1200 x 1000 "
        "mm region placed at X 1200..2200, Y -600..600, Z 1100..2100)",
    )
    parser.add_argument(
        "--tolerance",
        type=float,
        default=DEFAULT_TOLERANCE_MM,
        metavar="MM",
        help=f"accuracy requirement +-MM per axis (default: {DEFAULT_TOLERANCE_MM})",
    )
    parser.add_argument(
        "--std-fraction",
        type=float,
        default=DEFAULT_STD_FRACTION,
        metavar="F",
        help="'relatively small' standard deviation: std <= F x tolerance on every axis "
        f"(default: {DEFAULT_STD_FRACTION})",
    )
    parser.add_argument(
        "--repeat-rule",
        choices=REPEAT_RULES,
        default=REPEAT_RULES[0],
        help="how repeats enter max/min: the seed's mean of per-round extremes (default) or "
        "extremes of per-point means",
    )
    parser.add_argument(
        "--validation-points",
        type=int,
        default=200,
        metavar="N",
        help="random points for Table 5 in simulation (default: 200)",
    )
    parser.add_argument(
        "--validation-step",
        type=float,
        metavar="MM",
        help="in simulation, validate a grid at this step instead of the chosen one "
        "(e.g. 200 to compare with the seed's Table 5)",
    )
    parser.add_argument(
        "--validate",
        nargs=2,
        metavar=("GRID", "POINTS"),
        help="with --measured: grid measurement CSV at the chosen step and measured random points",
    )
    parser.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")


def _region(args) -> tuple[np.ndarray, np.ndarray]:
    r = args.region
    return np.array([r[0], r[2], r[4]]), np.array([r[1], r[3], r[5]])


def run(args: argparse.Namespace) -> int:
    out = Path(args.output)
    targets = [out / name for name in OUTPUTS]
    inputs = [p for p in [args.measured, *(args.validate or [])] if p]
    check_targets(targets, inputs=inputs, force=args.force)
    if args.validate and not args.measured:
        raise InputError("--validate goes with --measured (simulation validates by itself)")
    lo, hi = _region(args)
    started = time.perf_counter()
    settings: list[str] = []
    if args.simulate:
        robot = robot_with_tool(args.simulate, args.tool)
        abc = np.array(args.abc, dtype=float)
        centres = parse_centres(args.centre)
        names, xyz = list(centres), np.array(list(centres.values()), dtype=float)
        steps = parse_steps(args.steps)
        status = check_reach(robot, names, xyz, steps, abc, args.status)
        measure = simulated_measure(
            robot, abc, status, args.seed, args.noise_tracker, args.noise_repeat
        )
        cubes, residuals = simulate_study(measure, names, xyz, steps, args.repeats, progress)
        settings += [
            f"simulated robot {robot.name}, A B C {' '.join(f'{v:g}' for v in abc)} deg, "
            f"KUKA Status {status} throughout",
            f"noise: tracker {args.noise_tracker:g} mm, repeatability {args.noise_repeat:g} mm "
            f"(sigma per axis), seed {args.seed}",
        ]
    else:
        cubes = read_experiment(args.measured)
        residuals = measured_residuals(cubes, progress)
        settings.append(f"measured plan {Path(args.measured).name} (test points uncorrected)")
    result = analyse(cubes, residuals, args.tolerance, args.std_fraction, args.repeat_rule)
    settings += [
        "centres "
        + ", ".join(
            f"{n} ({', '.join(f'{v:g}' for v in c)})"
            for n, c in zip(cubes.names, cubes.centres, strict=True)
        ),
        f"steps {', '.join(f'{s:g}' for s in cubes.steps)} mm, {cubes.repeats} repeats, "
        f"tolerance +-{args.tolerance:g} mm, std fraction {args.std_fraction:g}, "
        f"repeat rule {args.repeat_rule}",
    ]
    validation = None
    step = result.decision.step
    if args.validation_step is not None:
        if not args.simulate:
            raise InputError("--validation-step goes with --simulate")
        if not args.validation_step > 0:
            raise InputError(f"--validation-step must be > 0 mm, got {args.validation_step:g}")
        step = args.validation_step
    if step is not None and args.simulate:
        validation = simulate_validation(
            measure, lo, hi, step, args.repeats, args.validation_points, seed=args.seed
        )
    elif step is not None and args.validate:
        validation = measured_validation(*args.validate)
    elapsed = time.perf_counter() - started

    h4, r4 = table4(result)
    print("Table 4: remaining error after compensation per cube step (mm)")
    print(text_table(h4, r4))
    print()
    for reason in result.decision.reasons:
        print(reason)
    files: dict[Path, str | bytes] = {out / "table4.csv": csv_text(h4, r4)}
    files[out / "fig12.png"] = fig12_png(result)
    report = [
        "# Grid-step study (accugrid study)",
        "",
        *[f"- {s}" for s in settings],
        f"- validation region X {lo[0]:g}..{hi[0]:g}, Y {lo[1]:g}..{hi[1]:g}, "
        f"Z {lo[2]:g}..{hi[2]:g} mm",
        f"- study time {elapsed:.2f} s",
        "",
        "## Table 4: remaining error after compensation (mm)",
        "",
        md_table(h4, r4),
        "",
        "## Decision (seed Sec. 4.4)",
        "",
        *[f"- {r}" for r in result.decision.reasons],
        "",
        "![Fig. 12: error-step curves](fig12.png)",
        "",
        "## Table 5: validation at the chosen step (mm)",
        "",
    ]
    if validation is not None:
        before, after = validation.table(args.repeat_rule)
        h5, r5 = table5(before, after)
        steps_used = " x ".join(f"{s:.3f}" for s in validation.model.step)
        print()
        chosen = "" if step == result.decision.step else " (--validation-step, not the chosen)"
        print(
            f"Table 5: {len(validation.points)} random points, grid step {steps_used} mm{chosen} "
            f"({int(np.prod(validation.model.counts))} vertices)"
        )
        print(text_table(h5, r5))
        files[out / "table5.csv"] = csv_text(h5, r5)
        files[out / "table5_hist.png"] = hist_png(validation)
        report += [
            f"{len(validation.points)} random points; grid step {steps_used} mm{chosen}, "
            f"{int(np.prod(validation.model.counts))} vertices.",
            "",
            md_table(h5, r5),
            "",
            "![Table 5 histograms](table5_hist.png)",
        ]
    else:
        why = "no step chosen" if step is None else "no --validate files given"
        print(f"\nTable 5: not computed ({why})")
        files[out / "table5.csv"] = "calibration\n"
        report.append(f"Not computed ({why}).")
        files.pop(out / "table5_hist.png", None)
    files[out / "report.md"] = "\n".join(report) + "\n"
    written = write_files(files, inputs=inputs, force=args.force)
    print(f"\nstudy time {elapsed:.2f} s; wrote {', '.join(str(p) for p in written)}")
    return 0
