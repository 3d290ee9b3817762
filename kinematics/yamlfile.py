"""YAML configuration via ``yaml.safe_load``, with errors naming the key, line and column."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any

import yaml

from accugrid.kinematics.errors import InputError

_MISSING = object()


@dataclass(frozen=True)
class YamlDoc:
    """A parsed YAML mapping plus the source position of every key path (1-based line, column)."""

    data: dict
    marks: dict[tuple, tuple[int, int]]
    path: str

    @classmethod
    def parse(cls, text: str, path: str | os.PathLike[str]) -> YamlDoc:
        path = os.fspath(path)
        try:
            data = yaml.safe_load(text)
            node = yaml.compose(text)
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            problem = getattr(exc, "problem", None) or "invalid YAML"
            if mark is None:
                raise InputError(problem, path) from None
            raise InputError(problem, path, mark.line + 1, mark.column + 1) from None
        if not isinstance(data, dict):
            raise InputError("expected a YAML mapping at the top level", path, 1, 1)
        marks: dict[tuple, tuple[int, int]] = {}
        _collect(node, (), marks)
        return cls(data, marks, path)

    def keyname(self, *keys: Any) -> str:
        """Human name of a key path, e.g. ``dh[2].a_mm``."""
        out = ""
        for k in keys:
            out += f"[{k}]" if isinstance(k, int) else (f".{k}" if out else str(k))
        return f"'{out}'"

    def error(self, message: str, *keys: Any) -> InputError:
        """An InputError located at the deepest known position of ``keys``."""
        for depth in range(len(keys), -1, -1):
            if keys[:depth] in self.marks:
                line, col = self.marks[keys[:depth]]
                return InputError(message, self.path, line, col)
        return InputError(message, self.path)

    def get(self, *keys: Any, default: Any = _MISSING) -> Any:
        value: Any = self.data
        for depth, k in enumerate(keys):
            container_ok = (
                isinstance(value, list) if isinstance(k, int) else isinstance(value, dict)
            )
            if not container_ok:
                kind = "a list" if isinstance(k, int) else "a mapping"
                name = self.keyname(*keys[:depth])
                raise self.error(f"{name} must be {kind}", *keys[:depth])
            present = k < len(value) if isinstance(k, int) else k in value
            if not present:
                if default is not _MISSING:
                    return default
                raise self.error(f"missing key {self.keyname(*keys)}", *keys[:depth])
            value = value[k]
        return value

    def has(self, *keys: Any) -> bool:
        return self.get(*keys, default=None) is not None

    def number(self, *keys: Any, default: Any = _MISSING) -> float:
        value = self.get(*keys, default=default)
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float))
            or not math.isfinite(value)
        ):
            raise self.error(f"{self.keyname(*keys)} must be a finite number, got {value!r}", *keys)
        return float(value)

    def string(self, *keys: Any, default: Any = _MISSING) -> str:
        value = self.get(*keys, default=default)
        if not isinstance(value, str) or (default is _MISSING and not value.strip()):
            raise self.error(f"{self.keyname(*keys)} must be a non-empty text", *keys)
        return value

    def sequence(self, *keys: Any, length: int | None = None) -> list:
        value = self.get(*keys)
        if not isinstance(value, list):
            raise self.error(f"{self.keyname(*keys)} must be a list", *keys)
        if length is not None and len(value) != length:
            raise self.error(
                f"{self.keyname(*keys)} must have {length} entries, has {len(value)}", *keys
            )
        return value


def _collect(node: yaml.Node | None, prefix: tuple, marks: dict) -> None:
    if node is None:
        return
    marks.setdefault(prefix, (node.start_mark.line + 1, node.start_mark.column + 1))
    if isinstance(node, yaml.MappingNode):
        for key_node, value_node in node.value:
            key = prefix + (key_node.value,)
            marks[key] = (key_node.start_mark.line + 1, key_node.start_mark.column + 1)
            _collect(value_node, key, marks)
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            _collect(item, prefix + (i,), marks)
