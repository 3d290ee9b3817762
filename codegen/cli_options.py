"""Command-line options shared by several ``accugrid`` subcommands (same flags, same units).

Each ``add_*`` takes the command's own help text, so ``--help`` still says what the option means
for that command; ``robot_with_tool`` turns ``--robot``/``--tool`` values into a Robot.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

import numpy as np

from accugrid.compensation.plans import SEED_ABC
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.robot import Robot, load_robot

__all__ = ["add_abc", "add_status", "add_tool", "robot_with_tool"]


def add_abc(parser: argparse.ArgumentParser, help_text: str) -> None:
    """``--abc A B C``: a fixed TCP orientation, KUKA ABC in deg (default: the seed's 0 90 0)."""
    parser.add_argument(
        "--abc",
        nargs=3,
        type=float,
        default=list(SEED_ABC),
        metavar=("A", "B", "C"),
        help=f"{help_text}, KUKA A B C in deg (default: 0 90 0)",
    )


def add_tool(parser: argparse.ArgumentParser, help_text: str) -> None:
    """``--tool X Y Z A B C``: flange_T_tool in mm and deg (default: none, the flange)."""
    parser.add_argument(
        "--tool",
        nargs=6,
        type=float,
        metavar=("X", "Y", "Z", "A", "B", "C"),
        help=help_text,
    )


def add_status(parser: argparse.ArgumentParser, help_text: str) -> None:
    """``--status S``: one KUKA Status 0..7 (default: None, the command's documented choice)."""
    parser.add_argument("--status", type=int, choices=range(8), metavar="S", help=help_text)


def robot_with_tool(name: str, tool: Sequence[float] | None) -> Robot:
    """``load_robot(name)`` carrying the ``--tool`` pose (mm, deg) when one was given."""
    robot = load_robot(name)
    if tool is not None:
        robot = robot.with_tool(pose_from_xyzabc(np.array(tool, dtype=float)))
    return robot
