"""Command-line options shared by several ``accugrid`` subcommands (same flags, same units).

Each ``add_*`` takes the command's own help text, so ``--help`` still says what the option means
for that command; ``robot_with_tool`` turns ``--robot``/``--tool`` values into a Robot.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from accugrid.compensation.plans import SEED_ABC, SEED_CENTRES, SEED_REPEATS
from accugrid.kinematics.errors import InputError

if TYPE_CHECKING:
    from accugrid.kinematics.identification import Terms
    from accugrid.kinematics.robot import Robot

__all__ = [
    "add_abc",
    "add_experiment_arguments",
    "add_harmonics",
    "add_policy",
    "add_status",
    "add_tool",
    "harmonics_of",
    "parse_centres",
    "parse_steps",
    "robot_with_tool",
]


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
    """``--harmonics A2:1,7,160 A3:7 ...``: reducer harmonic orders per axis, each word parsed
    into (axis 1..6, order) pairs (default: none); ``harmonics_of`` gives the terms."""
    parser.add_argument(
        "--harmonics",
        nargs="+",
        type=_axis_orders,
        default=[],
        metavar="AN:K[,K...]",
        help=f"{help_text}; e.g. A2:1,7,160 A3:1,7 (axis 1..6, orders >= 1)",
    )


def harmonics_of(args: argparse.Namespace) -> Terms:
    """The reducer harmonic terms of ``--harmonics``, all words together, checked once more as
    a whole (duplicates dropped, at most ``MAX_HARMONICS``)."""
    from accugrid.kinematics.identification import harmonic_terms  # only the model commands

    return harmonic_terms(pair for pairs in args.harmonics for pair in pairs)


def _axis_orders(text: str) -> Terms:
    """'A2:1,7,160' -> ((2, 1), (2, 7), (2, 160)), ranges checked by ``harmonic_terms``;
    argparse turns the ArgumentTypeError into exit 2."""
    from accugrid.kinematics.identification import harmonic_terms

    axis, sep, orders = text.strip().upper().partition(":")
    try:
        if not sep or not axis.startswith("A"):
            raise ValueError
        number = int(axis[1:])
        return harmonic_terms((number, int(k)) for k in orders.split(","))
    except InputError as error:  # a ValueError too: first
        raise argparse.ArgumentTypeError(f"'{text}': {error.message}") from None
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"'{text}' is not AXIS:ORDERS such as A2:1,7,160"
        ) from None


def robot_with_tool(name: str, tool: Sequence[float] | None) -> Robot:
    """``load_robot(name)`` carrying the ``--tool`` pose (mm, deg) when one was given."""
    from accugrid.kinematics.frames import pose_from_xyzabc
    from accugrid.kinematics.robot import load_robot  # only the commands that drive a robot

    robot = load_robot(name)
    if tool is not None:
        robot = robot.with_tool(pose_from_xyzabc(np.array(tool, dtype=float)))
    return robot


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


def add_policy(parser: argparse.ArgumentParser, what: str) -> None:
    """``--allow-partial`` and ``--strict``, the job rule of the correction policy
    (``compensation.policy``) for every command that corrects; ``what`` names its positions."""
    parser.add_argument(
        "--allow-partial",
        action="store_true",
        help=f"write the job although some {what} cannot be corrected (outside the grid, "
        "orientation or Status the grid does not hold for, unreachable): they are left as "
        "they are, counted by reason on stderr and marked (default: refuse the job, exit 2)",
    )
    parser.add_argument(
        "--strict",
        action="store_true",
        help=f"with a model: refuse {what} outside the poses it was identified from (region, "
        "tool tilt, joint ranges) instead of flagging them",
    )
