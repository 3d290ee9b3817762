"""The part frame from datums: robot_T_base by least squares.

DATUMS.csv: columns id, x, y, z (mm) of datum features (tooling balls, reference holes) measured
by the laser tracker, in the robot frame, or in the tracker frame with --frame (the file written
by fit-frame). A datum measured several times (one id on several rows) is averaged.
NOMINAL.csv: columns id, x, y, z (mm) of the same datums in the part's CAD frame. At least 3
datums not on one line are needed; with 4 or more, a datum that the others put 10 times farther
off than their residuals lead to expect (and at least 0.1 mm) is named as moved and refused.

The part file holds base: {x, y, z (mm), a, b, c (KUKA ABC, deg)}, the scale, the noise sigma
estimated from the residuals and the frame's covariance. The base is rigid: a part scaled by
--scale fit or --cte needs its holes' CAD coordinates scaled by the printed scale. A cell uses it as
base: {file: PART.yaml, number: N}. The command prints each datum's residual, the frame's 95 %
bound at the datums and the line that sets the base frame on each controller (KRL BASE_DATA,
RAPID wobjdata, G-code G10 L2).
"""

from __future__ import annotations

import argparse

from accugrid.app.cli_options import add_frame_number, add_table_format, number
from accugrid.app.jobs.fit_part import PartRequest, fit_part_files
from accugrid.infra.atomic import check_targets, write_files

__all__ = ["NAME", "add_arguments", "run"]

NAME = "fit-part"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("datums", metavar="DATUMS.csv", help="measured datums: id, x, y, z (mm)")
    parser.add_argument(
        "--nominal", required=True, metavar="NOMINAL.csv", help="CAD datums: id, x, y, z (mm)"
    )
    parser.add_argument(
        "--frame",
        metavar="FRAME.yaml",
        help="the datums are in the tracker frame: map them with this fit-frame file "
        "(default: they are in the robot frame)",
    )
    parser.add_argument("-o", "--output", required=True, metavar="PART.yaml", help="output YAML")
    parser.add_argument(
        "--scale",
        choices=["rigid", "fit"],
        default="rigid",
        help="rigid: the part has its CAD size (default); fit: fit an isotropic scale too "
        "(a part at another temperature; needs 3 datums or more, better 5)",
    )
    parser.add_argument(
        "--cte",
        type=number("1/K", -1e-3, 1e-3),
        metavar="PER_K",
        help="the part's thermal expansion coefficient in 1/K (e.g. 23e-6 for aluminium): the "
        "scale is 1 + cte (temperature - 20 degC); with --temperature",
    )
    parser.add_argument(
        "--temperature",
        type=number("degC", -50, 200),
        metavar="C",
        help="the part's temperature in degC during the measurement (with --cte)",
    )
    add_frame_number(parser, "base")
    add_table_format(parser)
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")


def run(args: argparse.Namespace) -> int:
    inputs = [args.datums, args.nominal] + ([args.frame] if args.frame else [])
    check_targets([args.output], inputs, args.force)
    job = fit_part_files(
        PartRequest(
            datums=args.datums,
            nominal=args.nominal,
            output=args.output,
            frame=args.frame,
            scale=args.scale,
            cte_per_k=args.cte,
            temperature_c=args.temperature,
            number=args.number,
        )
    )
    write_files(job.files, job.inputs, args.force)
    for line in job.lines:
        print(line)
    return 0
