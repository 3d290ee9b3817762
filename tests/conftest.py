"""Shared test fixtures: paths to the examples, ../shared/realworld and ../shared/realdata."""

from __future__ import annotations

import os
import shlex
import shutil
from pathlib import Path

import pytest
from hypothesis import settings

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
REALWORLD = ROOT.parent / "shared" / "realworld"
REALDATA = ROOT.parent / "shared" / "realdata"  # real tracker measurements (README.md in each)
RS274 = shutil.which("rs274") or ("/usr/bin/rs274" if os.path.exists("/usr/bin/rs274") else None)

# Property tests must stay quick on a shared 2-core machine; CI uses the same profile.
settings.register_profile("accugrid", max_examples=60, deadline=None)
settings.load_profile("accugrid")


@pytest.fixture
def realworld() -> Path:
    """../shared/realworld (CI has ../shared beside the checkout)."""
    if not REALWORLD.is_dir():
        pytest.fail(f"{REALWORLD} is missing: the real-world programs must sit beside the checkout")
    return REALWORLD


@pytest.fixture(scope="session")
def realdata() -> Path:
    """../shared/realdata: real tracker measurements (CI has ../shared beside the checkout)."""
    if not REALDATA.is_dir():
        pytest.fail(f"{REALDATA} is missing: the real tracker data must sit beside the checkout")
    return REALDATA


@pytest.fixture(scope="module")
def rs274(tmp_path_factory: pytest.TempPathFactory) -> str:
    """LinuxCNC's standalone RS274NGC interpreter; skipped where it is not installed and CI is
    not set (on CI a missing rs274 is a failure).

    rs274 memory-maps a tool table at ``$HOME/.tool.mmap`` and truncates it at start, so two runs
    sharing a home (two test processes at once) kill each other with SIGBUS: the path returned is
    a wrapper that gives each test module's runs a home of their own."""
    if RS274 is None:
        if os.environ.get("CI"):
            pytest.fail("rs274 (LinuxCNC) is not installed, and CI is set: .ci/run must install it")
        pytest.skip("rs274 (LinuxCNC's standalone interpreter) is not installed; CI runs this")
    home = tmp_path_factory.mktemp("rs274_home")
    wrapper = home / "rs274"
    wrapper.write_text(f'#!/bin/sh\nHOME={shlex.quote(str(home))} exec {shlex.quote(RS274)} "$@"\n')
    wrapper.chmod(0o755)
    return str(wrapper)
