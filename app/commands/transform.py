"""Map laser-tracker coordinates of a CSV into the robot frame (or back, with --inverse).

FRAME is a robot-frame YAML written by `accugrid fit-frame` (tracker_T_robot). The mapped
columns are one or both triples x,y,z and x_meas,y_meas,z_meas (mm), chosen by --triples:
  meas   x_meas,y_meas,z_meas only (the default when the file has them: in a measurement CSV
         x,y,z are the commanded points, already in the robot frame)
  xyz    x,y,z only (the default for a file without x_meas,y_meas,z_meas)
  both   both triples
Tracker exports are read as they come (--columns, --units, --delimiter, --decimal, --format, as
in every command that reads positions) and written back as they came: mapped numbers with 4
decimals of mm, in each column's own unit and the file's delimiter and decimal mark; a row whose
three cells of a triple are all empty stays empty. Every other column, comment line and blank
line is kept as it was, and a comment line naming the frame file (and its SHA-256) is put first.
"""

from __future__ import annotations

import argparse

from accugrid.app.cli_options import add_table_format
from accugrid.app.jobs.robot_frame import transform_csv
from accugrid.infra.atomic import check_targets, write_files

__all__ = ["NAME", "TRIPLES", "add_arguments", "run"]

NAME = "transform"
TRIPLES = ("meas", "xyz", "both")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("table", metavar="MEAS.csv", help="CSV with tracker-frame columns (mm)")
    parser.add_argument(
        "--frame", required=True, metavar="FRAME.yaml", help="robot frame from accugrid fit-frame"
    )
    parser.add_argument("-o", "--output", required=True, metavar="OUT.csv", help="CSV to write")
    parser.add_argument(
        "--triples",
        choices=TRIPLES,
        help="which triples to map (default: meas if the file has x_meas,y_meas,z_meas, else xyz)",
    )
    parser.add_argument(
        "--inverse",
        action="store_true",
        help="map robot-frame coordinates into the tracker frame instead",
    )
    add_table_format(parser)
    parser.add_argument("--force", action="store_true", help="overwrite an existing output")


def run(args: argparse.Namespace) -> int:
    check_targets([args.output], [args.table, args.frame], args.force)
    job = transform_csv(args.table, args.frame, args.output, args.triples, args.inverse)
    write_files(job.files, job.inputs, args.force)
    for line in job.lines:
        print(line)
    return 0
