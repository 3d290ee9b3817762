"""The program dialects accugrid reads and writes, by name and file suffix: the one registry.

A dialect is a plug-in (``codegen.plugin.DialectPlugin``): the folder ``codegen/<name>/`` (its
``plugin.py`` with ``PLUGIN``, emitter, reader and rewrite, cell section), ``templates/<name>/``
and a command. It is registered here by one line naming its ``plugin`` module; nothing else
branches on its name. A file whose suffix no dialect claims is refused instead of being guessed.
The library names a dialect's folder defines (its plug-in's ``exports``, ``EXPORTS``) are
resolved here, so ``accugrid.codegen`` lists them without naming a dialect's module.
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
    from accugrid.kinematics.model import RobotModel

__all__ = [
    "DIALECTS",
    "EXPORTS",
    "Dialect",
    "check_serves",
    "dialect_of",
    "measuring",
    "plugin_of",
    "programs_text",
]


@dataclass(frozen=True)
class Dialect:
    """name (the ``codegen`` and ``templates`` folder), what it is, its file suffixes, the
    module holding its ``PLUGIN`` and the library names it exports."""

    name: str
    title: str
    suffixes: tuple[str, ...]
    plugin: str
    exports: tuple[str, ...] = ()

    @classmethod
    def of_plugin(cls, module: str) -> Dialect:
        """The entry of the plug-in in ``module`` (a light module: its name, title, suffixes and
        exports are read here, at start-up)."""
        plugin = importlib.import_module(module).PLUGIN
        return cls(plugin.name, plugin.title, tuple(plugin.suffixes), module, plugin.exports)


DIALECTS = {
    d.name: d
    for d in map(
        Dialect.of_plugin,
        (
            "accugrid.codegen.krl.plugin",
            "accugrid.codegen.gcode.plugin",
            "accugrid.codegen.rapid.plugin",
            "accugrid.codegen.fanuc.plugin",
        ),
    )
}
EXPORTS = tuple(name for dialect in DIALECTS.values() for name in dialect.exports)
"""The library names the dialects' plug-ins export (``accugrid.codegen`` lists them)."""


def __getattr__(name: str) -> object:
    """The library name ``name`` some dialect's plug-in exports, from that dialect's ``emit``
    module (PEP 562)."""
    for dialect in DIALECTS.values():
        if name in dialect.exports:
            folder = dialect.plugin.rpartition(".")[0]
            return getattr(importlib.import_module(f"{folder}.emit"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def plugin_of(name: str) -> DialectPlugin:
    """The plug-in of dialect ``name``."""
    return importlib.import_module(DIALECTS[name].plugin).PLUGIN


def programs_text() -> str:
    """The programs accugrid reads, each dialect's title and suffixes ("KUKA KRL .src .dat
    .sub; ...")."""
    return "; ".join(f"{d.title} {' '.join(d.suffixes)}" for d in DIALECTS.values())


def measuring() -> list[str]:
    """The names of the dialects that write laser-tracker measurement programs
    (``DialectPlugin.measures``), in the registry's order."""
    return [name for name in DIALECTS if plugin_of(name).measures]


def dialect_of(path: str | os.PathLike[str]) -> str:
    """The name of the dialect whose suffixes include ``path``'s (case-insensitive); InputError
    naming the known suffixes otherwise."""
    suffix = Path(path).suffix.lower()
    for dialect in DIALECTS.values():
        if suffix in dialect.suffixes:
            return dialect.name
    raise InputError(
        f"unknown program type {suffix or '(no suffix)'!r}: known are {programs_text()}",
        os.fspath(path),
    )


def check_serves(name: str, robot: RobotModel, where: str | os.PathLike[str] = "") -> None:
    """InputError (at ``where``, the file naming the robot) unless dialect ``name``'s plug-in
    serves ``robot`` (``DialectPlugin.serves``), naming the robot, its controller and the
    commands whose programs drive it."""
    if plugin_of(name).serves(robot):
        return
    others = [d for d in DIALECTS.values() if plugin_of(d.name).serves(robot)]
    commands = " or ".join(f"accugrid {d.name} ({d.title})" for d in others)
    write = "writes" if len(others) == 1 else "write"
    raise InputError(
        f"robot {robot.name} has a {robot.controller.upper()} controller, which "
        f"{DIALECTS[name].title} programs do not drive: "
        + (f"{commands} {write} its programs" if others else "no dialect writes its programs"),
        os.fspath(where) if where else None,
    )
