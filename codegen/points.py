"""The drilling points CSV (docs/formats.md "Points") and the tool orientation of each hole.

Columns: ``x,y,z`` (mm, program BASE frame) required; ``id`` optional (unique, non-empty);
orientation either ``a,b,c`` (KUKA ABC, deg) or ``i,j,k`` (drill axis into the part, any non-zero
length, normalised here); ``diameter``, ``depth`` (mm) and ``feed`` (mm/s) optional and positive,
an empty cell meaning "the cell file's default"; other columns are carried through in ``table``.
Bounds: coordinates within +-``COORD_MAX_MM``, feed up to ``FEED_MAX_MM_S``, diameter and depth
up to ``SIZE_MAX_MM``: a program never carries an absurd number.

The rotation about a given drill axis (``i,j,k`` input) is chosen by
``kinematics.frames.orient_along_axes``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from accugrid.infra.csvtable import Table, TableFormat, parse_table, read_table
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix

__all__ = [
    "AXIS_MIN_LENGTH",
    "COORD_MAX_MM",
    "FEED_MAX_MM_S",
    "SIZE_MAX_MM",
    "Points",
    "parse_points",
    "read_points",
]

AXIS_MIN_LENGTH = 1e-9  # an i,j,k vector shorter than this has no direction
COORD_MAX_MM = 1e6  # |x|, |y|, |z| beyond 1 km are refused (no cell is that large)
FEED_MAX_MM_S = 2000.0  # same limit as the cell's speeds
SIZE_MAX_MM = 1e4  # diameter and depth


@dataclass
class Points:
    """Parsed drilling points. Arrays are float64; row r came from file line ``lines[r]``."""

    path: str
    table: Table
    ids: list[str]
    xyz: np.ndarray  # (N, 3) mm
    abc: np.ndarray | None  # (N, 3) deg, when given as a,b,c
    axis: np.ndarray | None  # (N, 3) unit drill axis into the part (from i,j,k or a,b,c tool Z)
    diameter: np.ndarray  # (N,) mm, NaN when not given
    depth: np.ndarray  # (N,) mm, NaN when not given
    feed: np.ndarray  # (N,) mm/s, NaN when not given

    def __len__(self) -> int:
        return len(self.ids)

    def __repr__(self) -> str:
        how = f", orientation {self.orientation}" if self.orientation else ""
        return f"Points({len(self)} holes from {os.path.basename(self.path)}{how})"

    @property
    def lines(self) -> list[int]:
        return self.table.lines

    @property
    def orientation(self) -> str | None:
        """ "abc", "ijk" or None (no orientation columns)."""
        if self.abc is not None:
            return "abc"
        return None if self.axis is None else "ijk"

    def name(self, r: int) -> str:
        """How a message located at hole r's line names it."""
        return f"hole '{self.ids[r]}'"

    def label(self, r: int) -> str:
        """How messages name hole r among others: its id and file line."""
        return f"hole '{self.ids[r]}' ({self.path}:{self.lines[r]})"


def read_points(path: str | os.PathLike[str], fmt: TableFormat | None = None) -> Points:
    """Read and validate a points CSV file (see module docstring); ``fmt``: how it is written
    (delimiter, decimal mark, column mapping, units; default: found)."""
    return _points(read_table(path, fmt))


def parse_points(text: str, path: str = "<string>", fmt: TableFormat | None = None) -> Points:
    """Parse points CSV text; ``path`` is used in messages only."""
    return _points(parse_table(text, path, fmt))


def _points(table: Table) -> Points:
    table.require(["x", "y", "z"])
    xyz = table.floats(["x", "y", "z"])
    table.check_bounds(xyz, ["x", "y", "z"], COORD_MAX_MM, "mm")
    ids = _ids(table)
    has_abc = [table.has(n) for n in "abc"]
    has_ijk = [table.has(n) for n in "ijk"]
    if any(has_abc) and any(has_ijk):
        raise InputError(
            "give the orientation either as a,b,c or as i,j,k, not both", table.path, 1
        )
    abc = axis = None
    if any(has_abc):
        table.require(["a", "b", "c"])
        abc = table.floats(["a", "b", "c"])
        axis = abc_to_matrix(abc)[:, :, 2] if len(abc) else np.zeros((0, 3))
    elif any(has_ijk):
        table.require(["i", "j", "k"])
        raw = table.floats(["i", "j", "k"])
        size = np.abs(raw)  # column by column below: reductions over a short axis are slow
        largest = np.maximum(np.maximum(size[:, 0], size[:, 1]), size[:, 2])  # scaled first:
        short = np.flatnonzero(~(largest > AXIS_MIN_LENGTH))  # huge i,j,k must not overflow
        if short.size:
            raise InputError("drill axis i,j,k has zero length", *table.where(int(short[0]), "i"))
        axis = raw / largest[:, None]
        square = np.square(axis, out=size)
        axis /= np.sqrt(square[:, 0] + square[:, 1] + square[:, 2])[:, None]  # the norm
    return Points(
        path=table.path,
        table=table,
        ids=ids,
        xyz=xyz,
        abc=abc,
        axis=axis,
        diameter=_optional_positive(table, "diameter", SIZE_MAX_MM, "mm"),
        depth=_optional_positive(table, "depth", SIZE_MAX_MM, "mm"),
        feed=_optional_positive(table, "feed", FEED_MAX_MM_S, "mm/s"),
    )


def _ids(table: Table) -> list[str]:
    if not table.has("id"):
        return [str(r + 1) for r in range(len(table))]
    ids = list(map(str.strip, table.text("id")))
    distinct = set(ids)
    if len(distinct) == len(ids) and "" not in distinct:
        return ids
    first: dict[str, int] = {}
    for r, name in enumerate(ids):
        if not name:
            raise InputError("empty id", *table.where(r, "id"))
        if name in first:
            raise InputError(
                f"duplicate id '{name}' (first on line {table.lines[first[name]]})",
                *table.where(r, "id"),
            )
        first[name] = r
    return ids


def _optional_positive(table: Table, name: str, limit: float, unit: str) -> np.ndarray:
    if not table.has(name):
        return np.full(len(table), np.nan)
    values = table.floats([name], allow_empty=True)[:, 0]
    bad = np.flatnonzero(values <= 0)
    if bad.size:
        r = int(bad[0])
        raise InputError(f"{name} must be positive, got {values[r]:g}", *table.where(r, name))
    table.check_bounds(values[:, None], [name], limit, unit)
    return values
