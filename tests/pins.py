"""Outputs pinned byte for byte: SHA-256 digests of the files a command wrote, compared with
digests recorded earlier, naming the first file that differs."""

from __future__ import annotations

import hashlib
from pathlib import Path

__all__ = ["digests", "first_difference"]


def digests(folder: Path, names: list[str] | None = None) -> dict[str, str]:
    """SHA-256 (hex) of ``names`` (paths relative to ``folder``), or of every file under
    ``folder`` when None, keyed by the relative POSIX path, in sorted order."""
    if names is None:
        names = [p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()]
    return {
        name: hashlib.sha256((folder / name).read_bytes()).hexdigest() for name in sorted(names)
    }


def first_difference(actual: dict, pinned: dict) -> str | None:
    """None when ``actual`` equals ``pinned`` (name -> digest or other value), else a message
    naming the first name, in ``actual``'s order then ``pinned``'s, whose value differs, is
    missing or is new, and how many differ in all."""
    names = list(actual) + [name for name in pinned if name not in actual]
    differing = [name for name in names if actual.get(name) != pinned.get(name)]
    if not differing:
        return None
    name = differing[0]
    if name not in pinned:
        what = f"{name} is new (not pinned): {actual[name]}"
    elif name not in actual:
        what = f"{name} is pinned but was not written"
    else:
        what = f"{name} differs from its pin: {actual[name]} (pinned {pinned[name]})"
    return f"{what}; {len(differing)} of {len(names)} differ: {', '.join(differing)}"
