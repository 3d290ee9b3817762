"""Helpers shared by the benchmark scripts: best-of-N wall time and peak traced memory."""

from __future__ import annotations

import time
import tracemalloc
from collections.abc import Callable


def measure(func: Callable[[], object], repeats: int = 3) -> tuple[float, float]:
    """Best wall time (s) of ``repeats`` calls and peak traced memory (MiB) of one call."""
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - start)
    tracemalloc.start()
    func()
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    return best, peak


def table(rows: list[tuple], header: tuple) -> str:
    """Rows as a fixed-width text table."""
    cells = [tuple(str(c) for c in header)] + [tuple(str(c) for c in row) for row in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)
