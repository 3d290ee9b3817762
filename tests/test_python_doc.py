"""docs/python.md runs as written: its session is a doctest run from the repository root."""

from __future__ import annotations

import doctest
import os

from conftest import ROOT


def test_the_python_page_runs_as_written():
    here = os.getcwd()
    os.chdir(ROOT)  # the page's paths are relative to the repository
    try:
        result = doctest.testfile(
            str(ROOT / "docs" / "python.md"),
            module_relative=False,
            optionflags=doctest.NORMALIZE_WHITESPACE,
            verbose=False,
        )
    finally:
        os.chdir(here)
    assert result.attempted >= 30
    assert result.failed == 0
