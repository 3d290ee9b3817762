"""Write a corrected FANUC TP drilling program (.ls, ASCII) from a points CSV.

Positions are Cartesian P[n] of the cell's user frame (base.number: the cell's base frame) and
tool frame (tool.number), X, Y, Z mm and W, P, R deg, CONFIG from the robot model's IK (a cell
whose robot is a FANUC arm, e.g. r2000ic-165f). Each hole: J to the approach point on the drill
axis, L at approach speed to the clearance point, L at the feed to the depth, WAIT dwell, L
back to the retract point; a DO switches the spindle. The program name is the file's stem (or
fanuc.program). Every hole is corrected with the grid and/or the calibrated model (its point
mapped to the robot frame, P' = P + e(P), and the same e applied to all its positions).

Units: mm, deg, mm/s, s in the inputs and in the program. Exit 2 on bad input, with nothing
written.
"""

from __future__ import annotations

import argparse

from accugrid.app.cli_options import add_program_arguments, program_request
from accugrid.app.jobs.program import write_program

__all__ = ["NAME", "add_arguments", "run"]

NAME = "fanuc"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_program_arguments(parser, "NAME.ls", "the TP program to write")


def run(args: argparse.Namespace) -> int:
    print(write_program(program_request(args, NAME, "FANUC TP drilling program"), args.force))
    return 0
