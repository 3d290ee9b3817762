"""Write a corrected KUKA KRL drilling program (.src/.dat) from a points CSV.

Each hole: travel (PTP ... C_PTP, or LIN ... C_DIS) to the approach point on the drill axis, LIN at
approach speed to the clearance point, LIN at the feed to the depth, WAIT SEC dwell, LIN back to
the retract point. Positions are E6POS in the .dat, in the cell's BASE frame (BASE_DATA[n]), with
the KUKA Status and Turn from the robot model's IK. Every hole is corrected with the grid (its
point mapped to the robot frame, P' = P + e(P), and the same e applied to all its positions).
Long jobs are split into NAME_001, NAME_002, ... called from NAME.src (program.lines_per_file).

Units: mm, deg, mm/s in the inputs; $VEL.CP in m/s in the program. Exit 2 on bad input, with
nothing written.
"""

from __future__ import annotations

import argparse

from accugrid.app.cli_options import add_program_arguments, program_request
from accugrid.app.jobs.program import write_program

__all__ = ["NAME", "add_arguments", "run"]

NAME = "krl"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_program_arguments(parser, "DIR", "folder for NAME.src and NAME.dat")


def run(args: argparse.Namespace) -> int:
    print(write_program(program_request(args, NAME, "KUKA KRL drilling program"), args.force))
    return 0
