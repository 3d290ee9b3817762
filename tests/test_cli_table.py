"""The CLI's static command table: complete, and only the running command is imported."""

from __future__ import annotations

import importlib
import pkgutil
import subprocess
import sys

from accugrid.app import commands
from accugrid.app.commands import COMMANDS


def test_table_lists_every_command_module_under_its_name():
    modules = {m.name for m in pkgutil.iter_modules(commands.__path__)}
    assert {module for module, _ in COMMANDS.values()} == modules
    for name, (module, help_text) in COMMANDS.items():
        loaded = importlib.import_module(f"accugrid.app.commands.{module}")
        assert loaded.NAME == name and help_text
        assert callable(loaded.add_arguments) and callable(loaded.run)


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
