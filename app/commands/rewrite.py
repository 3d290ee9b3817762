"""Pre-flight correction of an existing KRL (.src/.dat), G-code or ABB RAPID program.

Every Cartesian position that can be placed in the robot frame is corrected with the grid
(P' = P + e, robot frame, converted back to the program frame); only those X, Y, Z numbers change,
with the input's decimal places but never coarser than 0.01 mm (0.001 in). Every other byte
(spacing, comments, line endings, encoding) is kept. Anything that cannot be placed (frame
arithmetic ':', a base from a variable or a call, EK(), AXIS/E6AXIS targets, $POS_ACT,
G55-G59/G92 offsets, unknown motions, parameter words) is left untouched. A G-code arc (G2/G3)
moves rigidly, start, centre and end by one shift (the correction at its centre), where that
shift holds along the whole arc to the program's written resolution; otherwise the arc is left
as written and reported. A placed position the grid or model does not correct (outside the
grid unless --outside clamp, more than --orientation-limit from the grid's orientation, another
KUKA Status than the grid's: the S of a KRL position, else the last S written before it in its
file, else the cell's configuration.status, the cell's configuration for G-code) fails the job,
and so does a rewrite that corrects nothing, unless --allow-partial, which leaves them as they
are, counts them by reason on stderr and marks them in the report and the --header. The report
lists each position with its status and reason.

KRL: PROGRAM is a .src or .dat; give the .dat beside it as the second argument. A stored position
is corrected only if a motion uses it (never a frame given to $TOOL/$BASE/$LOAD, an operand of
':' or a CONST) and takes the base of the motions that use it ($BASE = BASE_DATA[n],
BAS(#BASE,n), FDAT BASE_NO); BASE_DATA values come from --config-dat or the cell file (base,
base_data); base 0 is the robot frame. Where a routine starts without setting $BASE, and for the
POS/E6POS of a .dat given alone, --base N says which BASE_DATA they are in (a position's own FDAT
wins over it).
G-code: positions are in the cell's program_frame (default: its base), G54 active; A, B, C
words are the tool orientation and stay as written.

RAPID (.mod/.modx/.prg/.sys): robtargets moved only by MoveL/MoveJ (and their DO/AO/GO/Sync
forms, TriggL/TriggJ) with the cell's rapid.tool in its rapid.wobj (the base frame) or wobj0 (the
robot frame); never tooldata, wobjdata, jointtarget, loaddata, pose, Offs/RelTool operands or
robtargets changed at run time.

Output: for one file, -o is the output file (or an existing directory). For a .src/.dat pair,
-o is a directory (the files keep their names, which KRL needs to match DEF/DEFDAT) or the output
.src path, with the .dat written beside it under the same stem.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from accugrid.app.cli_options import (
    COORDINATE_MAX,
    add_policy,
    add_table_format,
    number,
    policy_request,
)
from accugrid.app.jobs.rewrite import RewriteRequest, rewrite_job
from accugrid.codegen.dialects import DIALECTS, dialect_of, plugin_of
from accugrid.codegen.program_text import MAX_BYTES
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM
from accugrid.infra.atomic import check_targets, write_files
from accugrid.infra.errors import InputError
from accugrid.infra.memory import map_large_buffers

__all__ = ["NAME", "add_arguments", "run"]

NAME = "rewrite"
# program bytes from which large buffers are mapped (``infra.memory``): a million positions' 55
# to 206 MiB, not 100,000 positions' 6 to 20 MiB, whose peak is small and whose every fresh mapped
# page would cost it time (a 1e5-position KRL pair rewrite 0.60 -> 0.50 s without)
_MAPPED_FROM = 32 << 20


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "program", metavar="PROGRAM", help="KRL .src/.dat, G-code or RAPID (.mod/.modx/.prg/.sys)"
    )
    parser.add_argument("dat", nargs="?", metavar="PROGRAM.dat", help="the .dat of a KRL .src")
    parser.add_argument("--cell", required=True, metavar="CELL.yaml", help="cell file (frames)")
    parser.add_argument("--grid", metavar="MEAS.csv", help="measurement CSV (overrides the cell)")
    parser.add_argument(
        "--model",
        metavar="CAL.yaml",
        help="calibrated robot (accugrid identify; overrides the cell's correction.model): "
        "positions are corrected by the model at their orientation, the grid holds the residual",
    )
    parser.add_argument("-o", "--output", required=True, metavar="OUT", help="output file or dir")
    parser.add_argument("--report", metavar="REPORT.csv", help="write the per-position report")
    parser.add_argument(
        "--report-html",
        metavar="FILE",
        help="also write the self-contained HTML report (inputs with SHA-256, a map of the "
        "corrections, the positions flagged, not corrected or skipped with the reasons)",
    )
    add_policy(parser, "positions")
    add_table_format(parser)
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")
    parser.add_argument(
        "--config-dat", metavar="$config.dat", help="KRL $config.dat with BASE_DATA[n] values"
    )
    parser.add_argument(
        "--base",
        type=number("", 0, 32, whole=True),
        metavar="N",
        help="BASE_DATA number in effect where the program does not set one (a lone .dat, or "
        "the start of a routine); 0 = robot frame",
    )
    parser.add_argument(
        "--trust-calls",
        action="store_true",
        help="KRL: assume no call changes $BASE or $TOOL (without it, a call keeps them when its "
        "routine is in the given files and changes neither)",
    )
    parser.add_argument(
        "--ignore-external-axes",
        action="store_true",
        help="KRL, RAPID: correct positions with external axes in use (non-zero E1..E6, RAPID "
        "eax values other than 9E+09): the external axes move neither the robot nor the base",
    )
    parser.add_argument(
        "--decimals",
        type=number("", 0, 9, whole=True),
        metavar="N",
        help="decimals of corrected numbers (default: as input)",
    )
    parser.add_argument(
        "--max-mb",
        type=number("MiB", 0, 1e6, above=True),
        default=MAX_BYTES / 2**20,
        metavar="MiB",
        help=f"refuse program files larger than this, MiB (default: {MAX_BYTES // 2**20})",
    )
    parser.add_argument("--header", action="store_true", help="add the accugrid comment header")
    parser.add_argument(
        "--tolerance",
        type=number("mm", 0, COORDINATE_MAX, above=True),
        default=DEFAULT_TOLERANCE_MM,
        metavar="MM",
        help="hole position tolerance, mm: a move that the axes its line does not write leave "
        "farther than this from its correction is reported, not corrected; warn when rounding to "
        f"the written decimals leaves more than a tenth of it (default: {DEFAULT_TOLERANCE_MM:g})",
    )


def _outputs(inputs: list[Path], output: str, pair: tuple[str, str] | None) -> dict[Path, Path]:
    out = Path(output)
    if len(inputs) == 1:
        return {inputs[0]: out / inputs[0].name if out.is_dir() else out}
    if out.is_dir():  # an existing folder, whatever its name (out.v2)
        return {p: out / p.name for p in inputs}
    if pair is not None and out.suffix.lower() == pair[0]:
        return {p: out.with_suffix(p.suffix) for p in inputs}
    if out.suffix:
        raise InputError(
            f"for a {'/'.join(pair)} pair -o must be a directory or a {pair[0]} path", output
        )
    return {p: out / p.name for p in inputs}


def _pair(inputs: list[Path]) -> tuple[str, str] | None:
    """The suffixes of a program given as two files (``DialectPlugin.pair``), None for a
    dialect whose programs are one file; InputError when two files are not one program's."""
    kinds = [dialect_of(p) for p in inputs]
    pair = plugin_of(kinds[0]).pair
    if len(inputs) == 2 and (
        pair is None or kinds[1] != kinds[0] or inputs[0].suffix.lower() == inputs[1].suffix.lower()
    ):
        pairs = [(d.title, plugin_of(d.name).pair) for d in DIALECTS.values()]
        what = " or ".join(f"the {p[1]} of a {title} {p[0]}" for title, p in pairs if p)
        raise InputError(f"the second file must be {what}", os.fspath(inputs[1]))
    return pair


def _size(path: Path) -> int:
    """The file's size in bytes (0 when it cannot be read: the reader says why)."""
    try:
        return path.stat().st_size
    except OSError:
        return 0


def run(args: argparse.Namespace) -> int:
    inputs = [Path(args.program)] + ([Path(args.dat)] if args.dat else [])
    if sum(_size(path) for path in inputs) >= _MAPPED_FROM:
        map_large_buffers()  # a large program's columns freed go back to the system (peak memory)
    pair = _pair(inputs)
    if args.strict and args.model is None:
        print(
            "accugrid rewrite: note: --strict is no longer needed for positions outside the "
            "grid (refused by default now; --allow-partial keeps them as they are); it refuses "
            "positions outside a model's poses",
            file=sys.stderr,
        )
    outputs = _outputs(inputs, args.output, pair)
    reports = [Path(r) for r in (args.report, args.report_html) if r]
    targets = list(outputs.values()) + reports
    if len(set(map(os.path.abspath, targets))) != len(targets):
        raise InputError("two outputs would have the same name", args.output)
    read = inputs + [Path(args.cell)] + ([Path(args.config_dat)] if args.config_dat else [])
    check_targets(targets, read, args.force)
    job = rewrite_job(
        RewriteRequest(
            outputs=outputs,
            cell=args.cell,
            grid=args.grid,
            model=args.model,
            report=Path(args.report) if args.report else None,
            report_html=Path(args.report_html) if args.report_html else None,
            config_dat=Path(args.config_dat) if args.config_dat else None,
            header=args.header,
            decimals=args.decimals,
            policy=policy_request(args),
            base=args.base,
            trust_calls=args.trust_calls,
            ignore_external_axes=args.ignore_external_axes,
            max_bytes=int(args.max_mb * 2**20),
            tolerance_mm=args.tolerance,
        )
    )
    # a KRL pair: the .src (what a controller runs) replaced last
    write_files(job.files, job.read, args.force, main=[outputs[inputs[0]]])
    for line in job.warnings:
        print(f"accugrid rewrite: warning: {line}", file=sys.stderr)
    print(job.summary() + " -> " + ", ".join(os.fspath(p) for p in outputs.values()))
    return 0
