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

from accugrid.app.cli_options import add_table_format, number
from accugrid.app.jobs.robot_frame import fit_frame_files
from accugrid.infra.atomic import check_targets, write_files
from accugrid.kinematics.base_frame import SMR_RADIUS_MM

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
        type=number("mm", 0, 1000, above=True),
        default=SMR_RADIUS_MM,
        metavar="MM",
        help=f"SMR ball radius in mm (default {SMR_RADIUS_MM}, a 1.5-inch SMR)",
    )
    parser.add_argument("-o", "--output", required=True, metavar="FRAME.yaml", help="output YAML")
    parser.add_argument(
        "--plot", metavar="FIG.png", help="also write a PNG of the fitted plane and circles"
    )
    add_table_format(parser)
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")


def run(args: argparse.Namespace) -> int:
    inputs = [args.base_plane, args.a1_circle, args.flange_holes]
    check_targets([args.output] + ([args.plot] if args.plot else []), inputs, args.force)
    job = fit_frame_files(*inputs, args.output, args.plot, args.smr_radius)
    write_files(job.files, job.inputs, args.force)
    for line in job.lines:
        print(line)
    return 0
