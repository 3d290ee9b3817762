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
import dataclasses
from pathlib import Path

from accugrid.app.job import add_job_arguments, prepare, summary
from accugrid.codegen.cell import load_cell
from accugrid.codegen.dialects import plugin_of
from accugrid.codegen.rapid.emit import module_name
from accugrid.infra.atomic import check_targets, write_files

__all__ = ["NAME", "add_arguments", "run"]

NAME = "rapid"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_job_arguments(parser)
    parser.add_argument(
        "-o", "--output", required=True, metavar="FILE.mod", help="the module to write"
    )


def run(args: argparse.Namespace) -> int:
    out = Path(args.output)
    check_targets([out], [args.points, args.cell] + ([args.grid] if args.grid else []), args.force)
    cell = load_cell(args.cell)
    plugin = plugin_of(NAME)
    module_name(cell.dialects[NAME].module, out)  # a name RAPID refuses: before any work
    job = prepare(args, NAME, cell=cell, joints=True)  # confdata comes from the joint angles
    files = plugin.render(job.program, job.header, args.templates, out)
    job = dataclasses.replace(job, files=files)
    written = write_files(job.files, job.inputs, args.force, ready=job.finish)
    print(summary(job, written))
    return 0
