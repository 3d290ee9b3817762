"""G-code number literals read in bulk: the value of every literal from its span in the text.

A G-code literal (``parse._NUMBER``: an optional sign, digits, an optional point and digits, no
exponent) is read by the one bulk decimal reader (``kinematics.decimals``), exactly as
``float(literal)`` reads it; the few too long for it are read by ``float``.
"""

from __future__ import annotations

import numpy as np

from accugrid.kinematics.decimals import read_decimals

__all__ = ["NUMBER_BYTES", "literal_values"]

NUMBER_BYTES = b"0123456789.+-"  # the bytes a literal is made of


def literal_values(text: bytes | np.ndarray, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """``float(text[s:e])`` of every span (N,) of ``text`` (latin-1 bytes, or them as a uint8
    array) that holds one literal; (N,) float."""
    buf = np.frombuffer(text, np.uint8) if isinstance(text, bytes | bytearray) else text
    starts, ends = np.asarray(starts, np.int64), np.asarray(ends, np.int64)
    values, _, plain = read_decimals(buf, starts, ends)
    for k in np.flatnonzero(~plain).tolist():
        values[k] = float(bytes(buf[starts[k] : ends[k]]).decode("latin-1"))
    return values
