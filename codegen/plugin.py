"""The interface a program dialect implements as a plug-in (``DialectPlugin``).

A plug-in is one folder ``codegen/<name>/`` whose ``plugin.py`` holds ``PLUGIN``, an object with
the members below; ``codegen.dialects.DIALECTS`` names the folder (the one registry). The cell
file reads the plug-in's section through ``<name>/section.py`` (``KEYS``, ``read_section``), as
for every dialect. Text is latin-1 decoded bytes (one character per byte, offsets are byte
offsets), so a rewrite keeps any encoding and line ending.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np

if TYPE_CHECKING:
    from accugrid.codegen.program import Program
    from accugrid.codegen.rewrite import Options, Result

__all__ = ["DialectPlugin", "Positions"]


class Positions(Protocol):
    """The Cartesian positions a scan found in a program, as columns: ``xyz`` (N, 3) mm as
    written, in the frame of ``frame`` (N,) (an index into the dialect's frames), ``line``
    (N,) 1-based, ``name`` (N,) str, and ``reason`` (N,) str ("" where the position can be
    placed, else why it is left as it is)."""

    xyz: np.ndarray
    line: np.ndarray
    name: list[str]
    reason: list[str]


class DialectPlugin(Protocol):
    """What a dialect provides: ``name`` (its ``codegen`` and ``templates`` folder), ``title``,
    the file ``suffixes`` it reads and writes (lower case, with the dot) and:

    - ``render(program, header, templates, out)``: the files (path -> text) of a neutral
      ``Program`` written to ``out``, numbers through ``textsafe`` only;
    - ``scan(path, text, section)``: the positions of an existing program (``Positions``);
      ``section`` is the dialect's record of the cell (``cell.dialects[name]``);
    - ``splice(text, positions, new_xyz, opts)``: the program's bytes with the corrected
      numbers (N, 3) mm (NaN rows: unchanged) put in place of the old ones, nothing else changed;
    - ``rewrite(texts, opts, section)``: scan, correct (``codegen.rewrite.correct_points``, the one
      correction every dialect uses) and splice every program of a rewrite job;
    - ``add_header(text, lines)``: the program with the comment header inserted where its
      controller accepts comments."""

    name: str
    title: str
    suffixes: tuple[str, ...]

    def render(
        self,
        program: Program,
        header: list[str],
        templates: str | os.PathLike[str] | None,
        out: Path,
    ) -> Mapping[Path, str]: ...

    def scan(self, path: str, text: str, section: object) -> Positions: ...

    def splice(
        self, text: str, positions: Positions, new_xyz: np.ndarray, opts: Options
    ) -> bytearray: ...

    def rewrite(self, texts: dict[str, str], opts: Options, section: object) -> Result: ...

    def add_header(self, text: str, lines: list[str]) -> str: ...
