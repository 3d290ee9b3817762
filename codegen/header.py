"""The comment header every generated program starts with (DESIGN.md "Output safety").

accugrid version, the SHA-256 of the points, grid and cell files, the grid step and the largest
correction applied. Nothing time- or machine-dependent (no dates, no absolute paths), so the same
inputs give byte-identical programs. Lines are plain text; the templates wrap them as comments
through the ``comment`` filter.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np

from accugrid.codegen import __version__
from accugrid.codegen.textsafe import fixed


def file_sha256(path: str | os.PathLike[str]) -> str:
    """SHA-256 (hex) of a file's bytes."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def header_lines(
    command: str,
    points_path: str | os.PathLike[str],
    points_sha256: str,
    cell_path: str | os.PathLike[str],
    cell_sha256: str,
    grid_path: str | os.PathLike[str] | None,
    grid_sha256: str | None,
    grid_step_mm: np.ndarray | None,
    largest_mm: float,
    largest_hole: str | None,
    holes: int,
) -> list[str]:
    """The header as plain lines (file names only, never directories). ``grid_path`` None means
    the program was made without correction."""
    lines = [
        f"accugrid {__version__} {command}",
        f"points {Path(points_path).name} sha256 {points_sha256}",
        f"cell {Path(cell_path).name} sha256 {cell_sha256}",
    ]
    if grid_path is None:
        lines += ["grid none (--no-correction): positions are not corrected"]
    else:
        step = " x ".join(fixed(s) for s in np.asarray(grid_step_mm, dtype=float))
        lines += [
            f"grid {Path(grid_path).name} sha256 {grid_sha256}",
            f"grid step {step} mm",
        ]
    where = f" at hole {largest_hole}" if largest_hole is not None else ""
    lines += [f"largest correction {fixed(largest_mm)} mm{where}", f"holes {holes}"]
    return lines
