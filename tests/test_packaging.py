"""The distribution installs one import package, ``accugrid``, and nothing else at the top level."""

from __future__ import annotations

import importlib
import shutil
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

import pytest

import accugrid

ROOT = Path(__file__).resolve().parents[1]
PACKAGE_FOLDERS = ("infra", "kinematics", "compensation", "codegen", "app", "templates")


def _source_copy(tmp_path: Path) -> Path:
    """The files a build reads, copied (setuptools keeps a build/ folder beside its sources)."""
    source = tmp_path / "source"
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    for folder in PACKAGE_FOLDERS:
        shutil.copytree(ROOT / folder, source / folder, ignore=ignore)
    for name in ("pyproject.toml", "__init__.py", "README.md"):
        shutil.copy(ROOT / name, source / name)
    return source


def _build(kind: str, source: Path, out: Path) -> Path:
    """Build a wheel or sdist of ``source`` into ``out`` through setuptools' PEP 517 hooks, every
    setuptools warning (package data left out, undeclared package, ...) raised as an error."""
    code = f"from setuptools import build_meta as b; print(b.build_{kind}({str(out)!r}))"
    done = subprocess.run(
        [sys.executable, "-W", "error::UserWarning", "-c", code],
        cwd=source,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return out / done.stdout.strip().splitlines()[-1]


def _shipped_sources() -> set[str]:
    """Every module, robot and template of the package folders, as its path in the wheel."""
    names = {"accugrid/__init__.py"}
    for folder in PACKAGE_FOLDERS:
        for path in (ROOT / folder).rglob("*"):
            if path.suffix in (".py", ".yaml", ".j2") and "__pycache__" not in path.parts:
                names.add("accugrid/" + path.relative_to(ROOT).as_posix())
    return names


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    tmp_path = tmp_path_factory.mktemp("build")
    source = _source_copy(tmp_path)
    wheel = _build("wheel", source, tmp_path / "wheel")
    sdist = _build("sdist", source, tmp_path / "sdist")
    return wheel, sdist


def test_wheel_top_level_is_accugrid_alone(built: tuple[Path, Path]) -> None:
    wheel, _ = built
    names = zipfile.ZipFile(wheel).namelist()
    assert {n.split("/")[0] for n in names} == {
        "accugrid",
        wheel.name.split("-py")[0] + ".dist-info",
    }
    # every module and the package data a run needs travel inside the one package
    shipped = {n for n in names if not n.startswith(wheel.name.split("-py")[0])}
    assert shipped == _shipped_sources()
    assert "accugrid/kinematics/robots/kr210.yaml" in names
    assert "accugrid/templates/krl/program.src.j2" in names


def test_wheel_requires_matplotlib_without_an_extra(built: tuple[Path, Path]) -> None:
    """`pip install accugrid` alone must give the plotting commands what they import."""
    wheel, _ = built
    with zipfile.ZipFile(wheel) as whl:
        (meta,) = [n for n in whl.namelist() if n.endswith(".dist-info/METADATA")]
        requires = [
            line.split(":", 1)[1].strip()
            for line in whl.read(meta).decode().splitlines()
            if line.startswith("Requires-Dist:")
        ]
    unconditional = {r.split(">")[0].split("=")[0].strip() for r in requires if ";" not in r}
    assert {"numpy", "scipy", "jinja2", "pin", "pyyaml", "tqdm", "matplotlib"} <= unconditional


def test_sdist_builds_the_same_wheel(built: tuple[Path, Path], tmp_path: Path) -> None:
    """The sdist holds everything its wheel needs: a wheel built from it ships the same files."""
    wheel, sdist = built
    with tarfile.open(sdist) as tar:
        tar.extractall(tmp_path, filter="data")
    (unpacked,) = [p for p in tmp_path.iterdir() if p.is_dir()]
    again = _build("wheel", unpacked, tmp_path / "wheel")
    assert sorted(zipfile.ZipFile(again).namelist()) == sorted(zipfile.ZipFile(wheel).namelist())


def test_source_folders_are_not_importable_by_their_own_names(tmp_path: Path) -> None:
    """From any other folder, the installed accugrid exposes no `kinematics`, `codegen`, ..."""
    code = (
        "import importlib.util as u, accugrid.kinematics.robot;"
        f"print([n for n in {PACKAGE_FOLDERS!r} if u.find_spec(n)])"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, check=True, capture_output=True, text=True
    )
    assert out.stdout.strip() == "[]"


def test_flat_api_resolves_every_public_name() -> None:
    for name in accugrid.__all__:
        assert getattr(accugrid, name) is not None, name
    assert accugrid.load_robot("kr210").name == "kr210"


def test_every_package_lists_names_that_resolve() -> None:
    """Each package (a folder with an __init__.py) declares a non-empty ``__all__``, each name
    importable from it, and ``dir()`` shows them before they are loaded."""
    folders = [ROOT] + [p.parent for f in PACKAGE_FOLDERS for p in (ROOT / f).rglob("__init__.py")]
    for folder in folders:
        name = "accugrid" + "".join("." + part for part in folder.relative_to(ROOT).parts)
        package = importlib.import_module(name)
        assert package.__all__, name
        assert set(package.__all__) <= set(dir(package)), name
        for public in package.__all__:
            assert getattr(package, public) is not None, f"{name}.{public}"


def test_importing_accugrid_loads_no_heavy_library() -> None:
    """The lazy names keep ``import accugrid`` (and the CLI's start) free of numpy's users."""
    code = (
        "import sys, accugrid, accugrid.kinematics, accugrid.compensation, accugrid.codegen;"
        "print(sorted(m for m in ('numpy', 'scipy', 'pinocchio', 'jinja2') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    assert out.stdout.strip() == "[]"
