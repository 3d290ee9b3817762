"""Reading the CSV files of DESIGN.md with errors that name file, line and column.

Format: UTF-8 (a BOM is tolerated), a header row, comma-separated, ``.`` decimal point; lines end
with LF, CRLF or CR; lines whose first field starts with ``#`` (or ``//``, as metrology software
writes its notes) are comments; blank lines are skipped; column names are case-insensitive.
Quoted fields may hold commas and line breaks (they are data, never syntax). Numbers are ASCII
decimals only (``parse_number``). Files are read by the guarded reader (``infra.inputfile``:
regular files, size limit).

Tracker exports as they come (``TableFormat``): the delimiter (comma, semicolon, tab) is taken
from the header row and the rows below it; a decimal comma is recognised with a semicolon or tab
delimiter; a trailing delimiter (an empty last column) is dropped; a column mapping renames the
file's columns to accugrid's; a header that names a unit (``x [m]``, ``Nominal X (in)``,
``a1_rad``) is read as the column it names in that unit; lengths in m or inch are converted to mm
as decimal text, exactly, angles in rad to degrees (``infra.units``). A file that cannot be
decided, or whose header names another unit than the one declared, is an InputError that says
what was found and which setting decides it. The CLI sets the format of a command with
``reading_as``; the comma, point, mm file without mapping takes the fast reader as before.
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
from collections.abc import Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from accugrid.infra.decimals import read_decimals, words_at
from accugrid.infra.errors import InputError
from accugrid.infra.inputfile import read_input_text
from accugrid.infra.units import (
    ANGLE_UNITS,
    LENGTH_UNITS,
    column_kind,
    header_unit,
    unit_kind,
    unit_spec,
)

if TYPE_CHECKING:
    from accugrid.infra.yamlfile import YamlDoc

__all__ = [
    "DECIMALS",
    "DELIMITERS",
    "Table",
    "FORMAT_KEYS",
    "TableFormat",
    "decimals_of",
    "declared_or",
    "parse_number",
    "parse_table",
    "read_table",
    "read_table_format",
    "reading_as",
    "table_format_of",
]

DELIMITERS = {"comma": ",", "semicolon": ";", "tab": "\t"}
DECIMALS = {"point": ".", "comma": ","}
_COMMENT = ("#", "//")

_DECIMAL = re.compile(
    r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|(?i:nan|inf|infinity))"
)  # nan and inf pass here to be refused as "not a finite number"
_NOT_DECIMAL_CHAR = re.compile(r"[_nNiI\x1c-\x1f]")  # what float() takes beyond ASCII decimals
_BLANKS = " \t\n\r\x0b\x0c"  # around a number: ASCII blanks only (float() takes more)
_CHUNK = 1 << 16  # rows cut from the byte buffer at a time (bounds the temporaries)
# bytes a number cell of the fast reader may hold: ASCII digits, sign, point, exponent, blanks
_NUMBER_BYTE = np.zeros(256, dtype=bool)
_NUMBER_BYTE[np.frombuffer(b"0123456789+-.eE" + _BLANKS.encode(), dtype=np.uint8)] = True
# the first m bytes of a little-endian word kept: by m = 0..8
_FIRST_BYTES = np.array([(1 << (8 * m)) - 1 for m in range(9)], np.uint64)
_BLANK_BYTE = np.zeros(256, dtype=bool)
_BLANK_BYTE[np.frombuffer(_BLANKS.encode(), dtype=np.uint8)] = True
# what a data line of the fast reader may not start with (a blank or comment line starts so)
_ODD_START = np.zeros(256, dtype=bool)
_ODD_START[np.frombuffer(b"#,\n" + _BLANKS.encode() + bytes(range(0x1C, 0x20)), np.uint8)] = True


@dataclass(frozen=True)
class TableFormat:
    """How a CSV file is written where it differs from DESIGN.md's.

    ``delimiter`` ``,``, ``;`` or tab (used where the header holds it, else found from the file);
    ``decimal`` ``.`` or ``,`` (None: found; a comma only beside another delimiter); ``columns``:
    accugrid's column name -> the file's header name, applied to each file that has one of those
    names (the export; a file without any is read as it is); ``units``: the declared units
    of the export's length and angle columns (of every file without ``columns``), as
    ``infra.units.unit_spec`` reads them (``"m"``, ``"m,rad,x_meas=mm"``; held as {column or
    kind: unit}), converted to mm and deg on read; a column not declared takes the unit its
    header names, else mm or deg.
    """

    delimiter: str | None = None
    decimal: str | None = None
    columns: Mapping[str, str] | None = None
    units: str | Mapping[str, str] | None = None

    def __post_init__(self) -> None:
        if self.delimiter not in (None, *DELIMITERS.values()):
            raise ValueError(f"delimiter must be one of , ; or tab, got {self.delimiter!r}")
        if self.decimal not in (None, *DECIMALS.values()):
            raise ValueError(f"decimal must be '.' or ',', got {self.decimal!r}")
        object.__setattr__(self, "units", unit_spec(self.units))
        if self.delimiter == "," and self.decimal == ",":
            raise ValueError("a decimal comma needs a semicolon or tab delimiter")
        names = {k.strip().lower(): v.strip() for k, v in (self.columns or {}).items()}
        if len(names) != len(self.columns or {}) or "" in names or "" in names.values():
            raise ValueError(f"column mapping must pair distinct names: {self.columns!r}")
        sources = [v.lower() for v in names.values()]
        if len(set(sources)) != len(sources):
            raise ValueError(f"column mapping reads one file column twice: {self.columns!r}")
        object.__setattr__(self, "columns", names)

    def mapping_text(self) -> str:
        return ",".join(f"{k}={v}" for k, v in self.columns.items())

    def declared_unit(self, name: str) -> str | None:
        """The unit declared for accugrid column ``name`` (its own, else its kind's), or None."""
        kind = column_kind(name)
        return self.units.get(name) or (self.units.get(kind) if kind else None)


_PLAIN = TableFormat()
FORMAT_KEYS = ("columns", "units", "delimiter", "decimal")  # of a format file, a cell's tracker:


def table_format_of(doc: YamlDoc, *keys: Any) -> TableFormat:
    """The TableFormat a YAML mapping at ``keys`` of ``doc`` says (a format file's top level, a
    cell's ``tracker:``): ``columns`` {NAME: HEADER}, ``units`` (as ``unit_spec`` reads them:
    text or a mapping), ``delimiter`` comma, semicolon or tab, ``decimal`` point or comma.
    InputError at the key that is wrong."""
    doc.check_keys(dict.fromkeys(FORMAT_KEYS), *keys)

    def fail(message: str, *inner: Any) -> InputError:
        return doc.error(f"{doc.keyname(*keys, *inner)} {message}", *keys, *inner)

    def word(key: str, words: Mapping[str, str]) -> str | None:
        value = doc.get(*keys, key, default=None)
        if value is not None and value not in words:
            raise fail(f"must be {' or '.join(words)}, got {value!r}", key)
        return None if value is None else words[value]

    columns = doc.get(*keys, "columns", default=None) or {}
    if not isinstance(columns, dict):
        raise fail("must be a mapping of accugrid names to the file's column names", "columns")
    for name, header in columns.items():
        if not isinstance(header, str) or not header.strip():
            raise fail("must be the file's column name", "columns", name)
    units = doc.get(*keys, "units", default=None)
    try:
        if not isinstance(units, str | dict | None):
            raise ValueError(f"must be text such as m,rad or a mapping, got {units!r}")
        unit_spec(units)
    except ValueError as exc:
        raise fail(f": {exc}", "units") from None
    try:
        return TableFormat(
            delimiter=word("delimiter", DELIMITERS),
            decimal=word("decimal", DECIMALS),
            columns={str(name): header for name, header in columns.items()},
            units=units,
        )
    except ValueError as exc:  # two names for one column, a decimal comma with commas
        raise fail(f": {exc}") from None


def read_table_format(path: str | os.PathLike[str]) -> TableFormat:
    """A format file (YAML, ``FORMAT_KEYS`` at the top level): how a tracker's exports are
    written, said once; InputError at its line."""
    from accugrid.infra.yamlfile import load_yaml  # only when a format file is given

    return table_format_of(load_yaml(path))


_FORMAT: ContextVar[TableFormat | None] = ContextVar("table_format", default=None)


@contextmanager
def reading_as(fmt: TableFormat | None) -> Iterator[None]:
    """Within the block, ``read_table``/``parse_table`` calls without a format read with
    ``fmt`` (None: the default, DESIGN.md's format with the delimiter and decimal found)."""
    token = _FORMAT.set(fmt)
    try:
        yield
    finally:
        _FORMAT.reset(token)


def declared_or(fallback: TableFormat | None) -> TableFormat | None:
    """The format ``reading_as`` set when it declares anything (the command line's), else
    ``fallback`` (e.g. the cell file's tracker section)."""
    current = _FORMAT.get()
    return current if current is not None and current != _PLAIN else fallback


class Table:
    """A parsed CSV: header names as written, the cells and the file line of each row.

    Cells live either in ``rows`` (lists of strings, from the csv module) or, for the common file
    (ASCII, no quotes), in one byte buffer with the offsets of its separators (``_Cells``), from
    which a column is cut only when asked for; ``rows`` is then built on first use."""

    def __init__(
        self,
        path: str,
        header: list[str],
        rows: list[list[str]] | None = None,
        lines: Sequence[int] | None = None,
        cells: _Cells | None = None,
        header_line: int = 1,
    ) -> None:
        self.path = path
        self.header = header
        self._rows = rows
        self._cells = cells
        self.lines = _Lines([] if lines is None else lines)
        self.header_line = header_line
        self.delimiter = ","  # the file's, as parse_table found it
        self.decimal = "."  # the file's decimal mark, as parse_table found it
        self.unmapped = ""  # a column mapping that named none of this file's columns
        self.named: dict[str, tuple[str, str]] = {}  # column -> (header as written, its unit)
        self.units: dict[str, str] = {}  # column -> the file's unit where declared or named
        self.printed: dict[int, np.ndarray] = {}  # column index -> decimals as printed, in deg
        self._index = {name.strip().lower(): i for i, name in enumerate(self.header)}

    @property
    def rows(self) -> list[list[str]]:
        """The cells of every row, as strings."""
        if self._rows is None:
            self._rows = self._cells.rows() if self._cells is not None else []
        return self._rows

    def __len__(self) -> int:
        return len(self.lines)

    def __repr__(self) -> str:
        return f"Table({self.path!r}, {len(self)} rows, columns {', '.join(self.header)})"

    def row_bytes(self, lo: int, hi: int) -> np.ndarray | None:
        """The text of rows lo..hi-1 as read (ASCII, cells joined by commas, no cell needing
        quotes: what ``csv.writer`` writes for each row), one per row of an (hi - lo, width)
        uint8 array NUL-padded on the right, when the fast reader took the file; else None."""
        if self._cells is None:
            return None
        width, bounds = self._cells.width, self._cells.bounds
        start = bounds[lo * width : hi * width : width] + 1
        end = bounds[(lo + 1) * width : (hi + 1) * width : width]
        cells = self._cells.cut(start, end)
        return cells.view(np.uint8).reshape(hi - lo, cells.itemsize)

    def has(self, name: str) -> bool:
        return name.lower() in self._index

    def index(self, name: str) -> int:
        """0-based position of a column (case-insensitive); InputError if absent."""
        try:
            return self._index[name.lower()]
        except KeyError:
            raise InputError(
                f"missing column '{name}' (have: {', '.join(self.header)}){self.unmapped}",
                self.path,
                self.header_line,
            ) from None

    def require(self, names: Iterable[str]) -> None:
        """Raise one InputError listing every required column that is missing."""
        missing = [n for n in names if not self.has(n)]
        if missing:
            raise InputError(
                f"missing column(s) {', '.join(missing)} (have: {', '.join(self.header)})"
                + self.unmapped,
                self.path,
                self.header_line,
            )

    def text(self, name: str) -> list[str]:
        """The raw cells of one column, as strings."""
        return self._column(self.index(name))

    def _column(self, i: int) -> list[str]:
        if self._rows is None and self._cells is not None:
            return self._cells.text(i)
        return [row[i] for row in self.rows]

    def floats(self, names: Sequence[str], allow_empty: bool = False) -> np.ndarray:
        """Columns as a float64 array (N, len(names)), each column converted in one pass.

        Cells must be ASCII decimal numbers (``parse_number``). A cell that is not a finite number
        raises InputError naming file, line and column; an empty cell is NaN when
        ``allow_empty`` and an error otherwise.
        """
        cols = [self.index(n) for n in names]
        out = np.empty((len(self), len(cols)))
        for c, i in enumerate(cols):
            column = None
            if self._cells is not None:
                column = self._cells.floats(i, allow_empty)
            if column is None:
                cells = self._column(i)
                column = _fast_column(cells, allow_empty)
            if column is None:  # slow path: find the first bad cell and say where it is
                cells = self._column(i)
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
        """Digits after the decimal point of each cell as written (N, len(names)) float: the
        round-off of the printed number is half a unit of that digit in mm or deg (a column
        converted from rad counts log10(180/pi) digits fewer than it printed)."""
        columns = [
            self.printed.get(i, list(map(decimals_of, self._column(i))))
            for i in map(self.index, names)
        ]
        return np.array(columns, dtype=float).reshape(len(names), len(self)).T

    def check_bounds(
        self, values: np.ndarray, names: Sequence[str], limit: float, unit: str, hint: str = ""
    ) -> None:
        """InputError at the first cell of ``values`` (N, len(names)), read from the columns
        ``names``, beyond +-``limit`` (in ``unit``); ``hint`` ends the message."""
        rows, cols = np.nonzero(np.abs(values) > limit)
        if rows.size:
            r, name = int(rows[0]), names[int(cols[0])]
            raise InputError(
                f"{name} {values[r, cols[0]]:g} {unit} is beyond the limit of {limit:g} {unit}"
                + hint,
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


class _Lines(Sequence):
    """The file line of each row (a list, or a range for a file without comment rows: no
    million-int list); equal to a list of the same lines."""

    def __init__(self, lines: Sequence[int]) -> None:
        self._lines = lines

    def __len__(self) -> int:
        return len(self._lines)

    def __iter__(self):
        return iter(self._lines)

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        return np.asarray(self._lines, dtype=dtype)

    def __getitem__(self, r):
        found = self._lines[r]
        return list(found) if isinstance(r, slice) else found

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Sequence) and list(self._lines) == list(other)

    def __repr__(self) -> str:
        return repr(list(self._lines))


class _Cells:
    """The data rows of a simple CSV (ASCII, no quotes) as one byte buffer and the offsets of its
    separators: every row has ``width`` fields, field j of the buffer (row-major) spans
    ``data[bounds[j] + 1 : bounds[j + 1]]``. Columns are cut on demand, rows in chunks."""

    def __init__(self, data: bytes, width: int) -> None:
        self.data = data
        self.width = width
        self.buf = buf = np.frombuffer(data, dtype=np.uint8)
        is_sep = buf == 44
        is_sep |= buf == 10
        seps = np.flatnonzero(is_sep)
        self.bounds = np.empty(len(seps) + 2, np.int32 if len(data) < 2**31 - 1 else np.int64)
        self.bounds[0], self.bounds[1:-1], self.bounds[-1] = -1, seps, len(data)

    def rows_ok(self) -> bool:
        """Whether every line has ``width`` fields and starts like a data row."""
        buf = self.buf
        ends = self.bounds[self.width :: self.width]
        if len(self.bounds) - 1 != len(ends) * self.width or not (buf[ends[:-1]] == 10).all():
            return False
        starts = self.bounds[: -1 : self.width] + 1
        return not _ODD_START[buf[np.minimum(starts, len(buf) - 1)]].any() and bool(
            (ends > starts).all()
        )

    def __len__(self) -> int:
        return (len(self.bounds) - 1) // self.width

    def _span(self, i: int, lo: int, hi: int) -> tuple[np.ndarray, np.ndarray]:
        """Start and end offsets of column i's cells in rows lo..hi-1."""
        first, w = lo * self.width + i, self.width  # every width-th separator: strided views
        return self.bounds[first : hi * w + i : w] + 1, self.bounds[first + 1 : hi * w + i + 1 : w]

    def cut(self, start: np.ndarray, end: np.ndarray) -> np.ndarray:
        """The cells spanning ``data[start:end]`` as a fixed-width bytes array (NUL-padded; its
        width the longest cell's rounded up to whole 8-byte words): read a word (8 bytes) at a
        time, the bytes past each cell's end cleared."""
        size = end - start
        words = max(-(-int(size.max(initial=0)) // 8), 1)  # per cell
        if len(self.buf) < 8:
            return _byte_cut(self.buf, start, end, 8 * words)
        offset = 8 * np.arange(words, dtype=start.dtype)
        cut = words_at(self.buf, start[:, None] + offset)  # (n, words) uint64, little-endian
        cut &= _FIRST_BYTES[np.clip(size[:, None] - offset, 0, 8)]
        cut = cut.view(np.uint8).reshape(len(start), 8 * words)
        late = np.flatnonzero(start + 8 * words > len(self.buf))  # words past the buffer's end
        if late.size:
            tail = _byte_cut(self.buf, start[late], end[late], 8 * words)
            cut[late] = tail.view(np.uint8).reshape(late.size, -1)
        return cut.view(f"S{8 * words}").reshape(-1)

    def text(self, i: int) -> list[str]:
        if not len(self):
            return []
        chunks = range(0, len(self), _CHUNK)
        cuts = [self.cut(*self._span(i, lo, min(lo + _CHUNK, len(self)))) for lo in chunks]
        return b"\n".join(np.concatenate(cuts).tolist()).decode("ascii").split("\n")

    def rows(self) -> list[list[str]]:
        return [line.split(",") for line in self.data.decode("ascii").split("\n")]

    def floats(self, i: int, allow_empty: bool) -> np.ndarray | None:
        """Column i as floats when every cell is an ASCII decimal (``parse_number``; empty: NaN
        with ``allow_empty``); None when any is not (the caller then locates it)."""
        out = np.empty(len(self))
        for lo in range(0, len(self), _CHUNK):
            hi = min(lo + _CHUNK, len(self))
            start, end = self._span(i, lo, hi)
            values, _, done = read_decimals(self.buf, start, end)
            rest = np.flatnonzero(~done)  # exponents, blanks, long mantissas, empty, bad
            if rest.size:
                cells = self.cut(start[rest], end[rest])
                raw = cells.view(np.uint8).reshape(rest.size, -1)
                if not (_NUMBER_BYTE[raw] | (raw == 0)).all():
                    return None  # 1_000, nan, inf: the cell-by-cell path decides
                empty = (_BLANK_BYTE[raw] | (raw == 0)).all(axis=1)
                if empty.any():
                    if not allow_empty:
                        return None
                    values[rest[empty]] = np.nan
                    rest, cells = rest[~empty], cells[~empty]
                try:
                    values[rest] = cells.astype(float)
                except ValueError:
                    return None
                if np.isinf(values[rest]).any():
                    return None
            out[lo:hi] = values
        return out


def _byte_cut(buf: np.ndarray, start: np.ndarray, end: np.ndarray, width: int) -> np.ndarray:
    """``_Cells.cut`` byte by byte, ``width`` bytes per cell (for cells at the buffer's end)."""
    at = start[:, None] + np.arange(width, dtype=start.dtype)
    cut = buf.take(at, mode="clip")  # beyond the buffer: clipped, then cleared
    cut[at >= end[:, None]] = 0
    return cut.view(f"S{width}").reshape(-1)


def _parse_simple(text: str, path: str) -> Table | None:
    """The common file read fast: ASCII, no quotes, no NUL, lines ending in LF or CRLF, one
    header and then rows that each have as many fields (no blank or comment lines among them).
    None for anything else: ``parse_table``'s csv reader then reads (or refuses) it."""
    if not text.isascii() or '"' in text or "\x00" in text:
        return None
    if "\r" in text:
        if text.count("\r") != text.count("\r\n"):
            return None
        text = text.replace("\r\n", "\n")
    pos, line = 0, 0
    while True:  # comment and blank lines before the header
        end = text.find("\n", pos)
        first = text[pos:] if end < 0 else text[pos:end]
        line += 1
        if first.replace(",", "").strip() and not first.lstrip().startswith(_COMMENT):
            break
        if end < 0:
            return None
        pos = end + 1
    header = [cell.strip() for cell in first.split(",")]
    if not header[-1]:
        return None  # a trailing delimiter: the csv reader drops it
    _check_header(header, path, line)
    body = "" if end < 0 else text[end + 1 :].rstrip("\n")
    if not body:
        return Table(path, header, [], [], header_line=line)
    cells = _Cells(body.encode("ascii"), len(header))
    if not cells.rows_ok():
        return None
    lines = range(line + 1, line + 1 + len(cells))
    return Table(path, header, None, lines, cells, header_line=line)


def read_table(path: str | os.PathLike[str], fmt: TableFormat | None = None) -> Table:
    """Read a CSV file into a Table; InputError for unreadable, empty, ragged or non-UTF-8 files,
    and for anything the guarded reader refuses (``infra.inputfile``). ``fmt``: how the file
    is written (default: the one ``reading_as`` set, else found from the file)."""
    path = os.fspath(path)
    return parse_table(read_input_text(path)[1], path, fmt)


def parse_table(text: str, path: str = "<string>", fmt: TableFormat | None = None) -> Table:
    """Parse CSV text (see module docstring); ``path`` is used in error messages only."""
    fmt = fmt or _FORMAT.get() or _PLAIN
    delimiter = _delimiter_of(text, path, fmt.delimiter)
    if delimiter == ",":  # DESIGN.md's format: the fast reader first
        table = _parse_simple(text, path) or _parse_csv(text, path)
    else:
        table = _parse_csv(text, path, delimiter)
        table.delimiter = delimiter
        table.decimal = fmt.decimal or _decimal_of(table)  # a comma only beside another delimiter
        if table.decimal == ",":
            _decimal_points(table)
    _read_units(table, fmt if _name_columns(table, fmt) else _PLAIN)
    return table


def _records(text: str, delimiter: str, count: int) -> Iterator[tuple[int, list[str]]]:
    """(first line, fields) of up to ``count`` records that are not blank or comments."""
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=delimiter)
    end_line = 0
    try:
        for record in reader:
            start_line, end_line = end_line + 1, reader.line_num
            if "".join(record).strip() and not record[0].lstrip().startswith(_COMMENT):
                yield start_line, record
                count -= 1
                if not count:
                    return
    except csv.Error:
        return


def _header_line(text: str) -> tuple[int, str]:
    """(line number, text) of the first line that is neither blank nor a comment; (0, "")."""
    pos, number = 0, 0
    while pos <= len(text):
        end = text.find("\n", pos)
        line = text[pos:] if end < 0 else text[pos:end]
        number += 1
        if line.strip(_BLANKS + ",;") and not line.lstrip().startswith(_COMMENT):
            return number, line
        if end < 0:
            break
        pos = end + 1
    return 0, ""


def _delimiter_of(text: str, path: str, declared: str | None = None) -> str:
    """The delimiter of a file: ``declared`` when its header line holds it; else a comma unless
    the header line holds a semicolon or tab; then the one candidate that splits the header into
    several columns and the first rows below it into as many (or the only one that splits the
    header at all). InputError (at the header) naming what was found when none or several do."""
    number, line = _header_line(text)
    if declared and declared in line:
        return declared
    if ";" not in line and "\t" not in line:
        return ","
    head, end = text, -1
    for _ in range(number + 50):  # the header and up to 50 rows below it, whole lines
        end = text.find("\n", end + 1)
        if end < 0:
            break
    else:
        head = text[: end + 1]
    fits, splits, found = [], [], []
    for name, delimiter in DELIMITERS.items():
        records = list(_records(head, delimiter, 51))
        widths = sorted({len(fields) for _, fields in records})
        found.append(f"{name}: {len(records[0][1])} column(s) in the header, {widths} per row")
        if len(records[0][1]) > 1:
            splits.append(name)
            if len(widths) == 1:
                fits.append(name)
    if len(fits) == 1 or (not fits and len(splits) == 1):  # the reader then names a ragged row
        return DELIMITERS[(fits or splits)[0]]
    raise InputError(
        f"cannot tell the delimiter ({'; '.join(found)}): give --delimiter "
        + (" or ".join(fits) if fits else "comma, semicolon or tab"),
        path,
        number,
    )


_NUMBER_WITH = {
    sep: re.compile(
        rf"[{_BLANKS}]*[+-]?(?:[0-9]+\{sep}[0-9]*|\{sep}[0-9]+)(?:[eE][+-]?[0-9]+)?[{_BLANKS}]*"
    )
    for sep in ".,"
}


def _decimal_of(table: Table) -> str:
    """The decimal mark of a semicolon or tab file: a comma when some number is written with one
    and none with a point; a point otherwise. InputError at the first number of the second kind
    when both are found."""
    first: dict[str, tuple[int, int, str]] = {}
    for r, row in enumerate(table.rows):
        for i, cell in enumerate(row):
            for sep, pattern in _NUMBER_WITH.items():
                if sep not in first and pattern.fullmatch(cell):
                    first[sep] = (r, i, cell.strip(_BLANKS))
        if len(first) == 2:
            (r, i, cell), (r0, i0, cell0) = sorted(first.values())[::-1]
            raise InputError(
                f"numbers with a decimal point and with a decimal comma: '{_shorten(cell)}' here, "
                f"'{_shorten(cell0)}' on line {table.lines[r0]} column {i0 + 1}: give "
                "--decimal point or --decimal comma",
                table.path,
                table.lines[r],
                i + 1,
            )
    return "," if "," in first else "."


def _decimal_points(table: Table) -> None:
    """In place: a decimal comma made a point in every number written with one."""
    pattern = _NUMBER_WITH[","]
    for row in table.rows:
        for i, cell in enumerate(row):
            if "," in cell and pattern.fullmatch(cell):
                row[i] = cell.replace(",", ".")


def _name_columns(table: Table, fmt: TableFormat) -> bool:
    """Rename the file's columns to accugrid's: by ``fmt.columns`` (a mapped HEADER matches the
    header as written or without the unit it names) when the file has any of the mapped names,
    and a header that names a unit (``x [m]``) as the column it names; keep each column's
    header unit in ``table.named``. True when the file is the export ``fmt`` describes (it
    has a mapped name, or there is no mapping); InputError at the header for a mapped name it
    lacks while having others."""
    parsed = [header_unit(name) for name in table.header]
    table.named = {}
    wanted = {source.lower(): name for name, source in (fmt.columns or {}).items()}
    mapped = [
        wanted.get(name.strip().lower()) or wanted.get(bare.strip().lower())
        for name, (bare, _) in zip(table.header, parsed, strict=True)
    ]
    export = not wanted or any(mapped)
    if not export:
        table.unmapped = f"; the column mapping {fmt.mapping_text()} names none of them"
        mapped = [None] * len(mapped)
    for name, source in (fmt.columns or {}).items() if export else ():
        if name not in mapped:
            raise InputError(
                f"column mapping {name}={source}: no column '{source}' in the header "
                f"(have: {', '.join(table.header)})",
                table.path,
                table.header_line,
            )
    header = []
    for name, (bare, unit), target in zip(table.header, parsed, mapped, strict=True):
        if target is None and unit and column_kind(bare.strip().lower()):
            target = bare.strip()
        if target is not None and unit:
            table.named[target.lower()] = (name, unit)
        header.append(name if target is None else target)
    if header != table.header:
        _check_header(header, table.path, table.header_line)
        table.header = header
        table._index = {name.strip().lower(): i for i, name in enumerate(header)}
    return export


def _read_units(table: Table, fmt: TableFormat) -> None:
    """Convert the length and angle columns to mm and deg in place, each in its unit: the one
    ``fmt`` declares, else the one its header names (``table.named``), else mm or deg; record
    the units that are not (``table.units``). InputError at a header whose unit contradicts the
    declared one or is not of the column's kind."""
    lengths, angles = {}, {}
    for i, name in enumerate(table.header):
        key = name.strip().lower()
        kind = column_kind(key)
        if kind is None:
            continue
        declared, (written, named) = fmt.declared_unit(key), table.named.get(key, (name, None))
        if named and unit_kind(named) != kind:
            raise InputError(
                f"column '{written}' names the unit {named}, but {key} holds {kind}s "
                f"({'mm, m, in' if kind == 'length' else 'deg, rad'})",
                table.path,
                table.header_line,
                i + 1,
            )
        if declared and named and declared != named:
            raise InputError(
                f"column '{written}' is in {named} by its header, but the units declared for "
                f"{key} are {declared}: drop the declaration (--units) or correct the header",
                table.path,
                table.header_line,
                i + 1,
            )
        unit = declared or named
        if unit in ("m", "in"):
            lengths[i] = unit
        elif unit == "rad":
            angles[i] = unit
        if unit:
            table.units[key] = unit
    if lengths:
        _scale_lengths(table, lengths)
    if angles:
        _scale_angles(table, angles)


def _scale_lengths(table: Table, units: dict[int, str]) -> None:
    """In place: every number of the columns ``units`` (index -> m or in) as mm, in exact
    decimal arithmetic, so ``1.2345`` m reads as ``1234.5`` mm."""
    from decimal import Decimal  # only files in m or inch need it

    rows = table.rows
    table._cells = None  # the cells are now the rows
    factors = {i: Decimal(LENGTH_UNITS[unit]) for i, unit in units.items()}
    for row in rows:
        for i, factor in factors.items():
            text = row[i].strip(_BLANKS)
            if _DECIMAL.fullmatch(text) and not text[-1].isalpha():  # not nan, inf
                value = Decimal(text)
                row[i] = format(value.scaleb(3) if factor == 1000 else value * factor, "f")


def _scale_angles(table: Table, units: dict[int, str]) -> None:
    """In place: every number of the columns ``units`` (index -> rad) as deg (the float's
    shortest text); their printed round-off is kept for ``Table.decimals``."""
    rows = table.rows
    table._cells = None
    for i, unit in units.items():
        scale = ANGLE_UNITS[unit]
        cells = [row[i] for row in rows]
        table.printed[i] = np.array([decimals_of(c) for c in cells], float) - math.log10(scale)
        for row, cell in zip(rows, cells, strict=True):
            text = cell.strip(_BLANKS)
            if _DECIMAL.fullmatch(text) and not text[-1].isalpha():  # not nan, inf
                row[i] = repr(float(text) * scale)


def _parse_csv(text: str, path: str, delimiter: str = ",") -> Table:
    """Any file of the module docstring's format, through the csv module."""
    # Lines end only at CR, LF or CRLF: VT, FF, NEL and U+2028 inside a field are data.
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=delimiter, strict=True)
    header: list[str] | None = None
    rows: list[list[str]] = []
    lines: list[int] = []
    end_line = header_line = 0
    try:
        for record in reader:
            start_line, end_line = end_line + 1, reader.line_num
            if not "".join(record).strip() or record[0].lstrip().startswith(_COMMENT):
                continue  # blank or comment
            if header is None:
                header = [cell.strip() for cell in record]
                if len(header) > 1 and not header[-1]:
                    header.pop()  # a trailing delimiter
                _check_header(header, path, start_line)
                header_line = start_line
                continue
            if len(record) == len(header) + 1 and not record[-1].strip(_BLANKS):
                record.pop()  # a trailing delimiter
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
    return Table(path, header, rows, lines, header_line=header_line)


def _check_header(header: list[str], path: str, line: int) -> None:
    seen: dict[str, int] = {}
    for i, name in enumerate(header):
        if not name:
            raise InputError("empty column name in the header", path, line, i + 1)
        key = name.lower()
        if key in seen:
            raise InputError(f"column '{name}' appears twice in the header", path, line, i + 1)
        seen[key] = i
