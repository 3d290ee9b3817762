"""The distribution installs one import package, ``accugrid``, and nothing else at the top level."""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import accugrid

ROOT = Path(__file__).resolve().parents[1]
PACKAGE_FOLDERS = ("kinematics", "compensation", "codegen", "templates")


def test_wheel_top_level_is_accugrid_alone(tmp_path: Path) -> None:
    # build from a copy: setuptools keeps a build/ folder beside the sources it builds
    source = tmp_path / "source"
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    for folder in PACKAGE_FOLDERS:
        shutil.copytree(ROOT / folder, source / folder, ignore=ignore)
    for name in ("pyproject.toml", "__init__.py", "README.md"):
        shutil.copy(ROOT / name, source / name)
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation"]
        + ["-w", str(tmp_path), str(source)],
        check=True,
        capture_output=True,
    )
    (wheel,) = tmp_path.glob("accugrid-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert {n.split("/")[0] for n in names} == {
        "accugrid",
        wheel.name.split("-py")[0] + ".dist-info",
    }
    # the package data a run needs travels inside the one package
    assert "accugrid/kinematics/robots/kr210.yaml" in names
    assert "accugrid/templates/krl/program.src.j2" in names
    assert "accugrid/codegen/commands/krl.py" in names


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
