"""Write a corrected ABB RAPID drilling module (.mod) from a points CSV.

Positions are CONST robtargets in the cell's work object (rapid.wobj: the cell's base frame),
orientation as unit quaternions, confdata from the robot model's IK (a cell whose robot is an
ABB arm, e.g. irb6700). Each hole: MoveJ to the approach point on the drill axis, MoveL at
approach speed to the clearance point, MoveL at the feed to the depth, WaitTime dwell, MoveL
back to the retract point; SetDO switches the spindle. Every hole is corrected with the grid
and/or the calibrated model (its point mapped to the robot frame, P' = P + e(P), and the same e
applied to all its positions).

Units: mm, deg, mm/s, s in the inputs and in the program. Exit 2 on bad input, with nothing
written.
"""

from __future__ import annotations

import argparse

from accugrid.app.cli_options import add_program_arguments, program_request
from accugrid.app.jobs.program import write_program

__all__ = ["NAME", "add_arguments", "run"]

NAME = "rapid"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_program_arguments(parser, "FILE.mod", "the module to write")


def run(args: argparse.Namespace) -> int:
    print(write_program(program_request(args, NAME, "ABB RAPID drilling program"), args.force))
    return 0
