"""One BLAS thread for work made of many small matrix operations.

The identification's structure search makes thousands of QR, triangular solves and products of a
few hundred rows by tens of columns. OpenBLAS splits each over its threads; on a machine whose
cores are busy the threads wait for each other far longer than the work takes (10-70 ms for a
1 ms QR on a shared 2-core machine). ``one_blas_thread`` sets the OpenBLAS libraries NumPy and
SciPy ship (their wheels' ``*.libs`` folders) to one thread and restores them after; where no such
library is found (another BLAS) it does nothing.
"""

from __future__ import annotations

import ctypes
import glob
import os
from collections.abc import Iterator
from contextlib import contextmanager
from functools import cache

__all__ = ["one_blas_thread"]

_PREFIXES = ("scipy_openblas", "openblas")
_SUFFIXES = ("64_", "")


@cache
def _controls() -> tuple[tuple[object, object], ...]:
    """(set_num_threads, get_num_threads) of every OpenBLAS library NumPy and SciPy bundle."""
    import numpy
    import scipy

    found = []
    for package in (numpy, scipy):
        folder = os.path.dirname(os.path.dirname(package.__file__))
        name = os.path.basename(os.path.dirname(package.__file__))
        for path in sorted(glob.glob(os.path.join(folder, f"{name}.libs", "*openblas*"))):
            try:
                lib = ctypes.CDLL(path)
            except OSError:
                continue
            for prefix in _PREFIXES:
                for suffix in _SUFFIXES:
                    setter = getattr(lib, f"{prefix}_set_num_threads{suffix}", None)
                    getter = getattr(lib, f"{prefix}_get_num_threads{suffix}", None)
                    if setter is not None and getter is not None:
                        found.append((setter, getter))
                        break
                else:
                    continue
                break
    return tuple(found)


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the body with every bundled OpenBLAS on one thread (restored after)."""
    controls = _controls()
    before = [getter() for _, getter in controls]
    for setter, _ in controls:
        setter(1)
    try:
        yield
    finally:
        for (setter, _), threads in zip(controls, before, strict=True):
            setter(threads)
