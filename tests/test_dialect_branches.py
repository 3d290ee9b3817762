"""A dialect is its folder: no module outside ``codegen/<dialect>/`` branches on a dialect's name
or file suffix, imports a dialect folder's module (the registry, ``codegen/dialects.py``,
excepted) or names a dialect at all (its name, the words of its title, its suffixes, its
vocabulary: in a string, an identifier or an import; ``ALLOWED_FILES`` says where and why one
may), and no job below the command modules takes an ``argparse.Namespace``.

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


# A dialect's words besides its name, its title's words and its suffixes (registry).
VOCABULARY = {
    "krl": {"e6pos", "e6axis"},
    "gcode": {"g-code", "rs274ngc", "ngc"},
    "rapid": {"robtarget", "robtargets", "confdata"},
    "fanuc": {"uframe_num", "utool_num"},
}
GENERIC = {"iso"}  # a title's word that is no dialect's own (ISO 9283, the standard)
ALLOWED_FILES = {
    "codegen/dialects.py": "the registry: one line per dialect names its plug-in's module",
}
# The KUKA Status and Turn as the configuration every layer still speaks (RAPID's confdata checked
# as one), the KUKA A, B, C angles as the orientation convention and joint angles "(KUKA)" in its
# signs, until a vendor-neutral configuration replaces them.
ALLOWED_PHRASE = re.compile(r"KUKA (Status|Turn|ABC|A,? B,? C)\b|\(KUKA\)")
ALLOWED_NAMES = {"kuka_turn", "kuka_words", "to_kuka", "from_kuka", "kuka_status", "kuka_status_of"}


def _words_of(name: str) -> set[str]:
    title = {w.lower() for w in re.split(r"[\s/()]+", DIALECTS[name].title) if len(w) > 2}
    return {name.lower()} | (title - GENERIC) | VOCABULARY.get(name, set())


def _tokens(identifier: str) -> list[str]:
    """The words of an identifier: split at ``_`` and where lower case meets upper case."""
    return [t.lower() for t in re.split(r"_+|(?<=[a-z0-9])(?=[A-Z])", identifier) if t]


def _docstrings(tree: ast.AST) -> set[int]:
    """ids of the string nodes that document: a string standing alone as a statement (a
    module's, class's or function's docstring, or one after an assignment)."""
    return {
        id(node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Expr)
        and isinstance(node.value, ast.Constant)
        and isinstance(node.value.value, str)
    }


def named_dialects(source: str, names) -> list[tuple[int, str]]:
    """(line, word) of every word of the dialects ``names`` in ``source``'s strings (documents
    aside), identifiers and imports, and of every one of their suffixes in its strings."""
    words = {w for name in names for w in _words_of(name)}
    suffixes = [re.escape(s) for n in names for s in DIALECTS[n].suffixes]
    suffix = re.compile(rf"(?:{'|'.join(suffixes)})(?![\w-])", re.IGNORECASE)
    tree = ast.parse(source)
    documents = _docstrings(tree)
    found = []
    for node in ast.walk(tree):
        identifiers: list[str] = []
        text = ""
        if isinstance(node, ast.Name):
            identifiers = [node.id]
        elif isinstance(node, ast.Attribute):
            identifiers = [node.attr]
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            identifiers = [node.name]
        elif isinstance(node, ast.arg | ast.keyword):
            identifiers = [node.arg or ""]
        elif isinstance(node, ast.alias):
            identifiers = [*node.name.split("."), node.asname or ""]
        elif isinstance(node, ast.ImportFrom):
            identifiers = (node.module or "").split(".")
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            text = "" if id(node) in documents else ALLOWED_PHRASE.sub("", node.value)
            text = " ".join(w for w in text.split() if w.strip("\"'") not in ALLOWED_NAMES)
        line = getattr(node, "lineno", 0)
        for identifier in identifiers:
            if identifier not in ALLOWED_NAMES:
                found += [(line, w) for w in _tokens(identifier) if w in words]
        spoken = re.findall(r"[A-Za-z0-9][A-Za-z0-9-]*", text)
        found += [(line, w) for w in spoken if w.lower() in words]
        found += [(line, s) for s in suffix.findall(text)]
    return sorted(set(found))


@pytest.mark.parametrize(
    "snippet",
    [
        "text = 'a KUKA KRL program'",
        "text = f'{name}.src and {name}.DAT'",
        "text = 'write the G-code'",
        "files = render_krl(program)",
        "def write_rapid(): pass",
        "class KrlReader: pass",
        "def f(robtarget): pass",
        "f(gcodeFrame=1)",
        "value = cell.rapid_module",
        "import accugrid.codegen.krl.emit",
        "from accugrid.codegen.rapid import emit",
        "from accugrid.codegen.x import confdata_of as words",
        "def f():\n    return 'E6POS'",
    ],
)
def test_the_word_detector_finds_a_dialect_in_every_form(snippet):
    assert named_dialects(snippet, DIALECTS), snippet


@pytest.mark.parametrize(
    "snippet",
    [
        '"""The KRL reader and its .src files."""',
        'def f():\n    """Reads RAPID."""',
        "text = 'in KUKA Status 3 with KUKA A, B, C'",
        "text = 'ISO 9283 cube'",
        "name = sys.modules[__name__]",
        "krlike = kind",
        "text = 'a .srcx file'",
        "turn = kuka_turn(q)",
        "# a KRL comment\nx = 1",
    ],
)
def test_the_word_detector_passes_what_names_no_dialect(snippet):
    assert not named_dialects(snippet, DIALECTS), snippet


def test_no_module_outside_a_dialect_folder_names_a_dialect():
    """In a string, an identifier or an import, only its folder (and ``ALLOWED_FILES``) names a
    dialect; another dialect's folder does not either."""
    found = []
    modules = _modules() + [p for f in sorted(DIALECT_FOLDERS) for p in sorted(f.rglob("*.py"))]
    for path in modules:
        rel = path.relative_to(ROOT).as_posix()
        own = {name for name in DIALECTS if ROOT / "codegen" / name in path.parents}
        if rel in ALLOWED_FILES:
            continue
        for line, word in named_dialects(path.read_text(encoding="utf-8"), set(DIALECTS) - own):
            found.append(f"{rel}:{line}: {word!r}")
    assert not found, "a dialect named outside its folder:\n" + "\n".join(found)


def test_every_allowed_file_still_names_a_dialect():
    """An allowance no longer needed is dropped, so that the list holds only the exceptions."""
    for rel in ALLOWED_FILES:
        assert named_dialects((ROOT / rel).read_text(encoding="utf-8"), DIALECTS), rel
