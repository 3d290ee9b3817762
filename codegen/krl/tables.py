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

    ``numeric``: column -> (dtype, shape of one row); the other columns are Python lists."""

    def __init__(self, numeric: dict[str, tuple[str, tuple[int, ...]]], objects: tuple[str, ...]):
        self._numeric = numeric
        self._objects = objects
        self._blocks: list[dict[str, object]] = []
        self._rows: dict[str, list] = {k: [] for k in (*numeric, *objects)}
        self.count = 0

    def add(self, **row) -> int:
        """Append one row (every column given); its index."""
        for key, value in row.items():
            self._rows[key].append(value)
        self.count += 1
        return self.count - 1

    def pop(self) -> None:
        """Drop the row ``add`` appended last."""
        for values in self._rows.values():
            values.pop()
        self.count -= 1

    def set(self, index: int, key: str, value) -> None:
        """Change a column of a row ``add`` appended (not yet part of a block)."""
        pending = self.count - len(self._rows[key])
        self._rows[key][index - pending] = value

    def extend(self, size: int, **block) -> None:
        """Append ``size`` rows: each column an array (numeric) or a sequence (objects)."""
        if not size:
            return
        self._flush()
        self._blocks.append(block)
        self.count += size

    def _flush(self) -> None:
        rows = self._rows
        if rows and rows[next(iter(rows))]:
            block: dict[str, object] = {}
            for key, (dtype, shape) in self._numeric.items():
                block[key] = np.array(rows[key], dtype=dtype).reshape(-1, *shape)
            for key in self._objects:
                block[key] = rows[key]
            self._blocks.append(block)
            self._rows = {k: [] for k in rows}

    def finish(self) -> dict[str, object]:
        """Every column whole: numeric ones as arrays (count, *shape), the others as lists."""
        self._flush()
        out: dict[str, object] = {
            key: np.empty((self.count, *shape), dtype=dtype)
            for key, (dtype, shape) in self._numeric.items()
        }
        out.update({key: [] for key in self._objects})
        blocks, self._blocks, at = self._blocks, [], 0
        blocks.reverse()
        while blocks:  # a block at a time, each dropped once copied (one copy of a column)
            block = blocks.pop()
            size = 0
            for key, (dtype, shape) in self._numeric.items():
                part = np.asarray(block[key], dtype=dtype).reshape(-1, *shape)
                size = len(part)
                out[key][at : at + size] = part
            for key in self._objects:
                out[key].extend(block[key])
            at += size
        return out


@dataclass
class PositionTable:
    """Aggregates of one file (N rows). Offsets are character offsets into the file's text.

    line, column (of the ``{``), base (index into ``bases``; -1 for stored positions): (N,) int32;
    kind (DECL/ASSIGN/MOTION) (N,) int8; agg (offset of the ``{``) (N,) int64. xyz, abc (N, 3)
    float mm/deg as written, NaN where not given; span (N, 3, 2) int64 start/end of the X, Y, Z
    literals (-1: not given).
    type, name, reason: lists of str. external: row -> (key, value) of the first non-zero E1..E6."""

    line: np.ndarray
    column: np.ndarray
    kind: np.ndarray
    agg: np.ndarray
    base: np.ndarray
    xyz: np.ndarray
    abc: np.ndarray
    span: np.ndarray
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


def position_columns() -> Columns:
    """Empty columns of a ``PositionTable``."""
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
        },
        ("type", "name", "reason"),
    )


def use_columns() -> Columns:
    """Empty columns of a ``UseTable``."""
    return Columns(
        {"line": ("int32", ()), "column": ("int32", ()), "base": ("int32", ())},
        ("motion", "name", "text", "reason"),
    )
