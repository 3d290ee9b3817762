"""Fit the robot base frame from laser-tracker points (seed Sec. 4.1).

Three CSV files with columns x,y,z (mm, tracker frame; other columns are ignored):
  --base-plane    SMR centres scanned over the robot's mounting surface (40 or more points
                  spread around the robot base)
  --a1-circle     SMR on the flange while only A1 turns (20 or more points over 90-180 deg of
                  A1; 30 deg is the minimum accepted)
  --flange-holes  SMR seated on the flange holes with the robot at mechanical zero
                  (A1..A6 = 0, -90, 90, 0, 0, 0), one point per hole (6 for ISO 9409-1-160)

The fitted plane through the SMR centres is moved by the SMR radius to the base plane; the A1
circle's normal is Z (pointing away from the mounting surface) and its axis meets the base plane
at the origin; the flange-hole circle's centre fixes X (toward the flange). The output YAML holds
tracker_T_robot (x, y, z mm; a, b, c KUKA ABC deg; 4x4 matrix) and each fit's residuals.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from accugrid.codegen.atomic import check_targets, write_files
from accugrid.codegen.frame_file import frame_yaml
from accugrid.compensation.csvtable import read_table
from accugrid.kinematics.base_frame import SMR_RADIUS_MM, RobotFrameFit, fit_robot_frame
from accugrid.kinematics.digest import sha256_hex
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.frames import xyzabc_from_pose

__all__ = ["NAME", "add_arguments", "run"]

NAME = "fit-frame"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--base-plane", required=True, metavar="F1.csv", help="mounting-surface points (x,y,z mm)"
    )
    parser.add_argument(
        "--a1-circle", required=True, metavar="F2.csv", help="flange points while A1 turns (mm)"
    )
    parser.add_argument(
        "--flange-holes",
        required=True,
        metavar="F3.csv",
        help="SMR on each flange hole at mechanical zero (mm)",
    )
    parser.add_argument(
        "--smr-radius",
        type=float,
        default=SMR_RADIUS_MM,
        metavar="MM",
        help=f"SMR ball radius in mm (default {SMR_RADIUS_MM}, a 1.5-inch SMR)",
    )
    parser.add_argument("-o", "--output", required=True, metavar="FRAME.yaml", help="output YAML")
    parser.add_argument(
        "--plot", metavar="FIG.png", help="also write a PNG of the fitted plane and circles"
    )
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")


def _points(path: str) -> tuple[np.ndarray, bytes]:
    """The x,y,z columns (N, 3) mm of a tracker CSV and the file's bytes (for its SHA-256)."""
    table = read_table(path)
    table.require(["x", "y", "z"])
    return table.floats(["x", "y", "z"]), Path(path).read_bytes()


def run(args: argparse.Namespace) -> int:
    inputs = {
        "base_plane": args.base_plane,
        "a1_circle": args.a1_circle,
        "flange_holes": args.flange_holes,
    }
    targets = [args.output] + ([args.plot] if args.plot else [])
    if args.plot and Path(args.plot).resolve() == Path(args.output).resolve():
        raise InputError("--plot and -o name the same file", args.plot)
    check_targets(targets, inputs.values(), args.force)
    if not (np.isfinite(args.smr_radius) and args.smr_radius >= 0.0):
        raise InputError(f"--smr-radius must be a number >= 0 mm, got {args.smr_radius}")

    loaded = {key: _points(path) for key, path in inputs.items()}
    fit = fit_robot_frame(
        loaded["base_plane"][0],
        loaded["a1_circle"][0],
        loaded["flange_holes"][0],
        smr_radius_mm=args.smr_radius,
        sources=(args.base_plane, args.a1_circle, args.flange_holes),
    )
    digests = {key: (Path(path).name, sha256_hex(loaded[key][1])) for key, path in inputs.items()}
    outputs: dict[str, bytes | str] = {args.output: frame_yaml(fit, digests)}
    if args.plot:
        from accugrid.codegen.plots import frame_fit_png

        points = {key: value[0] for key, value in loaded.items()}
        outputs[args.plot] = frame_fit_png(fit, points)
    write_files(outputs, inputs.values(), args.force)
    print(_summary(args.output, fit))
    return 0


def _summary(path: str, fit: RobotFrameFit) -> str:
    x, y, z, a, b, c = xyzabc_from_pose(fit.tracker_T_robot)
    return (
        f"{path}: tracker_T_robot x {x:.3f} y {y:.3f} z {z:.3f} mm, a {a:.4f} b {b:.4f} "
        f"c {c:.4f} deg; residual RMS/max mm: plane {fit.plane.rms_mm:.4f}/{fit.plane.max_mm:.4f}, "
        f"A1 circle {fit.a1_circle.rms_mm:.4f}/{fit.a1_circle.max_mm:.4f} "
        f"({fit.a1_circle.arc_deg:.1f} deg of arc), "
        f"flange holes {fit.flange_holes.rms_mm:.4f}/{fit.flange_holes.max_mm:.4f}"
    )
