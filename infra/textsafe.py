"""The only way numbers and user text reach a robot program (docs/guarantees.md, "Output safety").

- ``fixed`` (and its bulk forms for 100,000-number files: ``fixed_many``, one %-pass, and
  ``fixed_bytes``, built by numpy; each property-tested to print what ``fixed`` prints): the one
  fixed-point formatter; never ``str(float)`` or ``%g`` in
  a program. ``fixed_same``: whether two numbers print the same.
- ``comment_text``: user text made harmless inside a one-line comment of any dialect.
"""

from __future__ import annotations

import functools
import math
import re
import unicodedata

import numpy as np

__all__ = [
    "COMMENT_MAX",
    "comment_text",
    "comment_texts",
    "fixed",
    "fixed_bytes",
    "fixed_many",
    "fixed_same",
    "fixed_texts",
]

COMMENT_MAX = 60

_SAFE = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789 _.,:+-=/#@"
_NOT_SAFE = re.compile(f"[^{re.escape(_SAFE)}]")
_SAFE_BYTES = (_SAFE + "\n").encode()  # and the line break that comment_texts joins with


def fixed(value: float, decimals: int = 3) -> str:
    """Format a finite number with exactly ``decimals`` places; ``-0.000`` becomes ``0.000``.

    Raises ValueError for NaN or infinity: such a number must never reach a program.
    """
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"refusing to write a non-finite number ({value}) into a program")
    text = f"{value:.{decimals}f}"
    if text.startswith("-") and not text.strip("-0."):
        text = text[1:]
    return text


def _ready(values: np.ndarray, places: int) -> np.ndarray:
    """The values (any shape) to print with ``"%.{places}f"`` so that each text is
    ``fixed(v, places)``: a copy whose values that would print as ``-0.000`` are +0.0.

    Raises ValueError for NaN or infinity, like ``fixed``.
    """
    values = np.array(values, dtype=float, order="C")
    if not np.isfinite(values).all():
        bad = values[~np.isfinite(values)][0]
        raise ValueError(f"refusing to write a non-finite number ({bad}) into a program")
    small = np.flatnonzero(np.signbit(values) & (values > -(10.0**-places)))
    if small.size:
        flat = values.reshape(-1)
        texts = ((f"%.{places}f\n" * small.size) % tuple(flat[small].tolist())).split("\n")
        zero = np.array(texts[:-1]) == "-" + fixed(0.0, places)
        flat[small[zero]] = 0.0
    return values


def fixed_many(values: np.ndarray, places: int) -> list[str]:
    """``fixed(v, places)`` of every value (N,), formatted in one pass (for 100k-number programs).

    Raises ValueError for NaN or infinity, like ``fixed``.
    """
    ready = _ready(values, places)
    if not len(ready):
        return []
    texts = ((f"%.{places}f\n" * len(ready)) % tuple(ready.tolist())).split("\n")
    texts.pop()
    return texts


_EXACT = 2.0**50  # |v| * 10**places below this: the float product's rint is a safe start
_GROUP = 4  # text bytes written at once: one uint32 from a table per group
_CHUNK = 1 << 15  # values formatted at a time by fixed_bytes


@functools.lru_cache(maxsize=64)
def _group_table(places: int, k: int) -> tuple[int, int, np.ndarray]:
    """Group k of a ``fixed_bytes`` text: its bytes 4k+3 .. 4k counted from the right end (the
    last decimal is byte 0, the point byte ``places``), left to right in memory. Returns (low,
    c, table): low the digits of q (the text's digits as one integer) right of the group, c the
    digits in it (4, or 3 beside the point), and table (3 * 10**c,) uint32, each the group's 4
    bytes for r (its digits as an integer) in section 0 (r + 0: every digit shown), 1 (r + 10**c:
    the group holds the first digit or is left of it: leading zeros NUL, except the ones digit
    and the decimals, always shown) or 2 (r + 2 * 10**c: as 1, with the ``-`` left of the first
    shown byte if the group has room, at the right end if it shows nothing)."""
    slots = []  # digit index in q of each byte, left to right; -1: the point
    for position in range(_GROUP * k + _GROUP - 1, _GROUP * k - 1, -1):
        if places and position == places:
            slots.append(-1)
        else:
            slots.append(position - 1 if places and position > places else position)
    low = min(d for d in slots if d >= 0)
    size = 10 ** sum(d >= 0 for d in slots)
    r = np.arange(size)
    table = np.zeros((3, size, _GROUP), np.uint8)
    for b, d in enumerate(slots):
        if d < 0:
            table[:, :, b] = ord(".")
            continue
        digit = (r // 10 ** (d - low) % 10 + ord("0")).astype(np.uint8)
        table[0, :, b] = digit
        table[1:, :, b] = np.where((d <= places) | (r >= 10 ** (d - low)), digit, 0)
    shown = table[2] > 0
    first = np.where(shown.any(axis=1), np.argmax(shown, axis=1), _GROUP)
    room = np.flatnonzero(first > 0)
    table[2, room, first[room] - 1] = ord("-")
    table = table.reshape(-1, _GROUP).view(np.uint32).reshape(-1)
    table.flags.writeable = False  # shared by every call (cached)
    return low, size, table


def fixed_bytes(values: np.ndarray, places: int) -> tuple[np.ndarray, np.ndarray]:
    """The text ``fixed(v, places)`` of every value (n,) built by numpy, without a Python format
    call per number: (n, w) uint8, C-contiguous, each row the text's ASCII bytes NUL-padded on
    the left (w = 1 + the digits of the largest whole part + 1 + places, or without the point
    and decimals at 0 places), and the printed values (n,) float (``float`` of each text).

    The digits are those of q = |v| * 10**places rounded as ``%``-formatting rounds (half to
    even on exact ties): the float product's rint, except for the few products within its
    rounding error of a half, which Python formats. Each row is written 4 bytes at a time from
    tables of 4-digit groups (``_group_table``), the leading zeros and the sign chosen by the
    table. Values too long for that (or places > 15) are formatted by ``fixed_many``. Raises
    ValueError for NaN or infinity, like ``fixed``.
    """
    flat = np.asarray(values, dtype=float).reshape(-1)
    scale = 10.0**places
    with np.errstate(over="ignore", invalid="ignore"):  # inf, NaN: formatted by fixed_many
        top = max(flat.max(initial=0.0), -flat.min(initial=0.0)) * scale  # NaN stays NaN
    if places > 15 or not top < _EXACT:
        return _fixed_bytes_long(flat, places)
    n = len(flat)
    bound = int(np.rint(top)) + 1  # no q above it (a close product's q is its rint +- 1)
    # 10**(digits - 1) is at most max(bound, 10**places): an int32 holds it and ten times it
    q = np.empty(n, np.int32 if 10 * max(bound, 10**places) < 2**31 else np.int64)
    negative = np.empty(n, bool)
    printed = np.empty(n)
    for a in range(0, n, _CHUNK):  # a block at a time: its temporaries stay in the cache
        b = min(a + _CHUNK, n)
        _rounded(flat[a:b], places, top, q[a:b], negative[a:b], printed[a:b])
    wholes = len(str(int(q.max(initial=0)) // 10**places))
    width = 1 + wholes + (1 + places if places else 0)
    return _text_cells(q, negative, places, width), printed


def _rounded(
    values: np.ndarray, places: int, top: float, q: np.ndarray, negative: np.ndarray, printed
) -> None:
    """For ``fixed_bytes``, of finite values (m,) whose |v| * 10**places are at most ``top``
    (below 2**50): into q (m,) int their digits as one integer (|v| * 10**places rounded as
    ``%``-formatting rounds), into ``negative`` (m,) bool where the text has a ``-`` (v < 0 and
    q > 0), into ``printed`` (m,) float the value of each text."""
    scale = 10.0**places
    scaled = np.multiply(values, scale)
    rounded = np.rint(scaled, out=printed)  # sign and all: rint(-x) is -rint(x)
    error = np.subtract(scaled, rounded, out=scaled)
    np.abs(error, out=error)
    near = np.flatnonzero(error >= 0.5 - top * 2.0**-51)  # holds all those within top * 2**-52
    close = near[np.abs(error[near] - 0.5) <= np.abs(values[near]) * scale * 2.0**-52]
    if close.size:
        rounded[close] = [int(f"{v:.{places}f}".replace(".", "")) for v in values[close].tolist()]
    np.less(rounded, 0.0, out=negative)  # not -0.0: a small negative printed as 0
    q[...] = rounded
    np.abs(q, out=q)
    np.divide(rounded, scale, out=printed)  # exact integer / power of ten: the text's value
    printed += 0.0  # -0.0 is 0.0


def _text_cells(q: np.ndarray, negative: np.ndarray, places: int, width: int) -> np.ndarray:
    """The (n, width) uint8 cells of ``fixed_bytes``: q (n,) the digits of each text as one
    integer, ``negative`` (n,) where a ``-`` goes left of the first digit. Every row is written
    in groups of 4 bytes (``_group_table``) from the right end, through uint32 views of the
    cells with the row length as stride, a block of rows at a time from the last block: the
    leftmost group of a row may start up to 3 bytes before it, over the end of the row before,
    which is written after. A sign column left alone in a group (width 4m + 1) is written as
    bytes."""
    n = len(q)
    lone = width % _GROUP == 1  # the sign column alone in the leftmost group
    groups = (width - lone + _GROUP - 1) // _GROUP
    pitch = max(width, _GROUP)  # narrower rows would overlap more than the row before
    over = _GROUP * groups + lone - pitch
    text = np.empty(over + n * pitch, np.uint8)
    for a in range((n - 1) // _CHUNK * _CHUNK, -1, -_CHUNK):  # n = 0: none
        b = min(a + _CHUNK, n)
        _write_rows(text, over + a * pitch, pitch, q[a:b], negative[a:b], places, width, groups)
    cells = text[over:].reshape(n, pitch)
    return cells if pitch == width else np.ascontiguousarray(cells[:, pitch - width :])


def _write_rows(
    text: np.ndarray,
    start: int,
    pitch: int,
    q: np.ndarray,
    negative: np.ndarray,
    places: int,
    width: int,
    groups: int,
) -> None:
    """The rows of ``_text_cells`` for q (m,) and ``negative`` (m,), into ``text`` from byte
    ``start`` on, ``pitch`` bytes apart; their last ``groups`` groups of 4 bytes and, if the
    row is longer, its sign column."""
    m = len(q)
    always = places + (2 if places else 1)  # text bytes always shown: decimals, point, ones
    signs = bool(negative.any())

    def signed(position: int) -> np.ndarray:
        """Where the ``-`` is at byte ``position`` (from the right) or left of it."""
        if position <= always:
            return negative
        return negative & (q >= 10 ** (position - (2 if places else 1)))

    if width > _GROUP * groups:
        column = np.ndarray((m,), np.uint8, text, start, (pitch,))
        if signs:
            np.multiply(signed(width - 1), np.uint8(ord("-")), out=column)
        else:
            column[...] = 0
    above = None  # q's digits left of the group
    for k in range(groups - 1, -1, -1):
        low, size, table = _group_table(places, k)
        here = q // q.dtype.type(10**low) if low else q
        code = None  # the table's section of each row: 0, 1 or 2 (times size)
        if above is None:  # the leftmost group (with digits): nothing above it
            index = np.add(size, here)
            if signs:
                code = signed(_GROUP * k).astype(q.dtype)
        else:
            index = here - above * size
            if _GROUP * (k + 1) > always:  # leading zeros or the sign may fall in this group
                top = above == 0
                code = top.astype(q.dtype)
                if signs:
                    code += top & signed(_GROUP * k)
        if code is not None:
            code *= size
            index += code
        rows = np.ndarray((m,), np.uint32, text, start + pitch - _GROUP * (k + 1), (pitch,))
        rows[...] = np.take(table, index)
        above = here


def _fixed_bytes_long(flat: np.ndarray, places: int) -> tuple[np.ndarray, np.ndarray]:
    """``fixed_bytes`` of values too long for its integer digits (or places > 15), through
    ``fixed_many``; raises ValueError for NaN or infinity."""
    texts = fixed_many(flat, places)
    if not texts:
        return np.zeros((0, 3 + places), np.uint8), np.zeros(0)
    cells = np.array([t.rjust(len(max(texts, key=len))) for t in texts], dtype=bytes)
    cells = cells.view(np.uint8).reshape(len(texts), -1)
    cells[cells == 32] = 0
    return cells, np.array(texts, dtype=float)


def fixed_same(a: np.ndarray, b: np.ndarray, places: int) -> np.ndarray:
    """Whether ``fixed(a, places) == fixed(b, places)``, elementwise (shapes broadcast), without
    formatting where the numbers decide it: equal values print the same, values more than one
    unit of the last place apart never do (each text is within half a unit of its value); only
    the pairs closer than that, but not equal, are formatted and compared."""
    a, b = np.broadcast_arrays(np.asarray(a, dtype=float), np.asarray(b, dtype=float))
    same = a == b
    unsure = ~same & (np.abs(a - b) <= 10.0**-places * (1.0 + 1e-9))  # margin: float rounding
    if unsure.any():
        same[unsure] = np.array(fixed_many(a[unsure], places)) == fixed_many(b[unsure], places)
    return same


def fixed_texts(values: np.ndarray, decimals: int, distinct: bool = False) -> np.ndarray:
    """``fixed(v, decimals)`` of every value (via ``fixed_many``), as an object array of the same
    shape. ``distinct``: format each distinct value once (where values repeat, e.g. angles)."""
    values = np.asarray(values, dtype=float)
    if not distinct:
        return np.array(fixed_many(values.ravel(), decimals), dtype=object).reshape(values.shape)
    unique, inverse = np.unique(values.ravel(), return_inverse=True)
    texts = np.array(fixed_many(unique, decimals), dtype=object)
    return texts[inverse.ravel()].reshape(values.shape)


def comment_text(text: str, limit: int = COMMENT_MAX) -> str:
    """User text reduced to a safe single-line comment body.

    Accents are folded to ASCII, and anything that could end a comment or start a statement in
    KRL or RS274NGC (newlines, ``;``, ``(``, ``)``, ``%``, ``&``, quotes, braces, control
    characters) becomes ``_``; the result is at most ``limit`` characters.
    """
    folded = unicodedata.normalize("NFKD", str(text)).encode("ascii", "ignore").decode("ascii")
    cleaned = _NOT_SAFE.sub("_", folded).strip()
    return cleaned[:limit]


def comment_texts(texts: list[str], limit: int = COMMENT_MAX, prefix: str = "") -> list[str]:
    """``comment_text(prefix + t, limit)`` of every text, for 100k-hole programs: when every text
    is already safe (the usual ids), only the cut to ``limit`` is left to do."""
    if prefix:
        texts = [prefix + t for t in texts]
    joined = "\n".join(texts)
    if (
        not joined.isascii()  # a character to fold
        or joined.encode("ascii").translate(None, _SAFE_BYTES)  # one to replace
        or joined.count("\n") >= len(texts)  # a line break inside a text
        or joined[:1] == " "  # a space to strip
        or joined[-1:] == " "
        or "\n " in joined
        or " \n" in joined
    ):
        return [comment_text(t, limit) for t in texts]
    return texts if max(map(len, texts), default=0) <= limit else [t[:limit] for t in texts]
