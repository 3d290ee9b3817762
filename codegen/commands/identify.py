"""Identify a calibrated robot model from laser-tracker measurements at scattered poses.

MEAS is a measurement CSV (DESIGN.md): commanded x,y,z (robot frame, mm) and a,b,c (KUKA deg),
measured x_meas,y_meas,z_meas (mm), optionally the joint angles the controller logged (a1..a6,
KUKA deg; checked to reproduce the commanded position under the nominal model within the
round-off of their printed decimals) and the Status s. Without logged joints each pose's joints
are the nominal IK in its Status: column s, else --status, else the IK default per pose.

Identified (position-only residuals, robust Gauss-Newton, kinematics.identification): the 24 DH
errors of seed Eq. 2 (Δa, Δd mm; Δα, Δθ rad), the TCP offset in the flange (mm), with
--base-frame the tracker-to-robot frame (then x_meas.. may be in tracker coordinates) and with
--compliance the compliance of A2 and A3 under gravity (rad/N.m; the robot YAML must carry the
gravity model, joint_errors.masses) and with --harmonics the sine and cosine coefficients (rad) of
reducer transmission errors of the given orders per axis (orders from the reducers' data sheets).
Directions the data cannot see (SVD of the column-scaled Jacobian) are held at zero and listed.

Output: a robot YAML (-o) loadable wherever a robot is accepted: the nominal model, the identified
errors and TCP, and an `identification:` summary (parameters with standard deviations, condition
number, observability O1, residuals, cross-validation, outlier rows); --urdf also writes the
calibrated model as URDF (metres, rad). Lengths in mm, angles in degrees unless named rad.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from accugrid.codegen.atomic import check_targets, write_files
from accugrid.codegen.calibration import MAX_ROWS, IdentifyOptions, calibrate
from accugrid.codegen.cli_options import (
    add_harmonics,
    add_status,
    add_table_format,
    add_tool,
    harmonics_of,
    robot_with_tool,
)
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.robot import Robot

__all__ = ["NAME", "add_arguments", "run"]

NAME = "identify"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "measurements",
        metavar="MEAS.csv",
        help=f"measurement CSV (mm, deg), at most {MAX_ROWS} rows",
    )
    parser.add_argument(
        "--robot",
        required=True,
        help="nominal robot: built-in (kr210, kr210-paper) or robot YAML file",
    )
    add_tool(
        parser,
        "tool the measurements were taken with (flange_T_tool, the controller's "
        "TOOL_DATA; the SMR position), mm and deg (default: the flange)",
    )
    add_status(
        parser,
        "KUKA Status 0..7 of every pose without logged joints or column s "
        "(default: the IK default per pose)",
    )
    parser.add_argument(
        "--folds",
        type=int,
        default=5,
        metavar="K",
        help="k-fold cross-validation over the distinct poses (default: 5; 0: none)",
    )
    parser.add_argument(
        "--base-frame",
        action="store_true",
        help="also identify the tracker-to-robot frame (measured positions in tracker coordinates)",
    )
    parser.add_argument(
        "--compliance",
        action="store_true",
        help="also identify the compliance of A2 and A3 (rad/N.m) under gravity; needs the "
        "robot's gravity model (joint_errors.masses in its YAML, e.g. kr210-realistic)",
    )
    add_harmonics(
        parser,
        "also identify reducer transmission errors s*sin(k*A)+c*cos(k*A) of these orders",
    )
    parser.add_argument("-o", "--output", required=True, metavar="CAL.yaml", help="robot YAML")
    parser.add_argument("--urdf", metavar="FILE.urdf", help="also write the model as URDF")
    parser.add_argument(
        "--report-html",
        metavar="FILE",
        help="also write the self-contained HTML report (inputs with SHA-256, residuals, "
        "cross-validation against +-0.3 mm, parameters, unidentifiable directions)",
    )
    add_table_format(parser)
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")


def run(args: argparse.Namespace) -> int:
    targets = [args.output] + [t for t in (args.urdf, args.report_html) if t]
    if args.urdf and Path(args.urdf).resolve() == Path(args.output).resolve():
        raise InputError("--urdf and -o name the same file", args.urdf)
    inputs = [args.measurements] + ([args.robot] if Path(args.robot).is_file() else [])
    check_targets(targets, inputs, args.force)
    robot = robot_with_tool(args.robot, args.tool)
    if not isinstance(robot, Robot):
        raise InputError(f"robot {robot.name}: identification needs a DH robot, not a URDF")
    options = IdentifyOptions(
        status=args.status,
        base_frame=args.base_frame,
        compliance=args.compliance,
        harmonics=harmonics_of(args),
        folds=args.folds,
    )
    calibration = calibrate(args.measurements, robot, options, args.output, args.urdf)
    if args.report_html:
        from accugrid.codegen.identify_report import identify_report

        roles = [("measurements", args.measurements), ("nominal robot", args.robot)]
        calibration.files[args.report_html] = identify_report(
            calibration.files[args.output], calibration.result.residuals, roles
        )
    write_files(calibration.files, inputs, args.force, main=[args.output])  # the YAML last
    print(calibration.report)
    return 0
