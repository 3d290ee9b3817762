"""Reading the CSV files of DESIGN.md with errors that name file, line and column.

Format: UTF-8 (a BOM is tolerated), a header row, comma-separated, ``.`` decimal point; lines end
with LF, CRLF or CR; lines whose first field starts with ``#`` are comments; blank lines are
skipped; column names are case-insensitive. Quoted fields may hold commas and line breaks (they
are data, never syntax). Numbers are ASCII decimals only (``parse_number``). Files are read by
the guarded reader (``kinematics.inputfile``: regular files, size limit).
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from accugrid.kinematics.errors import InputError
from accugrid.kinematics.inputfile import read_input_text

__all__ = ["Table", "decimals_of", "parse_number", "parse_table", "read_table"]

_DECIMAL = re.compile(
    r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|(?i:nan|inf|infinity))"
)  # nan and inf pass here to be refused as "not a finite number"
_NOT_DECIMAL_CHAR = re.compile(r"[_nNiI\x1c-\x1f]")  # what float() takes beyond ASCII decimals
_BLANKS = " \t\n\r\x0b\x0c"  # around a number: ASCII blanks only (float() takes more)


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
        """Columns as a float64 array (N, len(names)), each column converted in one pass.

        Cells must be ASCII decimal numbers (``parse_number``). A cell that is not a finite number
        raises InputError naming file, line and column; an empty cell is NaN when
        ``allow_empty`` and an error otherwise.
        """
        cols = [self.index(n) for n in names]
        out = np.empty((len(self.rows), len(cols)))
        for c, i in enumerate(cols):
            cells = [row[i] for row in self.rows]
            column = _fast_column(cells, allow_empty)
            if column is None:  # slow path: find the first bad cell and say where it is
                column = [self._number(cell, r, i, allow_empty) for r, cell in enumerate(cells)]
            out[:, c] = column
        return out

    def _number(self, cell: str, r: int, i: int, allow_empty: bool) -> float:
        if allow_empty and not cell.strip(_BLANKS):
            return math.nan
        try:
            return parse_number(cell, f"in column '{self.header[i]}'")
        except ValueError as exc:
            raise InputError(str(exc), self.path, self.lines[r], i + 1) from None

    def decimals(self, names: Sequence[str]) -> np.ndarray:
        """Digits after the decimal point of each cell as written (N, len(names)) int."""
        return np.array(
            [[decimals_of(row[i]) for i in map(self.index, names)] for row in self.rows], dtype=int
        ).reshape(len(self.rows), len(names))

    def check_bounds(
        self, values: np.ndarray, names: Sequence[str], limit: float, unit: str
    ) -> None:
        """InputError at the first cell of ``values`` (N, len(names)), read from the columns
        ``names``, beyond +-``limit`` (in ``unit``)."""
        rows, cols = np.nonzero(np.abs(values) > limit)
        if rows.size:
            r, name = int(rows[0]), names[int(cols[0])]
            raise InputError(
                f"{name} {values[r, cols[0]]:g} {unit} is beyond the limit of {limit:g} {unit}",
                *self.where(r, name),
            )

    def where(self, r: int, name: str | None = None) -> tuple[str, int, int | None]:
        """(path, line, column) of row r (0-based), for InputError(…, *table.where(r, name))."""
        return self.path, self.lines[r], None if name is None else self.index(name) + 1


def decimals_of(text: str) -> int:
    """Digits after the decimal point in a number literal as written (0 without a point)."""
    if "e" in text or "E" in text:
        text = text.replace("E", "e").split("e")[0]
    point = text.find(".")
    return 0 if point < 0 else len(text) - point - 1


def _shorten(text: str, limit: int = 40) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."


def parse_number(cell: str, what: str = "") -> float:
    """One CSV cell as a finite float: an ASCII decimal number (``-12.5``, ``.5``, ``1e-3``),
    surrounding blanks allowed. ValueError (message naming the cell) for anything else: empty,
    ``1_000``, ``nan``, ``inf``, non-ASCII digits, or a value beyond the float range."""
    text = cell.strip(_BLANKS)
    where = f" {what}" if what else ""
    if not text:
        raise ValueError(f"empty cell{where}")
    if not _DECIMAL.fullmatch(text):
        raise ValueError(f"'{_shorten(text)}'{where} is not a number (ASCII decimal)")
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"'{_shorten(text)}'{where} is not a finite number")
    return value


def _fast_column(cells: list[str], allow_empty: bool) -> np.ndarray | None:
    """The cells as floats when all are valid for ``parse_number`` (or empty, with
    ``allow_empty``: NaN); None when any is not (the caller then locates it)."""
    joined = " ".join(cells)
    if not joined.isascii() or _NOT_DECIMAL_CHAR.search(joined):
        return None  # float() would take 1_000, nan, inf or non-ASCII digits
    if allow_empty:
        cells = [cell if cell.strip(_BLANKS) else "nan" for cell in cells]
    try:
        column = np.fromiter(map(float, cells), dtype=float, count=len(cells))
    except ValueError:
        return None
    return None if np.isinf(column).any() else column


def read_table(path: str | os.PathLike[str]) -> Table:
    """Read a CSV file into a Table; InputError for unreadable, empty, ragged or non-UTF-8 files,
    and for anything the guarded reader refuses (``kinematics.inputfile``)."""
    path = os.fspath(path)
    return parse_table(read_input_text(path)[1], path)


def parse_table(text: str, path: str = "<string>") -> Table:
    """Parse CSV text (see module docstring); ``path`` is used in error messages only."""
    # Lines end only at CR, LF or CRLF: VT, FF, NEL and U+2028 inside a field are data.
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    header: list[str] | None = None
    rows: list[list[str]] = []
    lines: list[int] = []
    end_line = 0
    try:
        for record in reader:
            start_line, end_line = end_line + 1, reader.line_num
            if not "".join(record).strip() or record[0].lstrip()[:1] == "#":
                continue  # blank or comment
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
