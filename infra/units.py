"""How messages and reports write lengths and angles: one formatter for a vector of numbers."""

from __future__ import annotations

import numpy as np

__all__ = ["mm_text"]


def mm_text(values: np.ndarray, decimals: int = 3) -> str:
    """A vector (n,) of mm (or deg) as ``(x, y, z)`` with ``decimals`` places, for messages."""
    return "(" + ", ".join(f"{x:.{decimals}f}" for x in np.asarray(values, dtype=float)) + ")"
