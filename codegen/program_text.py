"""Program text shared by the dialects' readers, writers and rewriters: reading a program byte for
byte, lines, number literals, precision, replacing spans of text, comment blocks and the names a
controller takes (identifiers, a program named after its output file).

Programs are handled as bytes decoded as latin-1 (one character per byte), so any encoding and any
line ending survives a rewrite unchanged; offsets are character (= byte) offsets.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from accugrid.infra.csvtable import decimals_of
from accugrid.infra.errors import InputError
from accugrid.infra.inputfile import read_input_bytes
from accugrid.infra.textsafe import comment_text, fixed, fixed_many

__all__ = [
    "MAX_BYTES",
    "MIN_PLACES_INCH",
    "MIN_PLACES_MM",
    "UTF8_BOM",
    "check_text",
    "comment_block",
    "decimals_of",
    "distinct_ints",
    "formatted",
    "identifier_problem",
    "insert_after_lines",
    "number_text",
    "precision",
    "read_program",
    "row_counts",
    "splice",
    "split_lines",
    "stem_name",
]

MAX_BYTES = 64 * 2**20
MIN_PLACES_MM = 2  # a corrected number is never coarser than 0.01 mm ...
MIN_PLACES_INCH = 3  # ... or 0.001 in, unless the user asks (--decimals)
UTF8_BOM = "\xef\xbb\xbf"  # as latin-1 text
_FRACTION_RE = re.compile(r"\.(\d*+)")
_IDENTIFIER = re.compile(r"[A-Za-z][A-Za-z0-9_]*")


def read_program(path: str | os.PathLike[str], max_bytes: int = MAX_BYTES) -> str:
    """A program's bytes as latin-1 text (byte-preserving); InputError when unreadable or huge."""
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > max_bytes:
            raise InputError(
                f"file is {size / 2**20:.1f} MiB, over the limit of {max_bytes / 2**20:.1f} MiB "
                "(--max-mb)",
                os.fspath(path),
            )
        return read_input_bytes(path, max_bytes).decode("latin-1")
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror or exc}", os.fspath(path)) from None


def split_lines(text: str) -> list[str]:
    """Lines with their endings removed from the split but counted: '\\n' (or lone '\\r')."""
    if "\n" not in text and "\r" in text:
        return text.split("\r")
    return text.split("\n")


def check_text(text: str, path: str | os.PathLike[str] | None) -> None:
    """Refuse binary data: a NUL byte is never part of a program."""
    nul = text.find("\x00")
    if nul >= 0:
        line = text.count("\n", 0, nul) + 1
        raise InputError("binary data (NUL byte), not a program", path, line)


def splice(text: str, edits: list[tuple[int, int, str]]) -> bytearray:
    """``text`` as latin-1 bytes with ``text[start:end]`` replaced by each new string
    (non-overlapping edits, any order): the plain form of ``codegen.splice.ByteSplicer``."""
    pieces, last = [], 0
    for start, end, new in sorted(edits):
        pieces += (text[last:start], new)
        last = end
    pieces.append(text[last:])
    return bytearray("".join(pieces).encode("latin-1"))


def distinct_ints(values: np.ndarray) -> list[int]:
    """The distinct values of an array of non-negative ints, ascending: ``np.unique`` without
    its check for masked arrays, whose first call imports ``numpy.ma`` (numpy 2: about 10 ms of
    a rewrite's start-up)."""
    values = np.asarray(values).reshape(-1)
    if not values.size:
        return []
    return np.flatnonzero(np.bincount(values)).tolist()


def row_counts(mask: np.ndarray) -> np.ndarray:
    """The True cells (m,) int of each row of a bool array (m, w): a product with ones, 2-3x
    faster than ``sum(axis=1)`` or ``all(axis=1)`` over rows this short (a few to 64 cells)."""
    return mask.view(np.uint8) @ np.ones(mask.shape[1], np.intp)


def precision(literals, minimum: int = 0) -> int:
    """A file's precision: the most decimals among its X, Y, Z literals (3 when it has none), and
    at least ``minimum``.

    CAM posts drop trailing zeros (``X25.``, ``X24.5``, ``X24.125`` are one precision), so a
    corrected number gets the file's precision, not its own digits; ``minimum`` keeps a coarse
    file (one decimal in inches, integer mm) from rounding the correction away."""
    joined = "\n".join(literals)
    if not joined:
        return max(3, minimum)
    if "e" in joined or "E" in joined:
        found = max(map(decimals_of, joined.split("\n")))
    else:
        found = max(map(len, _FRACTION_RE.findall(joined)), default=0)
    return max(found, minimum)


def number_text(old_text: str, old_value: float, new_value: float, places: int) -> str:
    """The new literal with ``places`` decimals; the old one when the value does not change."""
    new_text = fixed(new_value, places)
    return old_text if float(new_text) == old_value else new_text


def formatted(values: np.ndarray, places: np.ndarray | int) -> list[str | None]:
    """``fixed`` text of each value (N,) with its places (N,) or one count; None where NaN."""
    values = np.asarray(values, dtype=float)
    places = np.broadcast_to(np.asarray(places, dtype=int), values.shape)
    out: list[str | None] = [None] * len(values)
    for p in distinct_ints(places):
        idx = np.flatnonzero(np.isfinite(values) & (places == p))
        for i, text in zip(idx.tolist(), fixed_many(values[idx], p), strict=True):
            out[i] = text
    return out


def comment_block(text: str, lines: list[str], form: str) -> str:
    """The comment ``lines`` (made safe, at most 200 characters each) as ``form`` fills them
    (``"; {}"``), one a line in ``text``'s line ending: a dialect's header block."""
    newline = "\r\n" if "\r\n" in text else "\n"
    return "".join(form.format(comment_text(line, 200)) + newline for line in lines)


def insert_after_lines(text: str, block: str, lead: str) -> str:
    """``text`` with ``block`` inserted after a UTF-8 byte-order mark and the lines that start
    with ``lead`` (KRL ``&``, G-code ``%``); at the end, on a line of its own, when the last of
    them has no line ending."""
    pos = len(UTF8_BOM) if text.startswith(UTF8_BOM) else 0
    while text.startswith(lead, pos):
        nl = text.find("\n", pos)
        if nl < 0:
            return text + ("\r\n" if "\r\n" in text else "\n") + block
        pos = nl + 1
    return text[:pos] + block + text[pos:]


def identifier_problem(name: str, most: int, limit: str) -> str | None:
    """Why ``name`` is not an identifier of at most ``most`` characters (a letter, then letters,
    digits or _), ``limit`` naming the limit ("RAPID allows at most"); None when it is one."""
    if not _IDENTIFIER.fullmatch(name):
        return "must be a letter, then letters, digits or _"
    if len(name) > most:
        return f"has {len(name)} characters, {limit} {most}"
    return None


def stem_name(out: Path, what: str, cell_key: str, problem_of) -> str:
    """The stem of the output file ``out`` as the program's ``what`` name ("module"); InputError
    naming the file when ``problem_of(name)`` says why the controller refuses it, pointing to the
    cell file's ``cell_key`` that names it instead."""
    problem = problem_of(out.stem)
    if problem:
        raise InputError(
            f"the {what} name {out.stem!r} (the file's stem) {problem}: rename the output or set "
            f"{cell_key} in the cell file",
            os.fspath(out),
        )
    return out.stem
