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
from accugrid.kinematics.joint_errors import MAX_ORDER
from accugrid.kinematics.robot import Robot, load_robot

__all__ = ["add_abc", "add_harmonics", "add_status", "add_tool", "robot_with_tool"]


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


def add_harmonics(parser: argparse.ArgumentParser, help_text: str) -> None:
    """``--harmonics A2:1,7,160 A3:7 ...``: reducer harmonic orders per axis, parsed into a list
    of (axis 1..6, order) pairs (default: none)."""
    parser.add_argument(
        "--harmonics",
        nargs="+",
        type=_axis_orders,
        default=[],
        metavar="AN:K[,K...]",
        help=f"{help_text}; e.g. A2:1,7,160 A3:1,7 (axis 1..6, orders >= 1)",
    )


def _axis_orders(text: str) -> list[tuple[int, int]]:
    """'A2:1,7,160' -> [(2, 1), (2, 7), (2, 160)]; argparse turns the ValueError into exit 2."""
    axis, sep, orders = text.strip().upper().partition(":")
    try:
        if not sep or not axis.startswith("A"):
            raise ValueError
        number = int(axis[1:])
        pairs = [(number, int(k)) for k in orders.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"'{text}' is not AXIS:ORDERS such as A2:1,7,160"
        ) from None
    if not 1 <= number <= 6 or any(not 1 <= k <= MAX_ORDER for _, k in pairs):
        raise argparse.ArgumentTypeError(f"'{text}': axis A1..A6 and orders 1..{MAX_ORDER} only")
    return pairs


def robot_with_tool(name: str, tool: Sequence[float] | None) -> Robot:
    """``load_robot(name)`` carrying the ``--tool`` pose (mm, deg) when one was given."""
    robot = load_robot(name)
    if tool is not None:
        robot = robot.with_tool(pose_from_xyzabc(np.array(tool, dtype=float)))
    return robot
