"""``accugrid rewrite``: the pre-flight correction of existing programs, of every registered
dialect (``codegen.dialects.DIALECTS``): the programs it reads, their paragraphs of its
``--help`` and their own options come from the dialects' plug-ins (``DialectPlugin.help``,
``options``); the job is ``jobs.rewrite.rewrite_job``.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from types import SimpleNamespace

from accugrid.app.cli_options import (
    COORDINATE_MAX,
    add_policy,
    add_table_format,
    number,
    policy_request,
)
from accugrid.app.jobs.rewrite import RewriteRequest, rewrite_job
from accugrid.codegen.dialects import DIALECTS, dialect_of, plugin_of
from accugrid.codegen.plugin import DialectOption
from accugrid.codegen.program_text import MAX_BYTES
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM
from accugrid.infra.atomic import check_targets, write_files
from accugrid.infra.errors import InputError
from accugrid.infra.memory import map_large_buffers

__all__ = ["command"]

NAME = "rewrite"
_HEAD = """Pre-flight correction of an existing program, one of:
{programs}

Every Cartesian position that can be placed in the robot frame is corrected with the grid
(P' = P + e, robot frame, converted back to the program frame); only those X, Y, Z numbers change,
with the input's decimal places but never coarser than 0.01 mm (0.001 in). Every other byte
(spacing, comments, line endings, encoding) is kept. Anything that cannot be placed (each kind of
program below says what) is left untouched. A placed position the grid or model does not correct
(outside the grid unless --outside clamp, more than --orientation-limit from the grid's
orientation, another Status than the grid's) fails the job, and so does a rewrite that corrects
nothing, unless --allow-partial, which leaves them as they are, counts them by reason on stderr
and marks them in the report and the --header. The report lists each position with its status
and reason.

"""
_TAIL = """
Output: for one file, -o is the output file (or an existing directory). For a program given as
two files, -o is a directory (the files keep their names) or the path of the first output, with
the second written beside it under the same stem.
"""
# program bytes from which large buffers are mapped (``infra.memory``): a million positions' 55
# to 206 MiB, not 100,000 positions' 6 to 20 MiB, whose peak is small and whose every fresh mapped
# page would cost it time (a 1e5-position KRL pair rewrite 0.60 -> 0.50 s without)
_MAPPED_FROM = 32 << 20


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "program", metavar="PROGRAM", help="the program: one of the kinds above, by its suffix"
    )
    pairs = _pairs()
    parser.add_argument(
        "second",
        nargs="?",
        metavar="PROGRAM" + "|".join(pair[1] for _, pair in pairs),
        help="the second file of a program given as two: "
        + "; ".join(f"the {pair[1]} of a {title} {pair[0]}" for title, pair in pairs),
    )
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
    _add_dialect_options(parser)


def _add_dialect_options(parser: argparse.ArgumentParser) -> None:
    """Each dialect's own options (``DialectPlugin.options``), in a group named by the dialects
    that read it."""
    readers: dict[DialectOption, list[str]] = {}
    for dialect in DIALECTS.values():
        for option in plugin_of(dialect.name).options:
            readers.setdefault(option, []).append(dialect.title)
    groups: dict[str, argparse._ArgumentGroup] = {}
    for option, titles in readers.items():
        title = " and ".join(titles) + " programs"
        group = groups.get(title) or groups.setdefault(title, parser.add_argument_group(title))
        if option.metavar is None:
            group.add_argument(option.flag, action="store_true", help=option.help)
        elif option.whole is not None:
            kind = number("", *option.whole, whole=True)
            group.add_argument(option.flag, type=kind, metavar=option.metavar, help=option.help)
        else:
            group.add_argument(option.flag, metavar=option.metavar, help=option.help)


def _dialect_options() -> list[DialectOption]:
    """Every dialect's own options, each once."""
    return list(dict.fromkeys(o for d in DIALECTS for o in plugin_of(d).options))


def _pairs() -> list[tuple[str, tuple[str, str]]]:
    """(title, pair) of every dialect whose program may be two files (``DialectPlugin.pair``)."""
    pairs = [(d.title, plugin_of(d.name).pair) for d in DIALECTS.values()]
    return [(title, pair) for title, pair in pairs if pair]


def command(name: str) -> SimpleNamespace:
    """The command: ``NAME``, ``__doc__`` (its description, with every dialect's paragraph),
    ``add_arguments`` and ``run``."""
    programs = "\n".join(f"  {d.title}: {' '.join(d.suffixes)}" for d in DIALECTS.values())
    paragraphs = "\n".join(plugin_of(d).help.rewrite for d in DIALECTS)
    return SimpleNamespace(
        NAME=name,
        __doc__=_HEAD.format(programs=programs) + paragraphs + _TAIL,
        add_arguments=add_arguments,
        run=run,
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
        what = " or ".join(f"the {pair[1]} of a {title} {pair[0]}" for title, pair in _pairs())
        raise InputError(f"the second file must be {what}", os.fspath(inputs[1]))
    return pair


def _size(path: Path) -> int:
    """The file's size in bytes (0 when it cannot be read: the reader says why)."""
    try:
        return path.stat().st_size
    except OSError:
        return 0


def run(args: argparse.Namespace) -> int:
    inputs = [Path(args.program)] + ([Path(args.second)] if args.second else [])
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
    options = {option.key: getattr(args, option.key) for option in _dialect_options()}
    files = [options[o.key] for o in _dialect_options() if o.file and options[o.key]]
    read = inputs + [Path(args.cell)] + [Path(file) for file in files]
    check_targets(targets, read, args.force)
    job = rewrite_job(
        RewriteRequest(
            outputs=outputs,
            cell=args.cell,
            grid=args.grid,
            model=args.model,
            report=Path(args.report) if args.report else None,
            report_html=Path(args.report_html) if args.report_html else None,
            header=args.header,
            decimals=args.decimals,
            policy=policy_request(args),
            options=options,
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
