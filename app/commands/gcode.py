"""Write a corrected RS274NGC (LinuxCNC) drilling program from a points CSV.

Positions are the tool centre point in the cell's program frame (program_frame, default the BASE
frame), mm; orientation as A B C words: the KUKA A, B, C of the tool in that frame, deg. Each hole:
G0 to the approach point on the drill axis; where the drill axis is the program's -Z, a canned
cycle (G81, G82 with the dwell, G83 with the cell's peck), else G1 moves along the drill axis at
approach speed and feed, G4 dwell, G1 retract. Every hole is corrected with the grid (its point
mapped to the robot frame, P' = P + e(P), and the same e applied to all its positions).

Units: mm, deg, mm/s in the inputs; F in mm/min (G94) in the program. Exit 2 on bad input, with
nothing written.
"""

from __future__ import annotations

import argparse

from accugrid.app.cli_options import add_program_arguments, program_request
from accugrid.app.jobs.program import write_program

__all__ = ["NAME", "add_arguments", "run"]

NAME = "gcode"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_program_arguments(parser, "FILE", "the .ngc to write")


def run(args: argparse.Namespace) -> int:
    print(write_program(program_request(args, NAME, "G-code drilling program"), args.force))
    return 0
