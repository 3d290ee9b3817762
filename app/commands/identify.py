"""Identify a calibrated robot model from laser-tracker measurements at scattered poses.

MEAS is a measurement CSV (docs/formats.md): commanded x,y,z (robot frame, mm) and a,b,c (KUKA
deg), measured x_meas,y_meas,z_meas (mm), optionally the joint angles the controller logged (a1..a6,
KUKA deg; checked to reproduce the commanded position under the nominal model within the
round-off of their printed decimals) and the Status s. Without logged joints each pose's joints
are the nominal IK in its Status: column s, else --status, else the IK default per pose.

Identified (position-only residuals, robust Gauss-Newton, kinematics.identification): the 24 DH
errors of seed Eq. 2 (Δa, Δd mm; Δα, Δθ rad), the TCP offset in the flange (mm), with
--base-frame the tracker-to-robot frame (then x_meas.. may be in tracker coordinates), and the
joint errors the measurements show (--structure auto, the default; kinematics.structure): reducer
harmonics s*sin(k*A)+c*cos(k*A) per axis and order k <= --max-order, and the gravity compliance
of every axis gravity loads, without masses (compliance x first moments of the links),
chosen from the data: every candidate group weighed at once by sparse Bayesian learning (each
group's prior by maximum evidence; --structure search: forward selection on the held-out error
instead), with the
cross-validation curve and an accuracy estimate by nested cross-validation over the distinct
poses. --harmonics pins
orders known from the reducers' data sheets and --compliance the compliance of A2 and A3 under the
robot YAML's gravity model (joint_errors.masses): always kept. --structure dh fits the DH errors
and TCP (and the pinned terms) only. Directions the data cannot see (SVD of the column-scaled
Jacobian) are held at zero and listed.

Output: a robot YAML (-o) loadable wherever a robot is accepted: the nominal model, the identified
errors and TCP, and an `identification:` summary (parameters with standard deviations, condition
number, observability O1, residuals, cross-validation, outlier rows); --urdf also writes the
calibrated model as URDF (metres, rad). Lengths in mm, angles in degrees unless named rad.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from accugrid.app.cli_options import (
    add_harmonics,
    add_robot,
    add_status,
    add_table_format,
    add_tool,
    harmonics_of,
    robot_with_tool,
)
from accugrid.app.jobs.identify import MAX_ROWS, IdentifyOptions, calibrate
from accugrid.infra.atomic import check_targets, write_files
from accugrid.infra.errors import InputError
from accugrid.kinematics.robot import Robot

__all__ = ["NAME", "add_arguments", "run"]

NAME = "identify"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "measurements",
        metavar="MEAS.csv",
        help=f"measurement CSV (mm, deg), at most {MAX_ROWS} rows",
    )
    add_robot(parser, "nominal model of the measured arm", required=True)
    add_tool(
        parser,
        "tool the measurements were taken with (the controller's TOOL_DATA; the SMR position)",
    )
    add_status(
        parser,
        "KUKA Status 0..7 of every pose without logged joints or column s "
        "(default: the IK default per pose)",
    )
    parser.add_argument(
        "--structure",
        default="auto",
        metavar="WORD",
        help="auto (default): choose the joint-error terms (reducer harmonics, gravity "
        "compliance) by sparse Bayesian learning, checked by cross-validation; search: by "
        "forward selection on the cross-validated error; dh: DH errors and TCP (and pinned "
        "terms) only",
    )
    parser.add_argument(
        "--max-order",
        type=int,
        default=None,
        metavar="K",
        help="highest reducer harmonic order auto searches (default: 16, clamped to what the "
        "poses resolve; a larger one is refused naming the limit)",
    )
    parser.add_argument(
        "--folds",
        type=int,
        default=5,
        metavar="K",
        help="k-fold cross-validation over the distinct poses (default: 5; 0: none, only with "
        "--structure dh)",
    )
    parser.add_argument(
        "--base-frame",
        action="store_true",
        help="also identify the tracker-to-robot frame (measured positions in tracker coordinates)",
    )
    parser.add_argument(
        "--compliance",
        action="store_true",
        help="always identify the compliance of A2 and A3 (rad/N.m) under the robot's gravity "
        "model (joint_errors.masses in its YAML, e.g. kr210-realistic)",
    )
    add_harmonics(
        parser,
        "always identify reducer transmission errors s*sin(k*A)+c*cos(k*A) of these orders",
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
        structure=args.structure,
        max_order=args.max_order,
    )
    calibration = calibrate(args.measurements, robot, options, args.output, args.urdf)
    if args.report_html:
        from accugrid.app.reports.identify import identify_report

        roles = [("measurements", args.measurements), ("nominal robot", args.robot)]
        calibration.files[args.report_html] = identify_report(
            calibration.files[args.output],
            calibration.result.residuals,
            roles,
            controller=calibration.controller,
        )
    write_files(calibration.files, inputs, args.force, main=[args.output])  # the YAML last
    print(calibration.report)
    return 0
