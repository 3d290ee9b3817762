"""Map laser-tracker coordinates of a CSV into the robot frame (or back, with --inverse).

FRAME is a robot-frame YAML written by `accugrid fit-frame` (tracker_T_robot). The mapped
columns are one or both triples x,y,z and x_meas,y_meas,z_meas (mm), chosen by --columns:
  meas   x_meas,y_meas,z_meas only (the default when the file has them: in a measurement CSV
         x,y,z are the commanded points, already in the robot frame)
  xyz    x,y,z only (the default for a file without x_meas,y_meas,z_meas)
  both   both triples
Mapped numbers are written with 4 decimals; a row whose three cells of a triple are all empty
stays empty. Every other column, comment line and blank line is kept as it was, and a comment
line naming the frame file (and its SHA-256) is put first.
"""

from __future__ import annotations

import argparse
import csv
import io
from pathlib import Path

import numpy as np

from accugrid.codegen.atomic import check_targets, write_files
from accugrid.codegen.frame_file import load_frame
from accugrid.codegen.textsafe import comment_text, fixed
from accugrid.compensation.csvtable import Table, parse_table
from accugrid.kinematics.digest import file_sha256
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.frames import invert, transform_points
from accugrid.kinematics.inputfile import read_input_text

__all__ = ["DECIMALS", "NAME", "TRIPLES", "add_arguments", "run"]

NAME = "transform"

TRIPLES = {"xyz": ("x", "y", "z"), "meas": ("x_meas", "y_meas", "z_meas")}
DECIMALS = 4


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("table", metavar="MEAS.csv", help="CSV with tracker-frame columns (mm)")
    parser.add_argument(
        "--frame", required=True, metavar="FRAME.yaml", help="robot frame from accugrid fit-frame"
    )
    parser.add_argument("-o", "--output", required=True, metavar="OUT.csv", help="CSV to write")
    parser.add_argument(
        "--columns",
        choices=["meas", "xyz", "both"],
        help="which triples to map (default: meas if the file has x_meas,y_meas,z_meas, else xyz)",
    )
    parser.add_argument(
        "--inverse",
        action="store_true",
        help="map robot-frame coordinates into the tracker frame instead",
    )
    parser.add_argument("--force", action="store_true", help="overwrite an existing output")


def _chosen(table: Table, choice: str | None) -> list[tuple[str, str, str]]:
    """The column triples to map, each checked to be complete in the header."""
    if choice is None:
        choice = "meas" if any(table.has(n) for n in TRIPLES["meas"]) else "xyz"
    keys = ["xyz", "meas"] if choice == "both" else [choice]
    triples = [TRIPLES[k] for k in keys]
    for triple in triples:
        table.require(triple)
    return triples


def _mapped(table: Table, triple: tuple[str, str, str], pose: np.ndarray) -> np.ndarray:
    """(N, 3) mapped values of one triple; NaN rows where all three cells are empty."""
    values = table.floats(list(triple), allow_empty=True)
    empty = np.isnan(values)
    partial = np.flatnonzero(empty.any(axis=1) & ~empty.all(axis=1))
    if partial.size:
        r = int(partial[0])
        name = triple[int(np.flatnonzero(empty[r])[0])]
        raise InputError(
            f"empty cell in column '{name}' while the rest of {','.join(triple)} is filled",
            *table.where(r, name),
        )
    return transform_points(pose, values)


def run(args: argparse.Namespace) -> int:
    check_targets([args.output], [args.table, args.frame], args.force)
    text = read_input_text(args.table)[1]
    table = parse_table(text, args.table)
    tracker_T_robot = load_frame(args.frame)
    frame_sha = file_sha256(args.frame)
    pose = tracker_T_robot if args.inverse else invert(tracker_T_robot)
    triples = _chosen(table, args.columns)
    columns = {table.index(n): n for triple in triples for n in triple}
    mapped = {}
    for triple in triples:
        values = _mapped(table, triple, pose)
        for k, name in enumerate(triple):
            mapped[table.index(name)] = values[:, k]

    direction = (
        "from the robot frame into the tracker frame"
        if args.inverse
        else ("from the tracker frame into the robot frame")
    )
    note = (
        f"accugrid transform: {','.join(columns.values())} mapped {direction} with "
        f"{Path(args.frame).name} sha256 {frame_sha}"
    )
    body = _rewrite(text, table, mapped)
    write_files(
        {args.output: f"# {comment_text(note, limit=400)}\n{body}"},
        [args.table, args.frame],
        args.force,
    )
    print(f"{args.output}: {len(table)} row(s), {note}")
    return 0


def _rewrite(text: str, table: Table, mapped: dict[int, np.ndarray]) -> str:
    """The CSV text with the mapped cells replaced; every other line kept as it was."""
    lines = text.splitlines(keepends=True)
    row_at = {line: r for r, line in enumerate(table.lines)}
    reader = csv.reader(lines, strict=True)
    out: list[str] = []
    end = 0
    for record in reader:
        start, end = end, reader.line_num
        r = row_at.get(start + 1)
        if r is None:
            out.extend(lines[start:end])
            continue
        cells = list(record)
        for i, values in mapped.items():
            if not np.isnan(values[r]):
                cells[i] = fixed(values[r], DECIMALS)
        ending = lines[end - 1][len(lines[end - 1].rstrip("\r\n")) :] or "\n"
        buffer = io.StringIO()
        csv.writer(buffer, lineterminator=ending).writerow(cells)
        out.append(buffer.getvalue())
    return "".join(out)
