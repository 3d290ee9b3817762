"""The CLI's command table: complete, a program command per registered dialect (a new registry
line is a new command, with no change to the command line), and only the running command is
imported."""

from __future__ import annotations

import importlib
import pkgutil
import subprocess
import sys

from accugrid.app import commands
from accugrid.app.cli import build_parser
from accugrid.app.commands import COMMANDS
from accugrid.codegen.dialects import DIALECTS, plugin_of


def test_table_lists_every_command_module_under_its_name():
    modules = {m.name for m in pkgutil.iter_modules(commands.__path__)}
    assert {module for module, _ in COMMANDS.values()} == modules
    for name, (module, help_text) in COMMANDS.items():
        loaded = importlib.import_module(f"accugrid.app.commands.{module}")
        command = loaded.command(name) if hasattr(loaded, "command") else loaded
        assert command.NAME == name and help_text and command.__doc__
        assert callable(command.add_arguments) and callable(command.run)


def test_every_registered_dialect_is_a_program_command_with_its_plugins_help():
    assert {n for n, (module, _) in COMMANDS.items() if module == "program"} == set(DIALECTS)
    for name in DIALECTS:
        said = plugin_of(name).help
        assert COMMANDS[name][1] == said.summary
        parsers = next(a for a in build_parser(name)._actions if a.dest == "command")
        text = parsers.choices[name].format_help()
        assert said.description.strip() in text and said.output[1] in text


_TOY = r"""
import dataclasses, sys, types
from accugrid.codegen import dialects
from accugrid.codegen.gcode.plugin import HELP, GcodePlugin
from accugrid.codegen.plugin import DialectOption

class Toy(GcodePlugin):
    name, title, suffixes = "toy", "Toy Robot Language", (".toy", ".tyy")
    options = (DialectOption("--toy-frame", "the toy's frame number", "N", whole=(1, 9)),)
    help = dataclasses.replace(
        HELP, summary="corrected toy program", description="Write a toy program.\n",
        output=("FILE.toy", "the toy program to write"), rewrite="Toy: its own paragraph.\n",
    )

module = types.ModuleType("toy_plugin")
module.PLUGIN = Toy()
sys.modules["toy_plugin"] = module
dialects.DIALECTS["toy"] = dialects.Dialect.of_plugin("toy_plugin")
from accugrid.app.cli import main
main(sys.argv[1:])
"""


def _toy(*argv: str) -> str:
    """What ``accugrid ARGV`` prints with a toy dialect registered by one more registry line
    (its plug-in in a module of its own) and nothing else changed."""
    run = subprocess.run([sys.executable, "-c", _TOY, *argv], capture_output=True, text=True)
    return " ".join((run.stdout + run.stderr).split())


def test_a_dialect_registered_by_one_line_is_a_command_and_a_kind_rewrite_reads():
    assert "toy corrected toy program" in _toy("--help")
    text = _toy("toy", "--help")
    assert "Write a toy program." in text and "the toy program to write" in text
    assert "a copy of templates/ or of its toy/ folder" in text
    text = _toy("rewrite", "--help")
    assert "Toy Robot Language: .toy .tyy" in text and "Toy: its own paragraph." in text
    assert "Toy Robot Language programs: --toy-frame N the toy's frame number" in text
    assert "unknown program type '.pdl': known are" in _toy(
        "rewrite", "x.pdl", "--cell", "c", "-o", "o"
    )
    assert "Toy Robot Language .toy .tyy" in _toy("rewrite", "x.pdl", "--cell", "c", "-o", "o")


def _imported_commands(*argv: str) -> set[str]:
    code = (
        "import sys\n"
        "from accugrid.app.cli import main\n"
        "try:\n"
        f"    main({list(argv)!r})\n"
        "except SystemExit:\n"
        "    pass\n"
        "names = [m for m in sys.modules if m.startswith('accugrid.app.commands.')]\n"
        "print('IMPORTED', *names)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    (line,) = [line for line in out.splitlines() if line.startswith("IMPORTED")]
    return set(line.split()[1:])


def test_help_imports_no_command_and_a_command_imports_only_itself():
    assert _imported_commands("--help") == set()
    assert _imported_commands("correct", "--help") == {"accugrid.app.commands.correct"}
