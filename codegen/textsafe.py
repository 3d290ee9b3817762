"""The only way numbers and user text reach a robot program (DESIGN.md, "Output safety").

- ``fixed`` (and its bulk forms for 100,000-number files: ``fixed_many``, ``fixed_ready`` with
  ``fixed_format``, and ``fixed_bytes``, built by numpy; each property-tested to
  print what ``fixed`` prints): the one fixed-point formatter; never ``str(float)`` or ``%g`` in
  a program. ``fixed_same``: whether two numbers print the same.
- ``comment_text``: user text made harmless inside a one-line comment of any dialect.
- ``krl_identifier``: a valid KRL name ([A-Za-z_][A-Za-z0-9_]*, at most 24 characters, not a
  reserved word: ``KRL_RESERVED``).
"""

from __future__ import annotations

import math
import re
import unicodedata

import numpy as np

__all__ = [
    "COMMENT_MAX",
    "KRL_NAME_MAX",
    "KRL_RESERVED",
    "comment_text",
    "comment_texts",
    "fixed",
    "fixed_bytes",
    "fixed_format",
    "fixed_many",
    "fixed_ready",
    "fixed_same",
    "fixed_texts",
    "krl_identifier",
]

KRL_NAME_MAX = 24
KRL_RESERVED = frozenset(
    """AND ANIN ANOUT AXIS B_AND B_EXOR B_NOT B_OR BOOL BRAKE C_DIS C_ORI C_PTP C_SPL C_VEL CASE
    CHAR CIRC CIRC_REL CONST CONTINUE DECL DEF DEFAULT DEFDAT DEFFCT DELAY DISTANCE DO E6AXIS
    E6POS ELSE END ENDDAT ENDFCT ENDFOR ENDIF ENDLOOP ENDSPLINE ENDSWITCH ENDWHILE ENUM EXIT EXOR
    EXT EXTFCT FALSE FOR FRAME GLOBAL GOTO HALT IF IMPORT IN INT INTERRUPT IS LIN LIN_REL LOOP
    MAXIMUM MINIMUM NOT OFF ON OR POS PRIO PTP PTP_REL PUBLIC REAL REPEAT RESUME RETURN SCIRC SEC
    SIGNAL SLIN SPL SPLINE SPTP STEP STRUC SWITCH THEN TIME_BLOCK TO TRIGGER TRUE UNTIL WAIT WHEN
    WHILE""".split()
)
"""KRL keywords and type names (KUKA System Software 8 manual): never a name we write."""
COMMENT_MAX = 60

_SAFE = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789 _.,:+-=/#@"
_NOT_SAFE = re.compile(f"[^{re.escape(_SAFE)}]")
_SAFE_BYTES = (_SAFE + "\n").encode()  # and the line break that comment_texts joins with
_NOT_IDENT = re.compile(r"[^A-Za-z0-9_]")


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


def fixed_ready(values: np.ndarray, places: int) -> np.ndarray:
    """The values (any shape) to print with ``"%.{places}f"`` (``fixed_format``) so that each
    text is ``fixed(v, places)``: a copy whose values that would print as ``-0.000`` are +0.0.
    Lets a %-template format numbers itself in one pass with the finished lines.

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


def fixed_format(places: int) -> str:
    """The %-conversion that prints a ``fixed_ready`` value as ``fixed`` does."""
    return f"%.{places}f"


def fixed_many(values: np.ndarray, places: int) -> list[str]:
    """``fixed(v, places)`` of every value (N,), formatted in one pass (for 100k-number programs).

    Raises ValueError for NaN or infinity, like ``fixed``.
    """
    ready = fixed_ready(values, places)
    if not len(ready):
        return []
    texts = (((fixed_format(places) + "\n") * len(ready)) % tuple(ready.tolist())).split("\n")
    texts.pop()
    return texts


_EXACT = 2.0**50  # |v| * 10**places below this: the float product's rint is a safe start


def fixed_bytes(values: np.ndarray, places: int) -> tuple[np.ndarray, np.ndarray]:
    """The text ``fixed(v, places)`` of every value (n,) built by numpy, without a Python format
    call per number: (n, w) uint8, each row the text's ASCII bytes NUL-padded on the left, and
    the printed values (n,) float (``float`` of each text).

    The digits are those of q = |v| * 10**places rounded as ``%``-formatting rounds (half to
    even on exact ties): the float product's rint, except for the few products within its
    rounding error of a half, which Python formats. Values too long for that (or places > 15)
    are formatted by ``fixed_many``. Raises ValueError for NaN or infinity, like ``fixed``.
    """
    flat = fixed_ready(values, places).reshape(-1)
    scale = 10.0**places
    with np.errstate(over="ignore"):  # inf: too long, formatted by fixed_many below
        scaled = np.abs(flat) * scale
    if places > 15 or not (scaled < _EXACT).all():
        texts = fixed_many(flat, places)
        cells = np.array([t.rjust(len(max(texts, key=len))) for t in texts], dtype=bytes)
        cells = cells.view(np.uint8).reshape(len(texts), -1)
        cells[cells == 32] = 0
        return cells, np.array(texts, dtype=float)
    rounded = np.rint(scaled)
    close = np.flatnonzero(np.abs(np.abs(scaled - rounded) - 0.5) <= scaled * 2.0**-52)
    rounded = rounded.astype(np.int64)
    if close.size:
        rounded[close] = [
            int(f"{v:.{places}f}".replace(".", "")) for v in np.abs(flat[close]).tolist()
        ]
    whole, part = np.divmod(rounded, 10**places)
    wholes = len(str(int(whole.max(initial=0))))
    cells = np.zeros((len(flat), 1 + wholes + (1 + places if places else 0)), np.uint8)
    cells[:, 0] = np.where((flat < 0) & (rounded > 0), ord("-"), 0)
    for column in range(wholes, 0, -1):  # ones first; leading zeros stay NUL
        shown = (whole > 0) | (column == wholes)
        whole, digit = np.divmod(whole, 10)
        cells[:, column] = np.where(shown, digit + 48, 0)
    if places:
        cells[:, 1 + wholes] = ord(".")
        for column in range(cells.shape[1] - 1, 1 + wholes, -1):
            part, digit = np.divmod(part, 10)
            cells[:, column] = digit + 48
    printed = rounded / scale  # exact integer / exact power of ten: float of the text
    np.negative(printed, out=printed, where=cells[:, 0] > 0)
    signs = np.flatnonzero(cells[:, 0])  # move each sign next to its first digit
    if signs.size:
        first = np.argmax(cells[signs, 1:] > 0, axis=1)
        cells[signs, 0] = 0
        cells[signs, first] = ord("-")
    return cells, printed


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


def krl_identifier(text: str, prefix: str = "P", limit: int = KRL_NAME_MAX) -> str:
    """A KRL identifier derived from user text: invalid characters become ``_``, a leading digit
    or a reserved word gets ``prefix``, and the result is cut to ``limit`` (24) characters."""
    name = _NOT_IDENT.sub("_", unicodedata.normalize("NFKD", str(text)))
    name = name.encode("ascii", "ignore").decode("ascii") or prefix
    if not (name[0].isalpha() or name[0] == "_") or name[:limit].upper() in KRL_RESERVED:
        name = prefix + name
    return name[:limit]
