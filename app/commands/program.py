"""The program commands, one per registered dialect (``codegen.dialects.DIALECTS``): ``accugrid
NAME POINTS --cell CELL -o OUT`` writes a new corrected drilling program in that dialect, its
summary, ``--help`` text, ``-o`` and report title from its plug-in (``DialectPlugin.help``), its
job ``jobs.program.write_program``."""

from __future__ import annotations

import argparse
from types import SimpleNamespace

from accugrid.app.cli_options import add_program_arguments, program_request
from accugrid.app.jobs.program import write_program
from accugrid.codegen.dialects import plugin_of

__all__ = ["command"]


def command(name: str) -> SimpleNamespace:
    """The command of dialect ``name``: ``NAME``, ``__doc__`` (its description),
    ``add_arguments(parser)`` and ``run(args) -> int``, as a command module has them."""
    help = plugin_of(name).help

    def add_arguments(parser: argparse.ArgumentParser) -> None:
        add_program_arguments(parser, name, *help.output)

    def run(args: argparse.Namespace) -> int:
        print(write_program(program_request(args, name, help.report), args.force))
        return 0

    return SimpleNamespace(
        NAME=name, __doc__=help.description, add_arguments=add_arguments, run=run
    )
