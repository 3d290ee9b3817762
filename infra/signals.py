"""Termination signals (SIGINT, SIGTERM, SIGHUP) turned into an exception while a block runs, so
that ``finally`` clauses clean up and a command ends with one line and exit 128 + the signal."""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Iterator

__all__ = ["TERMINATION_SIGNALS", "Terminated", "signals_raise"]

TERMINATION_SIGNALS = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
)


class Terminated(BaseException):
    """A termination signal (``signum``) arrived while a ``signals_raise`` block ran."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


def _raise(signum: int, frame: object) -> None:
    raise Terminated(signum)


@contextlib.contextmanager
def signals_raise() -> Iterator[None]:
    """The termination signals raise ``Terminated`` in the main thread while the block runs; the
    handlers before are restored after (blocks nest). In another thread the handlers are left
    alone."""
    previous = {}
    try:
        for sig in TERMINATION_SIGNALS:
            previous[sig] = signal.signal(sig, _raise)
    except ValueError:  # not the main thread
        pass
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
