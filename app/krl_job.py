"""`accugrid krl` as one call: the corrected program (``app.job.prepare``) rendered as a KRL
``.src``/``.dat`` pair, split into modules NAME_001.. when long (``krl.emit``)."""

from __future__ import annotations

import argparse
import dataclasses
import re
from pathlib import Path

from accugrid.app.job import Job, prepare
from accugrid.codegen.cell import Cell
from accugrid.codegen.krl.emit import module_split, render_krl

__all__ = ["krl_job", "krl_targets"]


def krl_targets(cell: Cell, out: Path) -> list[Path]:
    """The job's main files in folder ``out``: NAME.dat, NAME.src (NAME: the cell's program.name),
    to refuse existing outputs before any work."""
    name = cell.krl.name
    return [out / f"{name}.dat", out / f"{name}.src"]


def krl_job(args: argparse.Namespace, out: Path, cell: Cell | None = None) -> Job:
    """The whole job of ``accugrid krl`` arguments into folder ``out`` (``cell``: the cell file
    when already read): modules that cannot be named or called are refused before the
    correction; NAME.src is written last (NAME.dat before it) and the modules of an earlier job
    of this name are stale. The program's IK check still runs: write with ``ready=job.finish``."""
    split = []

    def check(cell: Cell, holes: int, header: list[str]) -> None:
        split.append(module_split(cell, holes, header, args.templates))

    job = prepare(args, "krl", check, cell)
    name = job.program.cell.krl.name
    files = render_krl(job.program, job.header, args.templates, split[0])
    module = re.compile(rf"{re.escape(name)}_[0-9]{{3,}}\.(src|dat)")
    stale = [p for p in out.glob(f"{name}_*") if module.fullmatch(p.name)]
    main = [out / f"{name}.dat", out / f"{name}.src"]
    return dataclasses.replace(job, files=files.at(out), main=main, stale=stale)
