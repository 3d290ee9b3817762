"""Fixed-point text of a whole table of numbers at once, for files of 100,000 rows: the text
``textsafe.fixed`` gives each number, built as bytes by numpy instead of one Python format call
per number.

A number is the integer q = |v| * 10**places rounded as ``"%.{places}f"`` rounds (correctly,
half to even on exact ties: ``numpy.rint`` of the float product, and Python's own formatting for
the few values so close to a half that the product's rounding could decide), printed as digits
with the point put in; ``-`` only when q > 0, so ``-0.0000`` is ``0.0000`` as in ``fixed``.
"""

from __future__ import annotations

import numpy as np

from accugrid.codegen.textsafe import fixed_many

__all__ = ["fixed_rows"]

_EXACT = 2.0**50  # |v| * 10**places below this: rint of the product is a safe start
_POW10_INT = 10 ** np.arange(19, dtype=np.int64)
_GROUP = 10_000  # digits are cut four at a time, each group's text one uint32 (4 bytes)


def _word_of(chars: bytes) -> np.uint32:
    """Up to four bytes (NUL-padded) read as one uint32, in memory order."""
    return np.frombuffer(chars.ljust(4, b"\0"), dtype=np.uint32)[0]


def _group_texts(drop: int | None = None) -> np.ndarray:
    """The ASCII text of 0..9999 as four digits, zero-padded, each read as one uint32 (10000,);
    the first ``drop`` bytes NUL, or (None) every leading zero (all four for 0)."""
    value = np.arange(_GROUP)
    text = (value[:, None] // np.array([1000, 100, 10, 1]) % 10 + 48).astype(np.uint8)
    if drop is None:
        zeros = 4 - np.searchsorted(_POW10_INT, value, side="right")
        text[np.arange(4) < zeros[:, None]] = 0
    else:
        text[:, :drop] = 0
    return text.view(np.uint32).reshape(-1)


_DIGITS = _group_texts(0)
# the leading group of a number: a higher group (0: all NUL), the ones (0: "0")
_LEADING = _group_texts()
_ONES = _LEADING.copy()
_ONES[0] = _word_of(bytes([0, 0, 0, ord("0")]))


def fixed_rows(values: np.ndarray, places: int, sep: str = ",") -> list[str]:
    """Each row of ``values`` (m, k) as ``sep.join(fixed(v, places) for v in row)``.

    ``places`` 0..15; ``sep`` is one ASCII character other than NUL and newline. Raises
    ValueError for NaN or infinity, like ``fixed``.
    """
    values = np.asarray(values, dtype=float)
    m, k = values.shape
    if not 0 <= places <= 15:
        raise ValueError(f"places must be 0..15, got {places}")
    if not (len(sep) == 1 and sep.isascii() and sep not in "\0\n"):
        raise ValueError(f"separator must be one ASCII character, got {sep!r}")
    flat = values.reshape(-1)
    if not np.isfinite(flat).all():
        bad = flat[~np.isfinite(flat)][0]
        raise ValueError(f"refusing to write a non-finite number ({bad}) into a program")
    with np.errstate(over="ignore"):  # inf: too long, formatted by Python below
        scaled = np.abs(flat) * 10.0**places
    if not m * k or not (scaled < _EXACT).all():  # no number, or one too long to do here
        texts = np.array(fixed_many(flat, places), dtype=object).reshape(m, k)
        return [sep.join(row) for row in texts.tolist()]
    rounded = _rounded(flat, scaled, places)
    whole, part = np.divmod(rounded, _POW10_INT[places])
    wholes = -(-len(str(int(whole.max()))) // 4)
    parts = -(-places // 4)
    # each number as uint32 words: separator and sign (NUL padded; the row's first number has a
    # newline, the first row's nothing), the whole digits, the point, the decimals; every NUL
    # is dropped at the end
    words = np.empty((m, k, 1 + wholes + (1 + parts if places else 0)), dtype=np.uint32)
    cells = words.reshape(m * k, -1)
    sign = _word_of(sep.encode() + b"-")
    cells[:, 0] = np.where((flat < 0) & (rounded > 0), sign, _word_of(sep.encode()))
    words[:, 0, 0] ^= _word_of(sep.encode()) ^ _word_of(b"\n")  # the sign byte stays
    words[0, 0, 0] ^= _word_of(b"\n")
    for g in range(wholes):  # from the right; above the leading digit, NUL
        whole, group = np.divmod(whole, _GROUP)
        short = _ONES if g == 0 else _LEADING
        cells[:, wholes - g] = np.where(whole > 0, _DIGITS[group], short[group])
    if places:
        cells[:, 1 + wholes] = _word_of(b".")
        for g in range(parts):  # from the right; the first group shows its last digits only
            part, group = np.divmod(part, _GROUP)
            table = _DIGITS if g < parts - 1 else _group_texts(4 * parts - places)
            cells[:, 1 + wholes + parts - g] = table[group]
    text = words.view(np.uint8).reshape(-1)
    return text[text != 0].tobytes().decode("ascii").split("\n")


def _rounded(values: np.ndarray, scaled: np.ndarray, places: int) -> np.ndarray:
    """|values| * 10**places (n,) rounded to int64 as ``"%.{places}f"`` rounds. ``scaled`` is
    that float product (one rounding, relative error <= 2**-53, all below 2**50): its rint is
    the answer unless the product lies within that error of a half; those values are
    formatted by Python."""
    nearest = np.rint(scaled)
    close = np.flatnonzero(np.abs(np.abs(scaled - nearest) - 0.5) <= scaled * 2.0**-52)
    rounded = nearest.astype(np.int64)
    if close.size:
        rounded[close] = [
            int(f"{v:.{places}f}".replace(".", "")) for v in np.abs(values[close]).tolist()
        ]
    return rounded
