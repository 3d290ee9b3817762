"""Shared test fixtures: paths to the project's examples and to ../shared/realworld."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import settings

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
REALWORLD = ROOT.parent / "shared" / "realworld"

# Property tests must stay quick on a shared 2-core machine; CI uses the same profile.
settings.register_profile("accugrid", max_examples=60, deadline=None)
settings.load_profile("accugrid")


@pytest.fixture
def realworld() -> Path:
    """../shared/realworld (CI has ../shared beside the checkout)."""
    if not REALWORLD.is_dir():
        pytest.fail(f"{REALWORLD} is missing: the real-world programs must sit beside the checkout")
    return REALWORLD
