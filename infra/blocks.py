"""Work over a large batch in independent blocks, on a few threads.

NumPy releases the GIL inside its array loops, so blocks of a batched computation (e.g. the IK of
16,384 poses) run side by side on the cores this process may use. ``run_blocks`` keeps memory
bounded (no more blocks in flight than threads) and behaves as the serial loop does: every block
before the first failing one runs, and that block's exception is raised in the caller's thread.
Each block must write its own, disjoint part of the output.
"""

from __future__ import annotations

import os
from collections import deque
from collections.abc import Callable, Sequence

__all__ = ["MAX_THREADS", "run_blocks", "threads"]

MAX_THREADS = 4  # beyond a few threads the blocks wait on memory bandwidth, not on cores


def threads() -> int:
    """Threads for block work: the CPUs this process may run on (its affinity mask where the
    platform has one, else the CPU count), 1..``MAX_THREADS``."""
    if hasattr(os, "sched_getaffinity"):
        cpus = len(os.sched_getaffinity(0))
    else:  # pragma: no cover - macOS, Windows
        cpus = os.cpu_count() or 1
    return max(1, min(cpus, MAX_THREADS))


def run_blocks(
    work: Callable[[int], None],
    starts: Sequence[int],
    workers: int | None = None,
    done: Callable[[int], None] | None = None,
) -> None:
    """``work(start)`` for every start, on up to ``workers`` threads (None: ``threads()``), at most
    that many blocks in flight; in order on the caller's thread when one thread or one block.
    The first failing block (in the order of ``starts``) raises its exception here, after every
    earlier block has run. ``done(start)``: called on the caller's thread once the blocks up to
    and including ``start`` have run, in the order of ``starts``."""
    workers = threads() if workers is None else workers
    workers = min(workers, len(starts))
    done = done or (lambda start: None)
    if workers <= 1:
        for start in starts:
            work(start)
            done(start)
        return
    from concurrent.futures import ThreadPoolExecutor  # imports logging: only when threaded

    with ThreadPoolExecutor(workers, thread_name_prefix="accugrid-block") as pool:
        pending: deque = deque()
        try:
            for start in starts:
                if len(pending) == workers:
                    done(_result(pending.popleft()))
                pending.append((start, pool.submit(work, start)))
            while pending:
                done(_result(pending.popleft()))
        finally:
            for _, future in pending:  # after a failure: later blocks not yet started never start
                future.cancel()


def _result(block: tuple) -> int:
    """The start of a (start, future) block once it has run (its exception raised here)."""
    start, future = block
    future.result()
    return start
