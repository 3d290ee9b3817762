"""The drill's TCP and axis measured on the calibrated arm.

MEAS.csv: the measurement CSV (docs/formats.md) of an SMR seated at the tool's point (a tip
adapter) at 6 or more orientations: x,y,z (commanded), x_meas,y_meas,z_meas (measured, robot
frame, mm) and the logged joints a1..a6 (deg; without them, a,b,c (deg) and the taught --tool
give the joints by the nominal IK, in the Status of column s); optional column point: tip
(default) or axis (a second SMR point on the drill axis, behind the tip, which gives the drill
axis). Repeats of a pose are averaged. The TCP is the least-squares point in the calibrated
flange's frame.

The tool file holds tool: {x, y, z (mm), a, b, c (KUKA ABC, deg)}, its 1 sigma and the model it
was measured on. A cell uses it as tool: {file: TOOL.yaml, number: N}. The command prints the
line that sets the tool on each controller (KRL TOOL_DATA, RAPID tooldata's tframe, G-code
G10 L1).
"""

from __future__ import annotations

import argparse

from accugrid.app.cli_options import (
    add_frame_number,
    add_table_format,
    add_tool,
    reading_format,
)
from accugrid.app.jobs.identify_tool import ToolRequest, identify_tool_files
from accugrid.infra.atomic import check_targets, write_files

__all__ = ["NAME", "add_arguments", "run"]

NAME = "identify-tool"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "measurements",
        metavar="MEAS.csv",
        help="SMR at the tool's point (and on its axis) at 6 or more orientations, joints logged",
    )
    parser.add_argument(
        "--model", required=True, metavar="CAL.yaml", help="the calibrated arm (accugrid identify)"
    )
    parser.add_argument("-o", "--output", required=True, metavar="TOOL.yaml", help="output YAML")
    add_tool(
        parser,
        "the tool as taught on the controller (mm, deg): its A B C are kept without axis rows, "
        "the logged joints are checked against its TCP, and the measured TCP is compared with it",
        "not checked; A B C 0",
    )
    add_frame_number(parser, "tool")
    add_table_format(parser)
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")


def run(args: argparse.Namespace) -> int:
    check_targets([args.output], [args.measurements, args.model], args.force)
    with reading_format(args):
        job = identify_tool_files(
            ToolRequest(
                measurements=args.measurements,
                model=args.model,
                output=args.output,
                taught=tuple(args.tool) if args.tool is not None else None,
                number=args.number,
            )
        )
    write_files(job.files, job.inputs, args.force)
    for line in job.lines:
        print(line)
    return 0
