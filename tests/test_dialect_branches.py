"""A dialect is its folder: no module outside ``codegen/<dialect>/`` branches on a dialect's name
or file suffix or imports a dialect folder's module (the registry, ``codegen/dialects.py``,
excepted), and no job below the command modules takes an ``argparse.Namespace``.

The source of every module is read as a syntax tree. A branch is a comparison (``==``, ``!=``,
``in``, ``not in``, ``is``) with a string that is a registered dialect name or suffix (case
ignored, also inside a tuple, list, set or dict literal, or a module-level constant holding
one), a ``match`` case on such a string, or ``endswith``/``startswith``/``removesuffix`` with one.
An import is an ``import``/``from`` statement anywhere in the module (a lazy one too, a relative
one resolved) or a string that is such a module's dotted name (``importlib.import_module``, a
lazy export table). The detectors are tried on snippets of every such form first, so that they
are shown to fail.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from accugrid.codegen.dialects import DIALECTS

ROOT = Path(__file__).resolve().parents[1]
ROOMS = ("infra", "kinematics", "compensation", "codegen", "app")
DIALECT_FOLDERS = {ROOT / "codegen" / name for name in DIALECTS}
WORDS = {name.lower() for name in DIALECTS} | {
    suffix.lower() for d in DIALECTS.values() for suffix in d.suffixes
}
SUFFIX_CALLS = {"endswith", "startswith", "removesuffix", "removeprefix"}
REGISTRY = ROOT / "codegen" / "dialects.py"
DIALECT_MODULE = re.compile(rf"accugrid\.codegen\.({'|'.join(map(re.escape, DIALECTS))})(\.\w+)*")


def _strings(node: ast.AST, constants: dict[str, str]) -> list[str]:
    """The strings a comparison operand stands for: a literal, a module-level constant, or the
    items of a tuple, list, set or dict literal of them."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return [node.value]
    if isinstance(node, ast.Name) and node.id in constants:
        return [constants[node.id]]
    if isinstance(node, ast.Tuple | ast.List | ast.Set):
        return [s for item in node.elts for s in _strings(item, constants)]
    if isinstance(node, ast.Dict):
        return [s for key in node.keys if key is not None for s in _strings(key, constants)]
    return []


def branches(source: str) -> list[tuple[int, str]]:
    """(line, registered word) of every branch on a dialect's name or suffix in ``source``."""
    tree = ast.parse(source)
    constants = {
        target.id: node.value.value
        for node in tree.body
        if isinstance(node, ast.Assign)
        and isinstance(node.value, ast.Constant)
        and isinstance(node.value.value, str)
        for target in node.targets
        if isinstance(target, ast.Name)
    }
    found = []
    for node in ast.walk(tree):
        operands: list[ast.AST] = []
        if isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
        elif isinstance(node, ast.match_case):
            operands = [p.value for p in ast.walk(node.pattern) if isinstance(p, ast.MatchValue)]
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr in SUFFIX_CALLS
        ):
            operands = list(node.args)
        for operand in operands:
            for text in _strings(operand, constants):
                if text.lower() in WORDS:
                    found.append((operand.lineno, text))
    return found


@pytest.mark.parametrize(
    "snippet",
    [
        "if kind == 'krl': pass",
        "ok = 'gcode' != kind",
        "ok = kind in ('krl', 'gcode')",
        "ok = kinds != {'krl'}",
        "ok = kind not in ['rapid']",
        "ok = kind in {'rapid': 1}",
        "ok = path.suffix.lower() == '.SRC'",
        "ok = name.endswith(('.ngc', '.nc'))",
        "ok = name.lower().endswith('.mod')",
        "KRL = 'krl'\nok = kind == KRL",
        "match kind:\n    case 'krl':\n        pass",
        "match kind:\n    case 'x' | '.dat':\n        pass",
    ],
)
def test_the_detector_finds_every_form_of_branch(snippet):
    assert branches(snippet), snippet


@pytest.mark.parametrize(
    "snippet",
    [
        "plugin = plugin_of(dialect_of(path))",
        "ok = kind == plugin.name",
        "ok = out.suffix.lower() == pair[0]",
        "text = 'a KRL .src and its .dat'",
        "ok = kind == 'krl_like'",
        "NAME = 'rapid'\nrun(NAME)",
    ],
)
def test_the_detector_passes_what_is_no_branch(snippet):
    assert not branches(snippet), snippet


def dialect_imports(source: str, package: str) -> list[tuple[int, str]]:
    """(line, module) of every import of a dialect folder's module in ``source``, a module of
    ``package`` (for relative imports)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package.split(".")[: len(package.split(".")) - node.level + 1]
            module = ".".join([*base, node.module or ""] if node.level else [node.module or ""])
            module = module.rstrip(".")
            names = [module, *(f"{module}.{alias.name}" for alias in node.names)]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            names = [node.value]
        found += [(node.lineno, name) for name in names if DIALECT_MODULE.fullmatch(name)]
    return sorted(set(found))


@pytest.mark.parametrize(
    ("snippet", "package"),
    [
        ("from accugrid.codegen.krl.emit import render_krl", "accugrid.app"),
        ("import accugrid.codegen.gcode.parse as p", "accugrid.app"),
        ("from accugrid.codegen import rapid", "accugrid.app"),
        ("from accugrid.codegen.krl import emit", "accugrid.codegen"),
        ("def f():\n    from accugrid.codegen.krl.section import KrlSection", "accugrid.codegen"),
        ("if TYPE_CHECKING:\n    from accugrid.codegen.gcode.section import S", "accugrid.codegen"),
        ("m = importlib.import_module('accugrid.codegen.rapid.rewrite')", "accugrid.app"),
        ("API = {'render_krl': 'accugrid.codegen.krl.emit'}", "accugrid.codegen"),
        ("from .krl import emit", "accugrid.codegen"),
        ("from . import krl", "accugrid.codegen"),
        ("from ..codegen.gcode.emit import render_gcode", "accugrid.app"),
    ],
)
def test_the_detector_finds_every_import_of_a_dialect_module(snippet, package):
    assert dialect_imports(snippet, package), snippet


@pytest.mark.parametrize(
    ("snippet", "package"),
    [
        ("from accugrid.codegen.dialects import plugin_of", "accugrid.app"),
        ("from accugrid.codegen import cell, plugin", "accugrid.app"),
        ("from accugrid.codegen.krl_like import x", "accugrid.app"),
        ("from . import rewrite", "accugrid.codegen"),
        ("text = 'see accugrid.codegen.krl.emit for the KRL'", "accugrid.app"),
        ('"""The reader: codegen.krl.emit."""', "accugrid.codegen"),
    ],
)
def test_the_detector_passes_what_is_no_import_of_a_dialect_module(snippet, package):
    assert not dialect_imports(snippet, package), snippet


def test_no_module_outside_a_dialect_folder_imports_one_but_the_registry():
    """The jobs, the cell and the library reach a dialect through the registry's plug-in."""
    found = []
    for path in _modules():
        if path == REGISTRY:
            continue
        rel = path.relative_to(ROOT)
        package = ".".join(["accugrid", *rel.parts[:-1]])
        for line, name in dialect_imports(path.read_text(encoding="utf-8"), package):
            found.append(f"{rel}:{line}: {name}")
    assert REGISTRY in _modules()
    assert not found, "dialect modules imported outside their folders:\n" + "\n".join(found)


def _modules() -> list[Path]:
    out = [ROOT / "__init__.py"]
    for room in ROOMS:
        for path in sorted((ROOT / room).rglob("*.py")):
            if not any(folder in path.parents for folder in DIALECT_FOLDERS):
                out.append(path)
    return out


def test_no_module_outside_a_dialect_folder_branches_on_a_dialect():
    modules = _modules()
    assert (
        ROOT / "codegen" / "rewrite.py" in modules
        and ROOT / "app" / "jobs" / "program.py" in modules
    )
    assert not any("krl" in p.parts for p in modules)
    found = [
        f"{path.relative_to(ROOT)}:{line}: {word!r}"
        for path in modules
        for line, word in branches(path.read_text(encoding="utf-8"))
    ]
    assert not found, "branches on a dialect outside its folder:\n" + "\n".join(found)


def test_no_job_below_the_commands_takes_an_argparse_namespace():
    """Jobs take request records; only the command line (``app/cli.py``, ``app/cli_options.py``,
    ``app/commands/``) sees argparse's ``Namespace``."""
    command_line = {ROOT / "app" / "cli.py", ROOT / "app" / "cli_options.py"}
    found = []
    for path in _modules():
        if path in command_line or ROOT / "app" / "commands" in path.parents:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Attribute) and node.attr == "Namespace":
                if isinstance(node.value, ast.Name) and node.value.id == "argparse":
                    found.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert not found, "argparse.Namespace below the commands: " + ", ".join(found)
