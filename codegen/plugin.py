"""The interface every program dialect implements as a plug-in (``DialectPlugin``).

A dialect is one folder ``codegen/<name>/`` whose ``plugin.py`` holds ``PLUGIN``, an object with
the members below, light to import (its emitter and reader are imported when first used);
``codegen.dialects.DIALECTS`` names the module (the one registry). The jobs go through the
plug-in only: ``app.job`` writes a new program (``targets``, ``plan``, ``render``),
``codegen.rewrite.rewrite`` corrects an existing one (``placement``, ``scan``, ``splice``),
``codegen.cell`` reads its cell section (``section_keys``, ``read_section``). Program text is
latin-1 decoded bytes (one character per byte, offsets are byte offsets), so a rewrite keeps any
encoding and line ending.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    import numpy as np

    from accugrid.codegen.cell import Cell
    from accugrid.codegen.cellfile import CellReader, SectionKeys
    from accugrid.codegen.program import Program
    from accugrid.codegen.rewrite import Options, ProgramContext, Scan

__all__ = ["DialectFolder", "DialectPlugin", "Rendered"]


@dataclass
class Rendered:
    """The files of a new program: ``files`` (path -> text, or text in pieces fetched as it is
    written), ``main`` (among them, renamed last, in order) and ``stale`` (files of an earlier
    job of the same name to remove)."""

    files: Mapping[Path, object]
    main: list[Path] = field(default_factory=list)
    stale: list[Path] = field(default_factory=list)


class DialectPlugin(Protocol):
    """What a dialect provides.

    - ``name``: its ``codegen`` and ``templates`` folder and command; ``title``: what it is;
      ``suffixes``: the file suffixes it reads and writes (lower case, with the dot);
      ``pair``: the suffixes of a program given as two files (what runs, then its data, e.g.
      a KRL ``.src`` and ``.dat``), None when one file is a program; ``joints``: its
      configuration words need every pose's joint angles (``Program.joints``).
    - ``section_keys()``, ``read_section(reader, robot_T_base)``: the YAML keys of its cell
      section and its record (``cell.dialects[name]``), InputError naming the key.
    - ``targets(cell, out)``: the files a new program into ``out`` writes that must not exist
      (without --force), refusing there an output it cannot name; ``plan(cell, holes, header,
      templates)``: run after reading and before the correction, refuses what it could not
      write (``header`` has as many lines as the job's); ``render(program, header, templates,
      out, plan)``: the files (``Rendered``), numbers through ``infra.textsafe`` only.
    - ``placement(cell, context)``: what places its positions in the robot frame (its record,
      from the cell and the command line's ``codegen.rewrite.ProgramContext``); ``scan(texts,
      opts, placement)``: the positions of existing programs (path -> text), as
      ``codegen.rewrite.Scan``; ``splice(scan, corrected, opts)``: the bytes of every program
      (path -> bytes) with the corrected robot-frame positions (M, 3) mm (NaN rows: not
      corrected) put back in place of the old numbers, nothing else changed, and the report
      rows of what it wrote.
    - ``add_header(text, lines)``: the program with the comment header inserted where its
      controller accepts comments.
    """

    name: str
    title: str
    suffixes: tuple[str, ...]
    pair: tuple[str, str] | None
    joints: bool

    def section_keys(self) -> SectionKeys: ...

    def read_section(self, reader: CellReader, robot_T_base: np.ndarray) -> object: ...

    def targets(self, cell: Cell, out: Path) -> list[Path]: ...

    def plan(
        self,
        cell: Cell,
        holes: int,
        header: list[str],
        templates: str | os.PathLike[str] | None,
    ) -> object: ...

    def render(
        self,
        program: Program,
        header: list[str],
        templates: str | os.PathLike[str] | None,
        out: Path,
        plan: object,
    ) -> Rendered: ...

    def placement(self, cell: Cell, context: ProgramContext) -> object: ...

    def scan(self, texts: dict[str, str], opts: Options, placement: object) -> Scan: ...

    def splice(
        self, scan: Scan, corrected: np.ndarray, opts: Options
    ) -> dict[str, bytes | bytearray]: ...

    def add_header(self, text: str, lines: list[str]) -> str: ...


class DialectFolder:
    """The members of ``DialectPlugin`` a dialect folder gives by its modules' names, imported
    when first used: ``section.py`` (``KEYS``, ``read_section``) and ``rewrite.py``
    (``scan_positions``, ``splice_positions``, ``add_header``). A plug-in derives from it and
    adds its name, suffixes, ``targets``, ``plan``, ``render`` and ``placement``."""

    name: str
    pair: tuple[str, str] | None = None
    joints: bool = False

    def _module(self, part: str):
        return importlib.import_module(f"accugrid.codegen.{self.name}.{part}")

    def section_keys(self) -> SectionKeys:
        return self._module("section").KEYS

    def read_section(self, reader: CellReader, robot_T_base: np.ndarray) -> object:
        return self._module("section").read_section(reader, robot_T_base)

    def plan(self, cell, holes, header, templates) -> object:
        return None  # nothing to refuse before the correction

    def scan(self, texts: dict[str, str], opts: Options, placement: object) -> Scan:
        return self._module("rewrite").scan_positions(texts, opts, placement)

    def splice(self, scan: Scan, corrected: np.ndarray, opts: Options) -> dict[str, bytes]:
        return self._module("rewrite").splice_positions(scan, corrected, opts)

    def add_header(self, text: str, lines: list[str]) -> str:
        return self._module("rewrite").add_header(text, lines)
