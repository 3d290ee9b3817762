"""The ``accugrid`` command line.

Every module in ``app/commands/`` is one subcommand: it defines ``NAME``,
``add_arguments(parser)`` and ``run(args) -> int``, or gives them as ``command(name)``
(``program``: one command per dialect; ``rewrite``: its help from every dialect's);
``commands.COMMANDS`` lists them with their help. Only the module of the command that runs is
imported (``accugrid --help`` imports none).
Exit codes (docs/guarantees.md): 0 success, 2 bad input or arguments (one line naming file, line and
column, no traceback), 1 internal error, 128 + the signal's number when SIGINT, SIGTERM or SIGHUP
ends the command (one line, no traceback, from the first statement of ``main`` on: the imports of
the command's modules included).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import os
import signal
import sys
import warnings

from accugrid import __version__
from accugrid.app.commands import COMMANDS
from accugrid.infra.errors import InputError, printable
from accugrid.infra.inputfile import track_inputs
from accugrid.infra.signals import TERMINATION_SIGNALS, Terminated, signals_raise

EXIT_OK, EXIT_INTERNAL, EXIT_INPUT = 0, 1, 2


__all__ = ["EXIT_INPUT", "EXIT_INTERNAL", "EXIT_OK", "build_parser", "main"]


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser; only ``command``'s module is imported and its arguments added (the others
    are listed with their help)."""
    parser = argparse.ArgumentParser(
        prog="accugrid",
        description="Grid-based TCP error compensation for robotic drilling. "
        "Lengths in mm, angles in degrees, speeds in mm/s, times in s.",
    )
    parser.add_argument("--version", action="version", version=f"accugrid {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, (module_name, help_text) in COMMANDS.items():
        if name != command:
            sub.add_parser(name, help=help_text, add_help=False)
            continue
        module = importlib.import_module(f"accugrid.app.commands.{module_name}")
        command = module.command(name) if hasattr(module, "command") else module
        cmd = sub.add_parser(
            name,
            help=help_text,
            description=command.__doc__,
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        command.add_arguments(cmd)
        cmd.set_defaults(handler=command.run)
    return parser


def _command(argv: list[str]) -> str | None:
    """The subcommand named on the command line (the first word that is not an option)."""
    return next((word for word in argv if not word.startswith("-")), None)


def _reading_format(args: argparse.Namespace) -> contextlib.AbstractContextManager[None]:
    """How the command's points and measurement CSVs are written (``--columns``, ``--units``,
    ...), for the commands that read them; nothing is imported for the others."""
    if not hasattr(args, "units"):
        return contextlib.nullcontext()
    from accugrid.app.cli_options import reading_format

    return reading_format(args)


def _ended(command: str | None, signum: int) -> int:
    """The one line of a command ended by signal ``signum``, and its exit code 128 + signum."""
    prog = f"accugrid {command}" if command else "accugrid"
    print(f"{prog}: interrupted ({signal.Signals(signum).name})", file=sys.stderr)
    return 128 + signum


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the process exit code (also used by the console script).

    Library warnings (numpy, ...) are held while the command runs: shown after a success, dropped
    after an error so the one-line message stands alone. Every file the command reads is tracked
    as an input that no output may replace (``infra.atomic``).
    """
    argv = sys.argv[1:] if argv is None else [str(a) for a in argv]
    try:
        with signals_raise():
            return _run(argv)
    except Terminated as ended:
        return _ended(_command(argv), ended.signum)
    except KeyboardInterrupt:  # SIGINT where no handler of ours was installed
        return _ended(_command(argv), signal.SIGINT)
    except SystemExit as stop:  # ``infra.atomic`` ends a write on a signal with 128 + it
        if stop.code in {128 + sig for sig in TERMINATION_SIGNALS}:
            return _ended(_command(argv), stop.code - 128)
        raise


def _run(argv: list[str]) -> int:
    """``main`` within its signal handlers."""
    for stream in (sys.stdout, sys.stderr):  # a non-UTF-8 byte of a file name prints as \udcff
        if isinstance(stream, io.TextIOWrapper):
            stream.reconfigure(errors="backslashreplace")
    args = build_parser(_command(argv)).parse_args(argv)
    with warnings.catch_warnings(record=True) as held, track_inputs():
        warnings.simplefilter("default")
        try:
            with _reading_format(args):  # inside: a --format file's error is an input error
                code = int(args.handler(args) or EXIT_OK)
        except InputError as exc:
            print(f"accugrid {args.command}: error: {exc}", file=sys.stderr)
            return EXIT_INPUT
        except BrokenPipeError:  # the reader of stdout left (`accugrid ... | head`)
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no 2nd error at exit
            print(f"accugrid {args.command}: standard output closed early", file=sys.stderr)
            return EXIT_INTERNAL
        except Exception as exc:  # noqa: BLE001 - the last line of defence: exit 1, no traceback
            if os.environ.get("ACCUGRID_DEBUG"):
                import traceback  # only here: it imports linecache, tokenize (~3 ms)

                traceback.print_exc()
            print(
                f"accugrid {args.command}: internal error: {type(exc).__name__}: "
                f"{printable(exc)} (set ACCUGRID_DEBUG=1 for the traceback)",
                file=sys.stderr,
            )
            return EXIT_INTERNAL
    for w in held:
        warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    return code


if __name__ == "__main__":
    sys.exit(main())
