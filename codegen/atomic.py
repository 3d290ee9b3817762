"""Writing outputs safely: all files of a job appear together or not at all.

Each file is written to a temporary file in its target folder and renamed over the target only
after every file of the job has been written. An existing output is refused without ``force``;
an input file is never a target.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path

from accugrid.kinematics.errors import InputError


def check_targets(
    targets: Iterable[str | os.PathLike[str]],
    inputs: Iterable[str | os.PathLike[str]] = (),
    force: bool = False,
) -> None:
    """Refuse before any work is done: a target that is an input, or exists without ``force``."""
    input_paths = [Path(p).resolve() for p in inputs if p is not None]
    for target in targets:
        path = Path(target)
        resolved = path.resolve()
        if resolved in input_paths or any(_same_file(path, p) for p in input_paths):
            raise InputError("refusing to overwrite an input file", os.fspath(target))
        if path.exists() and not force:
            raise InputError("output exists (use --force to overwrite)", os.fspath(target))
        if path.is_dir():
            raise InputError("output is a directory", os.fspath(target))


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def write_files(
    contents: Mapping[str | os.PathLike[str], bytes | str],
    inputs: Iterable[str | os.PathLike[str]] = (),
    force: bool = False,
) -> list[Path]:
    """Write every file of a job atomically; text is encoded as UTF-8 with newlines untouched.

    Returns the written paths. On any failure the targets are left as they were.
    """
    check_targets(contents, inputs, force)
    temps: list[tuple[str, Path]] = []
    try:
        for target, data in contents.items():
            path = Path(target)
            path.parent.mkdir(parents=True, exist_ok=True)
            payload = data.encode("utf-8") if isinstance(data, str) else data
            fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
            temps.append((tmp, path))
            with os.fdopen(fd, "wb") as handle:
                handle.write(payload)
                handle.flush()
                os.fsync(handle.fileno())
        for tmp, path in temps:
            os.replace(tmp, path)
    finally:
        for tmp, _ in temps:
            if os.path.exists(tmp):
                os.unlink(tmp)
    return [Path(t) for t in contents]
