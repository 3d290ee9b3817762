"""The positions and motion uses of one KRL file, column by column (``codegen.krl.parse`` fills
them, ``codegen.krl.rewrite`` reads them): compact arrays instead of an object per position, so a
million-position program fits in a few hundred bytes per position.

Rows are added one at a time (the statement reader, for the few lines that are not plain) or a
block at a time (the whole-text scanner, for runs of plain declarations and motions). The base of
each motion row is an index into ``bases`` (the ``BaseRef`` objects of the file, each once: the
flow rules compare them by identity); ``remap`` changes them afterwards for a range of rows (a
loop that changes $BASE, a jump target).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "ASSIGN",
    "DECL",
    "KIND_NAMES",
    "MOTION",
    "Columns",
    "PositionTable",
    "UseTable",
    "position_columns",
    "use_columns",
]

DECL, ASSIGN, MOTION = 0, 1, 2
KIND_NAMES = ("decl", "assign", "motion")


class Columns:
    """Named columns filled row by row or block by block, then ``finish``-ed to arrays.

    ``numeric``: column -> (dtype, shape of one row), kept in arrays of ``capacity`` rows (grown
    when full; pages never written are never resident, so a generous capacity costs nothing);
    the other columns are Python lists."""

    def __init__(
        self,
        numeric: dict[str, tuple[str, tuple[int, ...]]],
        objects: tuple[str, ...],
        capacity: int = 1024,
    ):
        self._numeric = numeric
        self._arrays = {
            key: np.empty((max(capacity, 1), *shape), dtype=dtype)
            for key, (dtype, shape) in numeric.items()
        }
        self._lists: dict[str, list] = {key: [] for key in objects}
        self._rows: dict[str, list] = {key: [] for key in numeric}  # added, not yet in arrays
        self._stored = 0  # rows in the arrays
        self.count = 0

    def add(self, **row) -> int:
        """Append one row (every column given); its index."""
        for key, values in self._rows.items():
            values.append(row[key])
        for key, values in self._lists.items():
            values.append(row[key])
        self.count += 1
        return self.count - 1

    def pop(self) -> None:
        """Drop the row ``add`` appended last."""
        for values in (*self._rows.values(), *self._lists.values()):
            values.pop()
        self.count -= 1

    def set(self, index: int, key: str, value) -> None:
        """Change a column of a row ``add`` appended (numeric: not yet followed by a block)."""
        if key in self._lists:
            self._lists[key][index] = value
        else:
            self._rows[key][index - self._stored] = value

    def extend(self, size: int, **block) -> None:
        """Append ``size`` rows: each column an array (numeric) or a sequence (objects)."""
        if not size:
            return
        self._flush()
        self._store(size, block)
        for key, values in self._lists.items():
            values.extend(block[key])
        self.count += size

    def _store(self, size: int, block: dict[str, object]) -> None:
        need = self._stored + size
        for key, array in self._arrays.items():
            if need > len(array):  # full: grow (the rows so far copied once)
                grown = np.empty((max(need, 2 * len(array)), *array.shape[1:]), array.dtype)
                grown[: self._stored] = array[: self._stored]
                self._arrays[key] = array = grown
            array[self._stored : need] = block[key]
        self._stored = need

    def _flush(self) -> None:
        rows = self._rows
        size = len(next(iter(rows.values()))) if rows else 0
        if size:
            block = {
                key: np.array(rows[key], dtype=dtype).reshape(-1, *shape)
                for key, (dtype, shape) in self._numeric.items()
            }
            self._store(size, block)
            self._rows = {key: [] for key in rows}

    def finish(self) -> dict[str, object]:
        """Every column whole: numeric ones as arrays (count, *shape), the others as lists."""
        self._flush()
        out: dict[str, object] = {key: a[: self.count] for key, a in self._arrays.items()}
        out.update(self._lists)
        return out


@dataclass
class PositionTable:
    """Aggregates of one file (N rows). Offsets are character offsets into the file's text.

    line, column (of the ``{``), base (index into ``bases``; -1 for stored positions): (N,) int32;
    kind (DECL/ASSIGN/MOTION) (N,) int8; agg (offset of the ``{``) (N,) int64. xyz, abc (N, 3)
    float mm/deg as written, NaN where not given; span (N, 3, 2) int64 start/end of the X, Y, Z
    literals (-1: not given); places (N,) int16 the most decimals among those literals as written
    (``decimals_of``, at most 32767; -1: none given), for ``codegen.program_text.precision``.
    type, name, reason: lists of str. external: row -> (key, value) of the first non-zero E1..E6."""

    line: np.ndarray
    column: np.ndarray
    kind: np.ndarray
    agg: np.ndarray
    base: np.ndarray
    xyz: np.ndarray
    abc: np.ndarray
    span: np.ndarray
    places: np.ndarray
    type: list[str]
    name: list[str]
    reason: list[str]
    external: dict[int, tuple[str, float]] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.line)


@dataclass
class UseTable:
    """Motions to a named target of one file (M rows): line, column, base (index into
    ``bases``) (M,) int32; motion, name (normalized), text (as written), reason: lists of str."""

    line: np.ndarray
    column: np.ndarray
    base: np.ndarray
    motion: list[str]
    name: list[str]
    text: list[str]
    reason: list[str]

    def __len__(self) -> int:
        return len(self.line)


def position_columns(capacity: int = 1024) -> Columns:
    """Empty columns of a ``PositionTable`` (room for ``capacity`` rows before growing)."""
    return Columns(
        {
            "line": ("int32", ()),
            "column": ("int32", ()),
            "kind": ("int8", ()),
            "agg": ("int64", ()),
            "base": ("int32", ()),
            "xyz": ("float64", (3,)),
            "abc": ("float64", (3,)),
            "span": ("int64", (3, 2)),
            "places": ("int16", ()),
        },
        ("type", "name", "reason"),
        capacity,
    )


def use_columns(capacity: int = 1024) -> Columns:
    """Empty columns of a ``UseTable`` (room for ``capacity`` rows before growing)."""
    return Columns(
        {"line": ("int32", ()), "column": ("int32", ()), "base": ("int32", ())},
        ("motion", "name", "text", "reason"),
        capacity,
    )
