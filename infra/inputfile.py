"""The one guarded way to read a user's input file (CSV, YAML, programs).

- Type before open: only a regular file is read (a FIFO would block, ``/dev/zero`` never ends); a
  symlink is followed and judged by what it points to.
- Size limit: a file over ``limit`` bytes is refused before it is read.
- Text: UTF-8 with an optional BOM; a bad byte is located by line and column. CR, LF and CRLF
  line ends are all left to the format readers (the CSV and YAML readers accept each).
- Every file read here while ``track_inputs()`` is active is remembered (device and inode), so the
  output writer (``infra.atomic``) can refuse to replace any of them.
"""

from __future__ import annotations

import contextlib
import os
import stat
from collections.abc import Iterator
from pathlib import Path

from accugrid.infra.errors import InputError

__all__ = [
    "MAX_INPUT_BYTES",
    "MAX_CONFIG_BYTES",
    "read_input_bytes",
    "read_input_text",
    "file_identities",
    "note_input",
    "track_inputs",
    "tracked_inputs",
]

MAX_INPUT_BYTES = 256 * 2**20
"""Largest CSV read (256 MiB holds about three million holes; programs have --max-mb)."""
MAX_CONFIG_BYTES = 4 * 2**20
"""Largest YAML configuration read (a cell or robot file is a few KiB)."""
MAX_FOLDER_FILES = 10_000
"""Files of an input folder (templates) taken as inputs."""

_KINDS = {
    stat.S_IFIFO: "a FIFO",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFSOCK: "a socket",
    stat.S_IFDIR: "a folder",
}
_tracking: list[set[tuple[int, int]]] = []


def _kind(mode: int) -> str:
    return _KINDS.get(stat.S_IFMT(mode), "not a regular file")


def read_input_bytes(path: str | os.PathLike[str], limit: int = MAX_INPUT_BYTES) -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes; InputError naming ``path`` else.

    The type is checked before opening (never blocks on a FIFO) and again on the open file.
    """
    where = os.fspath(path)
    try:
        before = os.stat(where)
        if not stat.S_ISREG(before.st_mode):
            raise InputError(f"not a regular file ({_kind(before.st_mode)})", where)
        if before.st_size > limit:
            raise InputError(
                f"file is {before.st_size / 2**20:.1f} MiB, over the limit of "
                f"{limit / 2**20:.1f} MiB",
                where,
            )
        fd = os.open(where, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        with os.fdopen(fd, "rb") as handle:
            now = os.fstat(handle.fileno())
            if not stat.S_ISREG(now.st_mode):
                raise InputError(f"not a regular file ({_kind(now.st_mode)})", where)
            # its size (+1 to see growth), not the limit: a buffer is allocated for the count
            data = handle.read(min(limit, now.st_size) + 1)
            while len(data) <= limit and (more := handle.read(min(limit + 1 - len(data), 2**20))):
                data += more  # the file grew since fstat
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror or exc}", where) from None
    if len(data) > limit:
        raise InputError(f"file is over the limit of {limit / 2**20:.1f} MiB", where)
    note_input(now)
    return data


def read_input_text(
    path: str | os.PathLike[str], limit: int = MAX_INPUT_BYTES
) -> tuple[bytes, str]:
    """A file's bytes (for hashing) and its UTF-8 text without a BOM; InputError located at the
    first byte that is not UTF-8 (line and column counted in bytes of that line, 1-based)."""
    raw = read_input_bytes(path, limit)
    try:
        return raw, raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        start = exc.start + (3 if raw.startswith(b"\xef\xbb\xbf") else 0)
        head = raw[:start].replace(b"\r\n", b"\n").replace(b"\r", b"\n")
        line = head.count(b"\n") + 1
        column = len(head) - (head.rfind(b"\n") + 1) + 1
        raise InputError("not UTF-8 text", os.fspath(path), line, column) from None


def file_identities(path: str | os.PathLike[str]) -> set[tuple[int, int]]:
    """(device, inode) of a file, or of a folder and every file in it (at most
    ``MAX_FOLDER_FILES``); empty when the path does not exist."""
    try:
        st = os.stat(path)
    except OSError:
        return set()
    found = {(st.st_dev, st.st_ino)}
    if stat.S_ISDIR(st.st_mode):
        for count, item in enumerate(Path(path).rglob("*")):
            if count >= MAX_FOLDER_FILES:
                break
            with contextlib.suppress(OSError):
                sub = item.stat()
                found.add((sub.st_dev, sub.st_ino))
    return found


def note_input(item: os.stat_result | str | os.PathLike[str]) -> None:
    """Record an input of the running command (if one is tracking): a stat result, or a path
    (a folder: every file in it) read by other means (Jinja templates, a URDF)."""
    if not _tracking:
        return
    if isinstance(item, os.stat_result):
        _tracking[-1].add((item.st_dev, item.st_ino))
    else:
        _tracking[-1].update(file_identities(item))


@contextlib.contextmanager
def track_inputs() -> Iterator[set[tuple[int, int]]]:
    """While active, every file read by ``read_input_bytes`` is recorded as an input."""
    _tracking.append(set())
    try:
        yield _tracking[-1]
    finally:
        _tracking.pop()


def tracked_inputs() -> frozenset[tuple[int, int]]:
    """(device, inode) of every input read under the innermost ``track_inputs``."""
    return frozenset(_tracking[-1]) if _tracking else frozenset()
