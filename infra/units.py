"""Units of lengths and angles: the words files and options use, the unit a column header names,
a unit declaration (``--units``), the check that positions are plausible for a robot's size, and
how messages write a vector of numbers.

Lengths are mm and angles degrees everywhere inside accugrid files and options (DESIGN.md); an
export in m, inch or rad is converted on read. A column's unit comes from, in this order: the
declaration (``--units``, a cell's ``tracker.units``), the unit its header names (``x [m]``,
``Nominal X (in)``, ``x_mm``), else mm or deg.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence

import numpy as np

from accugrid.infra.errors import InputError

__all__ = [
    "ANGLE_COLUMNS",
    "ANGLE_UNITS",
    "LENGTH_COLUMNS",
    "LENGTH_UNITS",
    "KINDS",
    "check_scale",
    "column_kind",
    "header_unit",
    "mm_text",
    "unit_kind",
    "unit_spec",
]

LENGTH_UNITS = {"mm": "1", "m": "1000", "in": "25.4"}  # mm per unit, as exact decimal text
ANGLE_UNITS = {"deg": 1.0, "rad": 180.0 / math.pi}  # deg per unit
# the columns holding lengths (DESIGN.md points, measurements, experiment plans) and angles
# (KUKA a,b,c and the logged axis angles a1..a6)
LENGTH_COLUMNS = frozenset(
    ("x", "y", "z", "x_meas", "y_meas", "z_meas", "diameter", "depth", "step")
)
ANGLE_COLUMNS = frozenset(("a", "b", "c", *(f"a{i}" for i in range(1, 7))))
KINDS = {"length": LENGTH_UNITS, "angle": ANGLE_UNITS}
_SPELLINGS = {"inch": "in", "inches": "in", "degree": "deg", "degrees": "deg", "°": "deg"}
_UNIT = r"mm|m|in|inch|inches|deg|degrees?|°|rad"
# a unit named at the end of a header: "x [m]", "Nominal X (mm)", "x_mm", "X mm"
_HEADER_UNIT = re.compile(
    rf"(?P<name>.*?\S)(?:\s*\[\s*(?P<a>{_UNIT})\s*\]"
    rf"|\s*\(\s*(?P<b>{_UNIT})\s*\)|[_ ](?P<c>{_UNIT}))",
    re.I,
)
_REACH_SHARE = 0.1  # a set of positions all nearer the base than this share of the reach is no job


def column_kind(name: str) -> str | None:
    """'length', 'angle' or None for an accugrid column name (lower case)."""
    return "length" if name in LENGTH_COLUMNS else "angle" if name in ANGLE_COLUMNS else None


def unit_kind(unit: str) -> str | None:
    """'length', 'angle' or None for a unit word (mm, m, in, deg, rad)."""
    return next((kind for kind, units in KINDS.items() if unit in units), None)


def header_unit(header: str) -> tuple[str, str | None]:
    """(name, unit) of a header that ends with a unit (``x [m]`` -> ``("x", "m")``, ``X_mm``,
    ``Nominal X (in)``), else (header, None)."""
    found = _HEADER_UNIT.fullmatch(header.strip())
    if not found:
        return header, None
    word = (found["a"] or found["b"] or found["c"]).lower()
    return found["name"], _SPELLINGS.get(word, word)


def unit_spec(spec: str | Mapping[str, str] | None) -> dict[str, str]:
    """A unit declaration as {column or kind: unit}: ``"m"`` (every length column in m),
    ``"m,rad"`` (lengths in m, angles in rad), ``"m,rad,x_meas=mm,y_meas=mm,z_meas=mm"``
    (column by column after the kinds), or such a mapping; None or "" declares nothing.
    Kinds are keyed ``length`` and ``angle``. ValueError naming a bad word."""
    if spec is None:
        return {}
    items = spec.items() if isinstance(spec, Mapping) else _spec_items(spec)
    declared: dict[str, str] = {}
    for key, word in items:
        unit = _SPELLINGS.get(word.strip().lower(), word.strip().lower())
        kind = unit_kind(unit)
        key = key.strip().lower()
        if kind is None:
            raise ValueError(
                f"unknown unit {word!r} (lengths: {', '.join(LENGTH_UNITS)}; angles: "
                f"{', '.join(ANGLE_UNITS)})"
            )
        if key in KINDS:
            if key != kind:
                raise ValueError(f"{key}={word}: {word} is not a unit of {key}s")
        elif key:
            if column_kind(key) is None:
                raise ValueError(
                    f"{key}={word}: {key} is not a length or angle column (lengths: "
                    f"{', '.join(sorted(LENGTH_COLUMNS))}; angles: "
                    f"{', '.join(sorted(ANGLE_COLUMNS))})"
                )
            if column_kind(key) != kind:
                raise ValueError(f"{key}={word}: {word} is not a unit of {column_kind(key)}s")
        else:
            key = kind
        if key in declared:
            raise ValueError(f"the unit of {key} is declared twice")
        declared[key] = unit
    return declared


def _spec_items(text: str) -> list[tuple[str, str]]:
    """'m,rad,x_meas=mm' -> [('', 'm'), ('', 'rad'), ('x_meas', 'mm')]."""
    items = []
    for item in text.split(","):
        key, sep, word = item.partition("=")
        if not (word if sep else key).strip():
            raise ValueError(f"{item.strip()!r} is not UNIT or NAME=UNIT")
        items.append((key, word) if sep else ("", key))
    return items


def check_scale(
    points_mm: np.ndarray,
    reach_mm: float,
    what: str,
    path: str | None = None,
    lines: Sequence[int] | None = None,
) -> None:
    """InputError when every position of ``points_mm`` (N, 3) mm (robot frame) lies nearer the
    robot's base than a tenth of its reach ``reach_mm``: no job lies inside the robot's own
    base, a file of lengths in m or inch read as mm does. The message names the farthest
    position (at ``path``, ``lines[row]``) and the unit that puts it in reach. ``what``: how
    the message names a position ('target', 'commanded position')."""
    if not len(points_mm):
        return
    distance = np.linalg.norm(points_mm, axis=1)
    far = int(np.argmax(distance))
    if distance[far] >= _REACH_SHARE * reach_mm:
        return
    likely = [
        word
        for word, scale in (("m", 1000.0), ("in", 25.4))
        if _REACH_SHARE * reach_mm <= distance[far] * scale <= 1.2 * reach_mm
    ]
    hint = (
        f"are the file's lengths in {likely[0]}? (read them with --units {likely[0]})"
        if likely
        else "check the file's length unit (--units)"
    )
    raise InputError(
        f"every {what} lies within {distance[far]:.1f} mm of the robot base (the farthest "
        f"{mm_text(points_mm[far], 1)} mm) while the robot reaches {reach_mm:.0f} mm: {hint}",
        path,
        None if lines is None else int(lines[far]),
    )


def mm_text(values: np.ndarray, decimals: int = 3) -> str:
    """A vector (n,) of mm (or deg) as ``(x, y, z)`` with ``decimals`` places, for messages."""
    return "(" + ", ".join(f"{x:.{decimals}f}" for x in np.asarray(values, dtype=float)) + ")"
