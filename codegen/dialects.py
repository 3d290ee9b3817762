"""The program dialects accugrid reads and writes, by name and file suffix.

A dialect is a unit: ``codegen/<name>/`` (emit, parse, rewrite, and section: its record of
the cell file, ``cell.dialects[name]``), ``templates/<name>/`` and a command. Adding one (ABB
RAPID, say) is one more registry entry here. A file whose suffix no
dialect claims is refused instead of being guessed.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from accugrid.kinematics.errors import InputError

__all__ = ["DIALECTS", "Dialect", "dialect_of"]


@dataclass(frozen=True)
class Dialect:
    """name (the ``codegen`` and ``templates`` folder), what it is, and its file suffixes."""

    name: str
    title: str
    suffixes: tuple[str, ...]


DIALECTS = {
    "krl": Dialect("krl", "KUKA KRL", (".src", ".dat", ".sub")),
    "gcode": Dialect(
        "gcode",
        "RS274NGC / ISO G-code",
        (".ngc", ".nc", ".gcode", ".gc", ".cnc", ".tap", ".iso", ".mpf", ".spf", ".eia"),
    ),
}


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
