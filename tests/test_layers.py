"""The rooms import one way: infra <- kinematics <- compensation <- codegen <- app.

Each top-level folder is one layer; a module may import its own room and the rooms below it,
never one above (read from the source's import statements, so a lazy import counts too)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ORDER = ("infra", "kinematics", "compensation", "codegen", "app")


def _imported_rooms(path: Path) -> set[tuple[str, int]]:
    """(room, line) of every ``accugrid.ROOM`` module the file imports."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module:
            names = [node.module]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        else:
            continue
        for name in names:
            parts = name.split(".")
            if parts[0] == "accugrid" and len(parts) > 1 and parts[1] in ORDER:
                found.add((parts[1], node.lineno))
    return found


@pytest.mark.parametrize("room", ORDER)
def test_a_room_imports_only_itself_and_the_rooms_below(room):
    allowed = set(ORDER[: ORDER.index(room) + 1])
    wrong = [
        f"{path.relative_to(ROOT)}:{line} imports accugrid.{other}"
        for path in sorted((ROOT / room).rglob("*.py"))
        for other, line in sorted(_imported_rooms(path))
        if other not in allowed
    ]
    assert list((ROOT / room).rglob("*.py")), f"{room}/ holds no module"
    assert not wrong, "\n".join(wrong)


def _dialect_folders() -> list[str]:
    """The folders under codegen/ that are packages (one per dialect)."""
    return sorted(p.parent.name for p in (ROOT / "codegen").glob("*/__init__.py"))


@pytest.mark.parametrize("dialect", _dialect_folders())
def test_a_dialect_folder_imports_no_other_dialect(dialect):
    others = set(_dialect_folders()) - {dialect}
    wrong = []
    for path in sorted((ROOT / "codegen" / dialect).rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = (
                [node.module or ""]
                if isinstance(node, ast.ImportFrom)
                else [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else []
            )
            for name in names:
                parts = name.split(".")
                if parts[:2] == ["accugrid", "codegen"] and len(parts) > 2 and parts[2] in others:
                    wrong.append(f"{path.relative_to(ROOT)}:{node.lineno} imports {name}")
    assert len(others) >= 2, "the registry's dialects are folders under codegen/"
    assert not wrong, "\n".join(wrong)


def _module_name(path: Path) -> str:
    """``accugrid.ROOM.MODULE`` of a source file (a package by its folder)."""
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(("accugrid", *(parts[:-1] if parts[-1] == "__init__" else parts)))


def _import_graph(room: str) -> dict[str, set[str]]:
    """Module -> the modules of the same room it imports, every import statement counted: at
    the top, inside a function (lazy) and under ``if TYPE_CHECKING`` (a type hint); a module's
    own packages, which Python imports before it, are left out."""
    paths = {_module_name(p): p for p in sorted((ROOT / room).rglob("*.py"))}
    graph = {}
    for name, path in paths.items():
        found = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module:
                targets = [f"{node.module}.{a.name}" for a in node.names] + [node.module]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                continue
            for target in targets:
                while target and target not in paths:
                    target = target.rpartition(".")[0]
                if target and target != name and not name.startswith(f"{target}."):
                    found.add(target)
                    break
        graph[name] = found
    return graph


def _cycle(graph: dict[str, set[str]]) -> list[str]:
    """One import circle of ``graph`` (module names, the first repeated at the end), or []."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(node: str) -> list[str]:
        state[node] = 1
        path.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return [*path[path.index(nxt) :], nxt]
            if nxt not in state and (found := visit(nxt)):
                return found
        state[node] = 2
        path.pop()
        return []

    for start in sorted(graph):
        if start not in state and (found := visit(start)):
            return found
    return []


def test_the_cycle_finder_finds_a_circle_and_passes_a_chain():
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b", "c"}, "b": {"c"}, "c": set()}) == []


@pytest.mark.parametrize("room", ORDER)
def test_no_import_circle_within_a_room(room):
    """No module imports itself round a circle, not even by a type hint or a lazy import (such
    a circle works only as long as nobody moves an import)."""
    circle = _cycle(_import_graph(room))
    assert not circle, " -> ".join(circle)
