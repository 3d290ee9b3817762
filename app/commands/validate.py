"""Check a calibrated model on points measured after correction (the last step of a calibration).

MEAS is a measurement CSV taken after correction at new points (not the identification poses):
x,y,z the targets, the nominal robot-frame positions the corrected program aimed at (the points
CSV given to correct/krl/gcode/rewrite, not the corrected commands x_cmd..), and x_meas,y_meas,
z_meas the TCP positions the laser tracker measured there (robot frame, mm); optional id, a,b,c,
s. Rows with the same target are repeats of one pose. `accugrid simulate --poses CORRECTED.csv`
writes such a file for a simulated robot.

Printed: the deviation d = measured - target per axis (min, max, max |d|, mean, std) and of the
3D distance, ISO 9283 positional accuracy AP (barycentre of a pose's measured positions minus its
target) and repeatability RP (mean + 3 std of the distances from that barycentre; poses measured
at least twice), the mean deviation and what it suggests, the worst rows by file:line, and the
verdict: PASS when every row lies within +-TOL on X, Y and Z and the mean deviation is no longer
than 10 x the model's validated error or 2 mm, whichever is longer (a longer one is a file
measured in another base frame or with another tool than the model's: the report says whether a
constant offset, in the tool frame when the file has a,b,c, or a rotation of the base frame
explains it). The HTML report lists every row beyond the tolerance; --report writes every row
with its deviation and whether it is beyond.

Exit status: 0 PASS; 3 FAIL (the reports are written all the same: a failed validation is a
result to sign, not an error); 2 bad input.
"""

from __future__ import annotations

import argparse
import os

from accugrid.app.cli_options import COORDINATE_MAX, add_table_format, number
from accugrid.app.jobs.validate import ValidateRequest, validate_files
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM
from accugrid.infra.atomic import check_targets, write_files
from accugrid.infra.errors import InputError

__all__ = ["EXIT_FAIL", "NAME", "add_arguments", "run"]

NAME = "validate"
EXIT_FAIL = 3  # the validation ran and failed (0: passed, 2: bad input, 1: internal error)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "measurements",
        metavar="MEAS",
        help="measurement CSV after correction: x,y,z targets, x_meas,y_meas,z_meas measured (mm)",
    )
    parser.add_argument(
        "--model",
        required=True,
        metavar="CAL",
        help="the calibrated robot YAML the correction used (accugrid identify)",
    )
    parser.add_argument(
        "--grid",
        metavar="G",
        help="the residual grid the correction used: read as a grid, named with its SHA-256, "
        "the poses outside its box counted",
    )
    parser.add_argument(
        "--tolerance",
        type=number("mm", 0, COORDINATE_MAX, above=True),
        default=DEFAULT_TOLERANCE_MM,
        metavar="MM",
        help=f"pass when every row is within +-MM on X, Y and Z, mm "
        f"(default: {DEFAULT_TOLERANCE_MM:g})",
    )
    parser.add_argument(
        "--report",
        metavar="REPORT.csv",
        help="write the per-row report: line, id, pose, target, measured, deviation (mm) and "
        "whether the row is beyond the tolerance",
    )
    parser.add_argument(
        "--report-html",
        metavar="FILE",
        help="also write the self-contained HTML report (inputs with SHA-256, verdict, every row "
        "beyond the tolerance, figures)",
    )
    add_table_format(parser)
    parser.add_argument("--force", action="store_true", help="overwrite existing reports")


def run(args: argparse.Namespace) -> int:
    inputs = [args.measurements, args.model, args.grid]
    reports = [r for r in (args.report, args.report_html) if r]
    if len(set(map(os.path.abspath, reports))) != len(reports):
        raise InputError("--report and --report-html name the same file", args.report_html)
    if reports:
        check_targets(reports, inputs, args.force)
    request = ValidateRequest(
        measurements=args.measurements,
        model=args.model,
        grid=args.grid,
        tolerance_mm=args.tolerance,
        report_html=args.report_html,
        report_csv=args.report,
    )
    done = validate_files(request)
    if done.job.files:
        write_files(done.job.files, done.job.inputs, args.force)
    for line in done.job.lines:
        print(line)
    return 0 if done.passed else EXIT_FAIL
