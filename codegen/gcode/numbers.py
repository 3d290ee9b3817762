"""G-code number literals read in bulk: the value of every literal from its span in the text.

A G-code literal (``parse._NUMBER``: an optional sign, digits, an optional point and digits, no
exponent) is read by the one bulk decimal reader (``infra.decimals``), exactly as
``float(literal)`` reads it, with its decimals; the few too long for it are read by ``float``.
"""

from __future__ import annotations

import numpy as np

from accugrid.infra.csvtable import decimals_of
from accugrid.infra.decimals import read_decimals

__all__ = ["NUMBER_BYTES", "literal_values"]

NUMBER_BYTES = b"0123456789.+-"  # the bytes a literal is made of


def literal_values(
    text: bytes | np.ndarray, starts: np.ndarray, ends: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``float(text[s:e])`` of every span (N,) of ``text`` (latin-1 bytes, or them as a uint8
    array) that holds one literal, and its decimals as written (digits after its point, 0
    without one): (N,) float and (N,) int."""
    buf = np.frombuffer(text, np.uint8) if isinstance(text, bytes | bytearray) else text
    starts, ends = np.asarray(starts, np.int64), np.asarray(ends, np.int64)
    values, decimals, plain = read_decimals(buf, starts, ends)
    for k in np.flatnonzero(~plain).tolist():
        literal = bytes(buf[starts[k] : ends[k]]).decode("latin-1")
        values[k], decimals[k] = float(literal), decimals_of(literal)
    return values, decimals
