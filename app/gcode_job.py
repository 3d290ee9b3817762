"""`accugrid gcode` as one call: the corrected program (``app.job.prepare``) rendered as one
RS274NGC file (``gcode.emit``), in pieces as it is written."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from accugrid.app.job import Job, prepare
from accugrid.codegen.gcode.emit import gcode_text

__all__ = ["gcode_job"]


def gcode_job(args: argparse.Namespace, out: Path) -> Job:
    """The whole job of ``accugrid gcode`` arguments into the file ``out``; the program's IK
    check still runs: write with ``ready=job.finish``."""
    job = prepare(args, "gcode")
    return dataclasses.replace(
        job, files={out: gcode_text(job.program, job.header, args.templates)}
    )
