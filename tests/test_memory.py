"""``infra.memory``: after ``map_large_buffers`` an array freed in the middle of the heap gives
its memory back to the system, where glibc's own threshold (raised by an earlier large array
freed) keeps it in the process. Each case runs in a fresh interpreter (the setting is for the
whole process)."""

import ctypes
import subprocess
import sys

import pytest

from accugrid.infra.memory import LARGE

CASE = """
import sys
import numpy as np
from accugrid.infra.memory import map_large_buffers

def resident():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096

if sys.argv[1] == "mapped":
    assert map_large_buffers()
first = np.ones(2 << 20)  # 16 MiB, mapped: freed, it raises glibc's threshold to its size
del first
middle = np.ones(int(sys.argv[2]) // 8)  # below 16 MiB: from the heap unless mapped
after = np.ones(200_000)  # 1.6 MiB above it on the heap: no trim from the top frees it
before = resident()
del middle
print(before - resident())
"""


def _freed(mode: str, size: int) -> int:
    done = subprocess.run(
        [sys.executable, "-c", CASE, mode, str(size)], capture_output=True, text=True, check=True
    )
    return int(done.stdout)


def _glibc() -> bool:
    try:
        ctypes.CDLL(None).gnu_get_libc_version  # noqa: B018
    except (OSError, AttributeError):
        return False
    return sys.platform.startswith("linux")


@pytest.mark.skipif(not _glibc(), reason="glibc's malloc and /proc only")
def test_a_large_array_freed_in_the_heap_goes_back_to_the_system():
    size = 2 * LARGE  # 8 MiB
    assert _freed("mapped", size) >= size * 0.9
    assert _freed("default", size) < size * 0.1  # the hole stays without it


@pytest.mark.skipif(not _glibc(), reason="glibc's malloc and /proc only")
def test_arrays_below_the_threshold_stay_on_the_heap():
    assert _freed("mapped", LARGE // 2) < LARGE // 2 * 0.1  # their pages are reused, not faulted
