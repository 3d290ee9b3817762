"""The program dialects accugrid reads and writes, by name and file suffix.

A dialect is a unit: ``codegen/<name>/`` (emit, parse, rewrite, and section: its record of
the cell file, ``cell.dialects[name]``), ``templates/<name>/`` and a command. A dialect written
as a plug-in (``codegen.plugin.DialectPlugin``, e.g. ABB RAPID) names its ``plugin`` module here
and nothing else branches on its name: the rewrite job and the header go through the plug-in.
A file whose suffix no dialect claims is refused instead of being guessed.
"""

from __future__ import annotations

import importlib
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from accugrid.infra.errors import InputError

if TYPE_CHECKING:
    from accugrid.codegen.plugin import DialectPlugin

__all__ = ["DIALECTS", "Dialect", "dialect_of", "plugin_of"]


@dataclass(frozen=True)
class Dialect:
    """name (the ``codegen`` and ``templates`` folder), what it is, and its file suffixes."""

    name: str
    title: str
    suffixes: tuple[str, ...]
    plugin: str | None = None  # module holding PLUGIN (a DialectPlugin)

    @classmethod
    def of_plugin(cls, module: str) -> Dialect:
        """The entry of the plug-in in ``module`` (a light module: its name, title and suffixes
        are read here, at start-up)."""
        plugin = importlib.import_module(module).PLUGIN
        return cls(plugin.name, plugin.title, tuple(plugin.suffixes), module)


DIALECTS = {
    "krl": Dialect("krl", "KUKA KRL", (".src", ".dat", ".sub")),
    "gcode": Dialect(
        "gcode",
        "RS274NGC / ISO G-code",
        (".ngc", ".nc", ".gcode", ".gc", ".cnc", ".tap", ".iso", ".mpf", ".spf", ".eia"),
    ),
    "rapid": Dialect.of_plugin("accugrid.codegen.rapid.plugin"),
}


def plugin_of(name: str) -> DialectPlugin | None:
    """The plug-in of dialect ``name``, None for a dialect not yet written as one."""
    module = DIALECTS[name].plugin
    return None if module is None else importlib.import_module(module).PLUGIN


def dialect_of(path: str | os.PathLike[str]) -> str:
    """The name of the dialect whose suffixes include ``path``'s (case-insensitive); InputError
    naming the known suffixes otherwise."""
    suffix = Path(path).suffix.lower()
    for dialect in DIALECTS.values():
        if suffix in dialect.suffixes:
            return dialect.name
    known = "; ".join(f"{d.title} {' '.join(d.suffixes)}" for d in DIALECTS.values())
    raise InputError(
        f"unknown program type {suffix or '(no suffix)'!r}: known are {known}", os.fspath(path)
    )
