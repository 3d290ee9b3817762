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
from pathlib import Path

from accugrid.app.job import add_job_arguments, summary, with_report
from accugrid.app.krl_job import krl_job, krl_targets
from accugrid.codegen.cell import load_cell
from accugrid.infra.atomic import check_targets, write_files

__all__ = ["NAME", "add_arguments", "run"]

NAME = "krl"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_job_arguments(parser)
    parser.add_argument(
        "-o", "--output", required=True, metavar="DIR", help="folder for NAME.src and NAME.dat"
    )


def run(args: argparse.Namespace) -> int:
    out = Path(args.output)
    inputs = [args.points, args.cell] + ([args.grid] if args.grid else [])
    cell = load_cell(args.cell)
    report = [Path(args.report_html)] if args.report_html else []
    check_targets(krl_targets(cell, out) + report, inputs, args.force)
    job = krl_job(args, out, cell)
    files = with_report(job, args.report_html, "KUKA KRL drilling program")
    written = write_files(
        files, job.inputs, args.force, ready=job.finish, main=job.main, stale=job.stale
    )
    print(summary(job, written))
    return 0
