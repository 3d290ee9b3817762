"""Typed, located getters over one cell YAML file, shared by the cell's section readers
(``codegen.cell`` for the neutral sections, ``codegen/<dialect>/section.py`` for a dialect's).

Every error is an ``InputError`` naming the key path (``drilling.depth``) and its file line.
Lengths mm, angles deg; the bounds below hold for every length and angle a program can carry
(speeds, times and counts have their own).
"""

from __future__ import annotations

import math
import os
from collections.abc import Collection, Mapping
from pathlib import Path

import numpy as np

from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import fixed
from accugrid.infra.yamlfile import YamlDoc, unknown_key
from accugrid.kinematics.frames import pose_from_xyzabc, xyzabc_from_pose

__all__ = [
    "ANGLE_MAX_DEG",
    "DISTANCE_MAX_MM",
    "FRAME_KEYS",
    "frame_lines",
    "FRAME_MAX_MM",
    "CellReader",
    "SectionKeys",
]

FRAME_KEYS = ("x", "y", "z", "a", "b", "c")
FRAME_MAX_MM = 1e6  # |x|, |y|, |z| of a frame, external axis positions
ANGLE_MAX_DEG = 360.0  # |a|, |b|, |c|
DISTANCE_MAX_MM = 1e4  # approach, clearance, retract, depth, peck, apo_cdis

SectionKeys = Mapping[str, frozenset[str]]  # YAML section -> the keys a reader takes from it


def frame_lines(pose: np.ndarray, mm_decimals: int, deg_decimals: int) -> list[str]:
    """A pose (4, 4) mm as the indented YAML lines ``x, y, z`` (mm) and ``a, b, c`` (KUKA ABC
    deg) of a frame file's frame, each through the fixed-point formatter."""
    xyzabc = xyzabc_from_pose(pose)
    places = (mm_decimals,) * 3 + (deg_decimals,) * 3
    return [f"  {k}: {fixed(v, d)}" for k, v, d in zip(FRAME_KEYS, xyzabc, places, strict=True)]


class CellReader:
    """A cell file's top-level mapping with typed getters. Values are taken by YAML section and
    key (``number("drilling", "depth", ...)``); a missing section reads as empty, a present one
    must be a mapping of only the keys some reader declared (``sections``); top-level keys
    other than ``top_keys`` and the sections are errors."""

    def __init__(self, path: Path, doc: YamlDoc, top_keys: set[str], sections: SectionKeys):
        self.path = path
        self.doc = doc
        self._allowed = dict(sections)
        self.top = self.mapping(doc.data, "", set(top_keys) | set(sections))
        self._sections: dict[str, dict] = {}

    def error(self, key: str, message: str) -> InputError:
        return InputError(f"{key}: {message}", os.fspath(self.path), self.doc.line(*key.split(".")))

    def mapping(self, data: object, key: str, allowed: Collection[str] | None) -> dict:
        """``data`` as a dict of str keys ({} for None); keys outside ``allowed`` are errors."""
        if data is None:
            return {}
        if not isinstance(data, Mapping):
            raise self.error(key, f"must be a mapping, got {type(data).__name__}")
        if allowed is not None:
            for k in data:
                if str(k) not in allowed:
                    name = f"{key}.{k}" if key else str(k)
                    raise InputError(
                        unknown_key(name, k, allowed),
                        os.fspath(self.path),
                        *self.doc.marks.get((*key.split("."), str(k)) if key else (str(k),), ()),
                    )
        return {str(k): v for k, v in data.items()}

    def section(self, name: str) -> dict:
        """The YAML section ``name`` (a declared one), checked once."""
        if name not in self._sections:
            self._sections[name] = self.mapping(self.top.get(name), name, self._allowed[name])
        return self._sections[name]

    def value(self, section: str, name: str, default: object = None) -> object:
        """The raw value of ``section.name`` (``default`` when absent)."""
        return self.section(section).get(name, default)

    def number(
        self,
        section: str,
        name: str,
        default: float | None,
        lo: float | None = None,
        hi: float | None = None,
        strict_lo: bool = False,
        data: dict | None = None,
    ) -> float:
        """A finite number within [lo, hi] (lo excluded with ``strict_lo``); ``data`` instead of
        the section's mapping for nested keys (``section`` is then their key path)."""
        full = f"{section}.{name}" if section else name
        value = (self.section(section) if data is None else data).get(name, default)
        if value is None:
            raise self.error(full, "is required")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(full, f"must be a number, got {value!r}")
        value = float(value)
        if not math.isfinite(value):
            raise self.error(full, "must be a finite number")
        if lo is not None and (value <= lo if strict_lo else value < lo):
            raise self.error(full, f"must be {'>' if strict_lo else '>='} {lo:g}, got {value:g}")
        if hi is not None and value > hi:
            raise self.error(full, f"must be <= {hi:g}, got {value:g}")
        return value

    def integer(
        self,
        section: str,
        name: str,
        default: int | None,
        lo: int | None = None,
        hi: int | None = None,
        optional: bool = False,
        data: dict | None = None,
    ) -> int | None:
        """An integer within [lo, hi]; None when absent and ``optional``."""
        full = f"{section}.{name}" if section else name
        value = (self.section(section) if data is None else data).get(name, default)
        if value is None:
            if optional:
                return None
            raise self.error(full, "is required")
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(full, f"must be an integer, got {value!r}")
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            raise self.error(full, f"must be between {lo} and {hi}, got {value}")
        return value

    def boolean(self, section: str, name: str, default: bool) -> bool:
        value = self.value(section, name, default)
        if not isinstance(value, bool):
            raise self.error(f"{section}.{name}", f"must be true or false, got {value!r}")
        return value

    def choice(self, section: str, name: str, default: str, choices: Collection[str]) -> str:
        """One of ``choices`` (their order in the message)."""
        value = self.value(section, name, default)
        if value not in choices:
            raise self.error(f"{section}.{name}", f"must be {' or '.join(choices)}, got {value!r}")
        return value

    def file_path(self, section: str, name: str, what: str) -> Path | None:
        """A file path relative to the cell file (None when absent); ``section`` "" for a
        top-level key."""
        value = self.top.get(name) if not section else self.value(section, name)
        if value is None:
            return None
        if not isinstance(value, str) or not value.strip():
            raise self.error(f"{section}.{name}" if section else name, f"must be {what}")
        return self.path.parent / value

    def frame(self, data: object, key: str, numbered: bool) -> tuple[int | None, np.ndarray]:
        """A required frame {x, y, z mm, a, b, c deg[, number 1..32]}: (number, (4, 4) pose)."""
        allowed = set(FRAME_KEYS) | ({"number"} if numbered else set())
        d = self.mapping(data, key, allowed)
        if not d:
            raise self.error(key, "is required (x, y, z in mm; a, b, c in deg)")
        number = self.integer(key, "number", None, 1, 32, data=d) if numbered else None
        xyzabc = [self.number(key, k, 0.0, -FRAME_MAX_MM, FRAME_MAX_MM, data=d) for k in "xyz"]
        xyzabc += [self.number(key, k, 0.0, -ANGLE_MAX_DEG, ANGLE_MAX_DEG, data=d) for k in "abc"]
        return number, pose_from_xyzabc(np.array(xyzabc))

    def frame_file(self, key: str, writer: str) -> tuple[int | None, str] | None:
        """The top-level ``key`` given as a file {file, number 1..32} (a path relative to the
        cell, written by the command ``writer``): (number, path); None when it is a frame."""
        data = self.top.get(key)
        if not isinstance(data, Mapping) or "file" not in data:
            return None
        d = self.mapping(data, key, {"file", "number"})
        number = self.integer(key, "number", None, 1, 32, data=d)
        name = d["file"]
        if not isinstance(name, str) or not name.strip():
            raise self.error(f"{key}.file", f"must be the path of a file written by {writer}")
        return number, name

    def abc(self, data: object, key: str, default: tuple) -> tuple[float, float, float]:
        """An optional {a, b, c} orientation (KUKA deg)."""
        if data is None:
            return default
        d = self.mapping(data, key, {"a", "b", "c"})
        return tuple(self.number(key, k, 0.0, -ANGLE_MAX_DEG, ANGLE_MAX_DEG, data=d) for k in "abc")
