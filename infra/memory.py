"""Large buffers mapped from the system and handed back to it when freed (glibc's malloc).

glibc serves a request of at least its mmap threshold with a mapping of its own, unmapped when
freed; smaller ones come from the heap, whose free space between blocks in use stays in the
process. It raises the threshold to the size of each mapped block freed (up to 32 MiB), so once a
job has freed a large array, its later arrays of up to 32 MiB (a column of a million positions)
come from the heap, and the holes they leave count in the process's memory until it ends: about
100 MiB of a million-position rewrite's peak. ``map_large_buffers`` fixes the threshold, which
also stops that adjustment; where the C library has no ``mallopt`` it does nothing.
"""

from __future__ import annotations

__all__ = ["LARGE", "map_large_buffers"]

LARGE = 4 << 20  # bytes: buffers from this size on are mapped (arrays of a block of positions
# stay on the heap, where reusing them needs no fresh pages)
_M_MMAP_THRESHOLD = -3  # mallopt's parameter number (malloc.h)


def map_large_buffers(threshold: int = LARGE) -> bool:
    """Have the C library map every buffer of ``threshold`` bytes or more and unmap it when it
    is freed, from now on for the whole process; whether it could (glibc: yes)."""
    import ctypes  # numpy has loaded it already

    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):  # no mallopt in this C library
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    return mallopt(_M_MMAP_THRESHOLD, threshold) == 1
