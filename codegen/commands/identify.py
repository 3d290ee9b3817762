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
gravity model, joint_errors.masses).
Directions the data cannot see (SVD of the column-scaled Jacobian) are held at zero and listed.

Output: a robot YAML (-o) loadable wherever a robot is accepted: the nominal model, the identified
errors and TCP, and an `identification:` summary (parameters with standard deviations, condition
number, observability O1, residuals, cross-validation, outlier rows); --urdf also writes the
calibrated model as URDF (metres, rad). Lengths in mm, angles in degrees unless named rad.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from accugrid import __version__
from accugrid.codegen.atomic import check_targets, write_files
from accugrid.codegen.cli_options import add_status, add_tool, robot_with_tool
from accugrid.compensation.measurements import read_measurements
from accugrid.kinematics.calibrated import calibrated_yaml, identification_summary
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.frames import xyzabc_from_pose
from accugrid.kinematics.identification import Identification, identify, pose_set
from accugrid.kinematics.robot import Robot

__all__ = ["NAME", "add_arguments", "run"]

NAME = "identify"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("measurements", metavar="MEAS.csv", help="measurement CSV (mm, deg)")
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
    parser.add_argument("-o", "--output", required=True, metavar="CAL.yaml", help="robot YAML")
    parser.add_argument("--urdf", metavar="FILE.urdf", help="also write the model as URDF")
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")


def run(args: argparse.Namespace) -> int:
    targets = [args.output] + ([args.urdf] if args.urdf else [])
    if args.urdf and Path(args.urdf).resolve() == Path(args.output).resolve():
        raise InputError("--urdf and -o name the same file", args.urdf)
    inputs = [args.measurements] + ([args.robot] if Path(args.robot).is_file() else [])
    check_targets(targets, inputs, args.force)
    if args.folds < 0 or args.folds == 1:
        raise InputError(f"--folds must be 0 (none) or at least 2, got {args.folds}")
    robot = robot_with_tool(args.robot, args.tool)
    if not isinstance(robot, Robot):
        raise InputError(f"robot {robot.name}: identification needs a DH robot, not a URDF")
    meas = read_measurements(args.measurements)
    status = meas.status if meas.status is not None else args.status
    data = pose_set(
        robot,
        meas.commanded,
        meas.measured,
        abc_deg=meas.abc,
        joints_deg=meas.joints,
        status=status,
        joint_decimals=meas.joint_decimals,
        position_decimals=meas.position_decimals,
        labels=[meas.where(r) for r in range(len(meas.commanded))],
        path=meas.path,
    )
    result = identify(
        robot, data, base_frame=args.base_frame, compliance=args.compliance, folds=args.folds
    )
    source = Path(args.measurements).name
    summary = identification_summary(result, robot, source, meas.sha256)
    header = f"accugrid {__version__} identify: {robot.name} calibrated from {source}"
    outputs: dict[str, str] = {args.output: calibrated_yaml(result.robot, summary, header)}
    if args.urdf:
        from accugrid.kinematics.urdf_export import urdf_text

        outputs[args.urdf] = urdf_text(result.robot)
    write_files(outputs, inputs, args.force)
    print(_summary(args.output, robot, result))
    if args.urdf:
        extra = " (geometric part only: URDF has no joint compliance)" if args.compliance else ""
        print(f"wrote {args.urdf}{extra}")
    return 0


def _per_axis(label: str, rms: np.ndarray, peak: np.ndarray) -> str:
    cells = "  ".join(
        f"{axis} rms {r:.4f} max {m:.4f}" for axis, r, m in zip("XYZ", rms, peak, strict=True)
    )
    return f"  {label}: {cells}"


def _summary(path: str, robot: Robot, result: Identification) -> str:
    lines = [
        f"{path}: {robot.name} calibrated from {result.poses} poses ({result.rows} rows); "
        f"{result.rank} of {len(result.x)} parameters identifiable, condition number "
        f"{result.condition_number:.1f}, observability O1 {result.o1:.4f}"
    ]
    if result.unidentifiable_text:
        lines.append("  unidentifiable (held at 0): " + "; ".join(result.unidentifiable_text))
    lines.append(_per_axis("residual (measured - model), mm", result.rms_mm, result.max_mm))
    if result.cross_validation is not None:
        cv = result.cross_validation
        lines.append(
            _per_axis(f"{cv.folds}-fold cross-validation, held-out poses, mm", cv.rms_mm, cv.max_mm)
        )
    if result.outliers:
        shown = ", ".join(result.outliers[:10]) + (" ..." if len(result.outliers) > 10 else "")
        lines.append(
            f"  {len(result.outliers)} outlier rows (beyond 3 x {result.sigma_mm:.4f} mm): {shown}"
        )
    if result.tracker_T_robot is not None:
        x, y, z, a, b, c = xyzabc_from_pose(result.tracker_T_robot)
        lines.append(
            f"  tracker_T_robot x {x:.3f} y {y:.3f} z {z:.3f} mm, a {a:.4f} b {b:.4f} c {c:.4f} deg"
        )
    lines.append("  identified parameters (value +- std):")
    cells = [
        f"{name} {value:+.4g} +- {std:.2g} {unit}"
        for name, value, std, unit, ok in zip(
            result.names, result.x, result.std, result.units, result.identifiable, strict=True
        )
        if ok
    ]
    lines += ["    " + " | ".join(cells[i : i + 4]) for i in range(0, len(cells), 4)]
    tied = [n for n, ok in zip(result.names, result.identifiable, strict=True) if not ok]
    if tied:
        lines.append(
            "  determined only in the combinations above (minimum-norm values in the file): "
            + ", ".join(tied)
        )
    return "\n".join(lines)
