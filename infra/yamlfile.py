"""The one YAML loader: strict, bounded, with errors naming file, key, line and column.

Every configuration file (robot, cell, frame) is read by ``load_yaml``: the file through the
guarded reader (``infra.inputfile``: regular file, size limit, UTF-8), then a safe loader that
refuses what no accugrid file needs and what makes a small file expensive: aliases and anchors
(``&a``/``*a``, the "billion laughs"), explicit tags (``!!int``, ``!!python/...``), duplicate keys
(the last one would win silently), nesting deeper than ``MAX_DEPTH``, complex keys, and integers
outside the float range. Each refusal is an InputError at the offending line and column.

Unknown keys are errors too: each reader declares the keys of its sections once, as a ``Schema``
(key -> None for a value, a nested Schema for a mapping, ``[Schema]`` for a list of mappings), and
``YamlDoc.check_keys`` refuses any other key at its line and column, naming the nearest valid
one ("erors: unknown key; did you mean errors?").
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Collection, Mapping
from dataclasses import dataclass
from typing import Any, Union

import yaml

from accugrid.infra.digest import sha256_hex
from accugrid.infra.errors import InputError
from accugrid.infra.inputfile import MAX_CONFIG_BYTES, read_input_text

__all__ = ["MAX_DEPTH", "Schema", "YamlDoc", "load_yaml", "unknown_key"]

MAX_DEPTH = 32  # nested mappings/sequences; our files use 4
_INT_CHARS = 400  # a longer integer is beyond float64 (and slow to convert): refused unread
_MISSING = object()

# key -> None (any value), a nested Schema (a mapping), or [Schema] (a list of mappings)
Schema = Mapping[str, Union["Schema", list, None]]


def unknown_key(name: str, key: object, allowed: Collection[str]) -> str:
    """'NAME: unknown key; did you mean X?' (else the allowed keys) for ``key`` at ``name``."""
    import difflib  # only for a message: not on every command's start-up (~1 ms)

    near = difflib.get_close_matches(str(key), sorted(allowed), n=1, cutoff=0.6)
    if near:
        return f"{name}: unknown key; did you mean {near[0]}?"
    return f"{name}: unknown key (allowed: {', '.join(sorted(allowed))})"


class _Refused(yaml.YAMLError):
    def __init__(self, problem: str, mark: yaml.Mark | None) -> None:
        super().__init__(problem)
        self.problem = problem
        self.problem_mark = mark


class _StrictLoader(yaml.SafeLoader):
    """SafeLoader without aliases, anchors, tags, duplicate keys, deep nesting or huge ints."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._depth = 0

    def compose_node(self, parent: yaml.Node | None, index: object) -> yaml.Node:
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent):
            raise _Refused("aliases (*name) are not accepted", event.start_mark)
        if getattr(event, "anchor", None) is not None:
            raise _Refused("anchors (&name) are not accepted", event.start_mark)
        if getattr(event, "tag", None) is not None:
            raise _Refused(
                f"explicit tags ({event.tag}) are not accepted; write the plain value",
                event.start_mark,
            )
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise _Refused(f"nested deeper than {MAX_DEPTH} levels", event.start_mark)
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def compose_mapping_node(self, anchor: str | None) -> yaml.MappingNode:
        node = super().compose_mapping_node(anchor)
        seen: dict[tuple[str, str], yaml.Node] = {}
        for key, _ in node.value:
            if not isinstance(key, yaml.ScalarNode):
                raise _Refused("keys must be plain values", key.start_mark)
            ident = (key.tag, key.value)
            if ident in seen:
                first = seen[ident].start_mark.line + 1
                raise _Refused(
                    f"duplicate key '{key.value}' (first on line {first})", key.start_mark
                )
            seen[ident] = key
        return node

    def construct_yaml_int(self, node: yaml.ScalarNode) -> int:
        value = None if len(node.value) > _INT_CHARS else super().construct_yaml_int(node)
        if value is None or abs(value) > 1e308:
            raise _Refused("integer out of range (beyond 1e308)", node.start_mark)
        return value


_StrictLoader.add_constructor("tag:yaml.org,2002:int", _StrictLoader.construct_yaml_int)
# YAML 1.1 (PyYAML) reads 5e-8 and 1E3, without a decimal point, as text; YAML 1.2 and every
# user read them as numbers
_StrictLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."),
)


def _located(exc: yaml.YAMLError, text: str, path: str) -> InputError:
    """An InputError at the position a PyYAML error names."""
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    problem = getattr(exc, "problem", None) or getattr(exc, "reason", None) or "invalid YAML"
    if mark is not None:
        return InputError(f"invalid YAML: {problem}", path, mark.line + 1, mark.column + 1)
    position = getattr(exc, "position", None)  # ReaderError: a character YAML does not allow
    if isinstance(position, int):
        head = text[:position]
        line = head.count("\n") + 1
        return InputError(f"invalid YAML: {problem}", path, line, position - head.rfind("\n"))
    return InputError(f"invalid YAML: {problem}", path)


def load_yaml(path: str | os.PathLike[str], limit: int = MAX_CONFIG_BYTES) -> YamlDoc:
    """Read and parse a YAML file (see the module docstring); InputError on any problem."""
    raw, text = read_input_text(path, limit)
    return YamlDoc.parse(text, path, sha256_hex(raw))


@dataclass(frozen=True)
class YamlDoc:
    """A parsed YAML mapping plus the source position of every key path (1-based line, column).

    Mapping keys in ``marks`` are the key's text as written; sequence items their index.
    ``sha256`` is the file's digest (empty for text not read from a file).
    """

    data: dict
    marks: dict[tuple, tuple[int, int]]
    path: str
    sha256: str = ""

    @classmethod
    def parse(cls, text: str, path: str | os.PathLike[str], sha256: str = "") -> YamlDoc:
        """Parse YAML text strictly; an empty document is an empty mapping."""
        path = os.fspath(path)
        try:
            loader = _StrictLoader(text)  # checks the characters first
            try:
                node = loader.get_single_node()
                data = {} if node is None else loader.construct_document(node)
            finally:
                loader.dispose()
        except yaml.YAMLError as exc:
            raise _located(exc, text, path) from None
        if not isinstance(data, dict):
            raise InputError("the top level must be a mapping (key: value lines)", path, 1, 1)
        marks: dict[tuple, tuple[int, int]] = {}
        _collect(node, (), marks)
        return cls(data, marks, path, sha256)

    def line(self, *keys: Any) -> int | None:
        """1-based line of the deepest of ``keys`` present in the file (None if none is)."""
        for depth in range(len(keys), 0, -1):
            if keys[:depth] in self.marks:
                return self.marks[keys[:depth]][0]
        return None

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

    def check_keys(self, schema: Schema, *keys: Any) -> None:
        """InputError at the first key of the mapping at ``keys`` (and of its nested mappings
        and lists of mappings, as ``schema`` declares them) that ``schema`` does not name. An
        absent or empty value passes; a value where a mapping belongs is an error."""
        value = self.get(*keys, default=None)
        if value is None:
            return
        if not isinstance(value, dict):
            raise self.error(f"{self.keyname(*keys)} must be a mapping", *keys)
        for key, item in value.items():
            if key not in schema:
                name = self.keyname(*keys, key).strip("'")
                raise self.error(unknown_key(name, key, schema), *keys, key)
            inner = schema[key]
            if isinstance(inner, list):
                if not isinstance(item, list):
                    raise self.error(f"{self.keyname(*keys, key)} must be a list", *keys, key)
                for i in range(len(item)):
                    self.check_keys(inner[0], *keys, key, i)
            elif inner is not None:
                self.check_keys(inner, *keys, key)

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
            key = prefix + (str(key_node.value),)
            marks[key] = (key_node.start_mark.line + 1, key_node.start_mark.column + 1)
            _collect(value_node, key, marks)
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            _collect(item, prefix + (i,), marks)
