"""The comment header every output starts with (docs/guarantees.md): programs (``krl``, ``gcode``,
``rewrite``, ``plan``) and the corrected-points CSV (``correct``).

In this order: the accugrid version and command; each input file's name and SHA-256; the grid's
name, SHA-256 and step; command-specific details; the largest correction applied; for the
corrections (programs, rewrites, the corrected CSV) the largest 95 % bound of a corrected position's
error (``compensation.budget``); a closing count. Nothing time- or machine-dependent (no dates, no
absolute paths), so the same inputs give byte-identical outputs. Lines are plain text; the templates
wrap them as comments through the ``comment`` filter, ``csv_comment`` for CSV files."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from accugrid.codegen import __version__
from accugrid.infra.textsafe import comment_text, fixed

__all__ = ["csv_comment", "grid_lines", "header_lines", "input_line"]


def input_line(role: str, path: str | os.PathLike[str], sha256: str) -> str:
    """``ROLE NAME sha256 HEX``: the file's name only, never its directory."""
    return f"{role} {Path(path).name} sha256 {sha256}"


def grid_lines(name: str, sha256: str | None, step_mm: np.ndarray) -> list[str]:
    """The grid's name and SHA-256, and its step (3,) mm."""
    step = " x ".join(fixed(s) for s in np.asarray(step_mm, dtype=float))
    return [f"grid {name} sha256 {sha256}", f"grid step {step} mm"]


def header_lines(
    command: str,
    inputs: Sequence[str] = (),
    details: Sequence[str] = (),
    largest_mm: float = 0.0,
    where: str = "",
    closing: Sequence[str] = (),
    u95_mm: np.ndarray | None = None,
) -> list[str]:
    """The header as plain lines: version and command, ``inputs`` (``input_line`` and
    ``grid_lines``), ``details``, the largest correction (mm, ``where`` appended), with
    ``u95_mm`` (N,) mm the positions' 95 % bounds (NaN: none) the largest of them (one line
    whatever they hold, so a header's length is known before the correction), ``closing``."""
    bound = []
    if u95_mm is not None:
        u95 = np.asarray(u95_mm, dtype=float)
        known = u95[np.isfinite(u95)]
        bound.append(
            f"largest u95 {fixed(float(known.max()))} mm over {known.size} positions: the 95 "
            "percent bound of the error"
            if known.size
            else "largest u95 unknown: no corrected position with an error budget"
        )
    return [
        f"accugrid {__version__} {command}",
        *inputs,
        *details,
        f"largest correction {fixed(largest_mm)} mm{where}",
        *bound,
        *closing,
    ]


def csv_comment(lines: Sequence[str]) -> str:
    """The header as CSV comment lines (``# ...``), sanitized, each ending in a newline."""
    return "".join(f"# {comment_text(line, limit=400)}\n" for line in lines)
