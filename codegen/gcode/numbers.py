"""G-code number literals read in bulk: the value of every literal from its span in the text.

A G-code literal (``parse._NUMBER``: an optional sign, digits, an optional point and digits, no
exponent) with at most 15 digits is an integer below 2**53 divided by a power of ten up to 1e15;
both are exact doubles and IEEE division rounds correctly, so the quotient is the double nearest
the decimal, which is what ``float(literal)`` gives. Longer literals are read by ``float``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["NUMBER_BYTES", "literal_values"]

NUMBER_BYTES = b"0123456789.+-"  # the bytes a literal is made of
_EXACT_DIGITS = 15  # 10**15 < 2**53: a mantissa of this many digits is an exact double
_WIDEST = _EXACT_DIGITS + 2  # sign and point besides the digits
_POWERS = 10.0 ** np.arange(_EXACT_DIGITS + 1)


def literal_values(text: bytes | np.ndarray, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """``float(text[s:e])`` of every span (N,) of ``text`` (latin-1 bytes, or them as a uint8
    array) that holds one literal; (N,) float."""
    buf = np.frombuffer(text, np.uint8) if isinstance(text, bytes | bytearray) else text
    starts, ends = np.asarray(starts, np.int64), np.asarray(ends, np.int64)
    if not len(starts):
        return np.empty(0)
    width = ends - starts
    mantissa = np.zeros(len(starts), np.int64)
    digits = np.zeros(len(starts), np.int64)
    decimals = np.zeros(len(starts), np.int64)
    point = np.zeros(len(starts), bool)
    for col in range(min(int(width.max()), _WIDEST)):  # column by column, for all literals
        char = buf[np.minimum(starts + col, len(buf) - 1)]
        live = col < width
        digit = live & (char >= 48) & (char <= 57)
        mantissa = np.where(digit, mantissa * 10 + (char - 48), mantissa)
        digits += digit
        decimals += digit & point
        point |= live & (char == 46)
    values = mantissa / _POWERS[np.minimum(decimals, _EXACT_DIGITS)]
    values = np.where(buf[starts] == ord("-"), -values, values)
    for k in np.flatnonzero((digits > _EXACT_DIGITS) | (width > _WIDEST)).tolist():
        values[k] = float(bytes(buf[starts[k] : ends[k]]).decode("latin-1"))
    return values
