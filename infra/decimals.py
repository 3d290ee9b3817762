"""Decimal literals read in bulk from a file's bytes: the one exact fast reader behind the points
CSV, the G-code and the KRL readers of 100,000-line files.

A plain decimal is an optional sign, at most 8 digits before an optional point and at most 7
after it, at least one digit. Its digits as an integer below 2**53 divided by a power of ten up
to 1e7, both exact doubles, is the correctly rounded quotient: what ``float(literal)`` gives
(``-0`` too). Anything else (exponents, blanks, longer literals) is reported as not plain and
left to the caller's exact path.

Digits are read eight at a time from one little-endian 64-bit word: the bytes checked to be
digits by two masks, then combined pairwise, by quads and by eights with a multiply and shift
each (SWAR: SIMD within a register).
"""

from __future__ import annotations

import numpy as np

__all__ = ["read_decimals", "words_at"]

_U64 = np.dtype("<u8")
_POW10 = 10.0 ** np.arange(16)  # exact in float64
_ZEROS = np.uint64(0x3030303030303030)  # "00000000"
_HIGH = np.uint64(0xF0F0F0F0F0F0F0F0)
_SIX = np.uint64(0x0606060606060606)
_POINTS = np.uint64(0x2E2E2E2E2E2E2E2E)  # "........"
_LOW7 = np.uint64(0x7F7F7F7F7F7F7F7F)
_LOW4 = np.uint64(0x0F0F0F0F0F0F0F0F)
# the last L bytes of a word kept (the digits), the others made "0": by L = 0..8
_KEEP = np.array([((1 << (8 * n)) - 1) << (8 * (8 - n)) for n in range(9)], np.uint64)
_FILL = _ZEROS & ~_KEEP
_AFTER_BIAS = 7 + (1023 + 7) // 8  # 7 - byte, byte = (biased exponent - 1023 - 7) / 8
_BLOCK = 1 << 16  # literals read at a time


def words_at(buf: np.ndarray, at: np.ndarray) -> np.ndarray:
    """The 8 bytes at each offset ``at`` (k,) of ``buf`` (uint8, at least 8 bytes) as one
    little-endian uint64 (k,); offsets out of ``buf`` read its first or last 8 bytes."""
    words = np.ndarray((len(buf) - 7,), _U64, buffer=buf, strides=(1,))  # unaligned, overlapping
    return words[np.clip(at, 0, len(buf) - 8)]


def read_decimals(
    buf: np.ndarray, start: np.ndarray, end: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The literals ``buf[start[i]:end[i]]`` (k,) read as plain decimals.

    ``buf`` uint8 (a file's bytes), ``start``/``end`` (k,) int byte offsets. Returns values (k,)
    float (equal to ``float(literal)``), decimals (k,) int64 (digits after the point) and plain
    (k,) bool; where plain is False the value and decimals are undefined. Read a block of
    literals at a time: the temporaries stay in the cache."""
    if len(buf) < 8:  # a word must fit
        buf = np.concatenate([buf, np.zeros(8 - len(buf), np.uint8)])
    start = np.asarray(start, np.int64)
    end = np.asarray(end, np.int64)
    values = np.empty(len(start))
    after = np.empty(len(start), np.int64)
    plain = np.empty(len(start), bool)
    for a in range(0, len(start), _BLOCK):
        b = a + _BLOCK
        _read_block(buf, start[a:b], end[a:b], values[a:b], after[a:b], plain[a:b])
    return values, after, plain


def _read_block(
    buf: np.ndarray,
    start: np.ndarray,
    end: np.ndarray,
    values: np.ndarray,
    after: np.ndarray,
    plain: np.ndarray,
) -> None:
    """``read_decimals`` of a block of literals (m,), into ``values``, ``after`` and ``plain``
    (m,)."""
    first = np.take(buf, start, mode="clip")
    minus = first == 45
    signed = minus | (first == 43)
    signed &= start < end
    minus &= signed
    size = end - start
    size -= signed  # digits and point
    last = _ending(buf, end)
    x = last ^ _POINTS
    dots = ~(((x & _LOW7) + _LOW7) | x | _LOW7)  # 0x80 at a "."
    dots &= np.take(_KEEP, np.clip(size, 0, 8))
    has_point = dots != 0
    # the highest "." (the float's exponent: 8 * byte + 7): 7 - byte digits after it
    byte = dots.astype(np.float64).view(np.int64)
    byte >>= 52
    np.subtract(_AFTER_BIAS, byte >> 3, out=after)
    after *= has_point
    before = size - after
    before -= has_point
    np.less_equal(before, 8, out=plain)
    plain &= (before + after) >= 1
    part, part_ok = _whole(last, after)
    whole, whole_ok = _whole(_ending(buf, end - after - has_point), np.clip(before, 0, 8))
    plain &= whole_ok
    plain &= part_ok
    scale = np.take(_POW10, after)
    np.multiply(whole.view(np.int64), scale, out=values)
    values += part.view(np.int64)  # exact: integers below 2**53
    values /= scale
    np.copysign(values, np.subtract(0.5, minus), out=values)


def _whole(word: np.ndarray, count: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The integer (k,) uint64 the last ``count`` (k,) (0 to 8) bytes of each word (k,) write,
    and whether they are all ASCII digits (k,)."""
    word = word & np.take(_KEEP, count)
    word |= np.take(_FILL, count)
    ok = (word & _HIGH) == _ZEROS
    ok &= ((word + _SIX) & _HIGH) == _ZEROS
    v = word & _LOW4  # the digits' values, the first (highest place) in the lowest byte
    v *= np.uint64(10 << 8 | 1)  # each pair: 10 * first + second, in the pair's high byte
    v >>= np.uint64(8)
    v &= np.uint64(0x00FF00FF00FF00FF)
    v *= np.uint64(100 << 16 | 1)  # each quad: 100 * first pair + second
    v >>= np.uint64(16)
    v &= np.uint64(0x0000FFFF0000FFFF)
    v *= np.uint64(10000 << 32 | 1)  # 10000 * first quad + second
    v >>= np.uint64(32)
    return v, ok


def _ending(buf: np.ndarray, end: np.ndarray) -> np.ndarray:
    """The 8 bytes before each offset ``end`` (k,) as words (k,) (the last byte highest)."""
    word = words_at(buf, end - 8)
    near = np.flatnonzero(end < 8)  # the first bytes of the buffer: read at 0, moved up
    word[near] <<= (8 * (8 - end[near])).astype(np.uint64)
    return word
