"""Reading the CSV files of DESIGN.md with errors that name file, line and column.

Format: UTF-8 (a BOM is tolerated), a header row, comma-separated, ``.`` decimal point; lines whose
first field starts with ``#`` are comments; blank lines are skipped; column names are
case-insensitive. Quoted fields may hold commas and newlines (they are data, never syntax).
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from accugrid.kinematics.errors import InputError


@dataclass
class Table:
    """A parsed CSV: header names as written, raw cells and the file line of each row."""

    path: str
    header: list[str]
    rows: list[list[str]]
    lines: list[int] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._index = {name.strip().lower(): i for i, name in enumerate(self.header)}

    def __len__(self) -> int:
        return len(self.rows)

    def has(self, name: str) -> bool:
        return name.lower() in self._index

    def index(self, name: str) -> int:
        """0-based position of a column (case-insensitive); InputError if absent."""
        try:
            return self._index[name.lower()]
        except KeyError:
            raise InputError(
                f"missing column '{name}' (have: {', '.join(self.header)})", self.path, 1
            ) from None

    def require(self, names: Iterable[str]) -> None:
        """Raise one InputError listing every required column that is missing."""
        missing = [n for n in names if not self.has(n)]
        if missing:
            raise InputError(
                f"missing column(s) {', '.join(missing)} (have: {', '.join(self.header)})",
                self.path,
                1,
            )

    def text(self, name: str) -> list[str]:
        """The raw cells of one column, as strings."""
        i = self.index(name)
        return [row[i] for row in self.rows]

    def floats(self, names: Sequence[str], allow_empty: bool = False) -> np.ndarray:
        """Columns as a float64 array (N, len(names)).

        A cell that is not a finite number raises InputError naming file, line and column; an
        empty cell is NaN when ``allow_empty`` and an error otherwise.
        """
        cols = [self.index(n) for n in names]
        try:  # fast path: every cell a finite number
            out = np.array([[row[i] for i in cols] for row in self.rows], dtype=float)
            out = out.reshape(len(self.rows), len(cols))
            if np.isfinite(out).all():
                return out
        except ValueError:
            pass
        # slow path: find the first bad cell and say where it is
        out = np.empty((len(self.rows), len(cols)))
        for r, row in enumerate(self.rows):
            for c, i in enumerate(cols):
                out[r, c] = self._number(row[i], r, i, allow_empty)
        return out

    def _number(self, cell: str, r: int, i: int, allow_empty: bool) -> float:
        text = cell.strip()
        if not text:
            if allow_empty:
                return math.nan
            raise InputError(
                f"empty cell in column '{self.header[i]}'", self.path, self.lines[r], i + 1
            )
        try:
            value = float(text)
        except ValueError:
            raise InputError(
                f"'{_shorten(text)}' in column '{self.header[i]}' is not a number",
                self.path,
                self.lines[r],
                i + 1,
            ) from None
        if not math.isfinite(value):
            raise InputError(
                f"'{_shorten(text)}' in column '{self.header[i]}' is not a finite number",
                self.path,
                self.lines[r],
                i + 1,
            )
        return value

    def where(self, r: int, name: str | None = None) -> tuple[str, int, int | None]:
        """(path, line, column) of row r (0-based), for InputError(…, *table.where(r, name))."""
        return self.path, self.lines[r], None if name is None else self.index(name) + 1


def _shorten(text: str, limit: int = 40) -> str:
    text = text.replace("\n", "\\n").replace("\r", "\\r")
    return text if len(text) <= limit else text[: limit - 3] + "..."


def read_text(path: str | os.PathLike[str]) -> tuple[bytes, str]:
    """A file's bytes (for hashing) and its UTF-8 text (BOM dropped); InputError if unreadable."""
    try:
        raw = Path(path).read_bytes()
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror or exc}", path) from None
    try:
        return raw, raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise InputError("not UTF-8 text", path, line) from None


def read_table(path: str | os.PathLike[str]) -> Table:
    """Read a CSV file into a Table; InputError for unreadable, empty, ragged or non-UTF-8 files."""
    path = os.fspath(path)
    return parse_table(read_text(path)[1], path)


def parse_table(text: str, path: str = "<string>") -> Table:
    """Parse CSV text (see module docstring); ``path`` is used in error messages only."""
    reader = csv.reader(text.splitlines(keepends=True), strict=True)
    header: list[str] | None = None
    rows: list[list[str]] = []
    lines: list[int] = []
    end_line = 0
    try:
        for record in reader:
            start_line, end_line = end_line + 1, reader.line_num
            if not record or all(not cell.strip() for cell in record):
                continue
            if record[0].lstrip().startswith("#"):
                continue
            if header is None:
                header = [cell.strip() for cell in record]
                _check_header(header, path, start_line)
                continue
            if len(record) != len(header):
                raise InputError(
                    f"{len(record)} fields, but the header has {len(header)}", path, start_line
                )
            rows.append(record)
            lines.append(start_line)
    except csv.Error as exc:
        raise InputError(f"malformed CSV: {exc}", path, reader.line_num) from None
    if header is None:
        raise InputError("no header row (the file is empty or only comments)", path)
    return Table(path, header, rows, lines)


def _check_header(header: list[str], path: str, line: int) -> None:
    seen: dict[str, int] = {}
    for i, name in enumerate(header):
        if not name:
            raise InputError("empty column name in the header", path, line, i + 1)
        key = name.lower()
        if key in seen:
            raise InputError(f"column '{name}' appears twice in the header", path, line, i + 1)
        seen[key] = i
