"""Pinned outputs. Text transformations are pinned byte for byte: the SHA-256 of each file a
command wrote. Numerically derived outputs (identified models, programs corrected by them) are
pinned by their structure and their numbers: the file with every number masked must hash the
same, and every number must agree with its pin within ``NUMBER_TOLERANCE``, so that another CPU
or BLAS kernel, which changes the last digits of a least-squares solution, passes while any
change of structure or any real change of a number fails."""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

__all__ = ["NUMBER_TOLERANCE", "digests", "first_difference", "numbers"]

# A number standing on its own (not part of a name such as P12 or a hex digest).
_NUMBER = re.compile(
    rb"(?<![A-Za-z0-9_.])[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?(?![A-Za-z0-9_.])"
)
# A SHA-256 named in a header: it is the digest of another pinned file, whose last digits may
# differ, so the structure check masks it (tests of each header check the digest itself).
_DIGEST = re.compile(rb"(?<![0-9a-f])[0-9a-f]{64}(?![0-9a-f])")
_WHITE_SPACE = re.compile(rb"\s+")

# Two numbers agree when |actual - pinned| <= RELATIVE * |pinned| + ABSOLUTE + one unit in the
# pinned number's last written decimal place (a value on a rounding boundary may print either
# way). Kernels differ by ~1e-12 relative; accugrid's outputs resolve 1e-3 mm: 1e-6 is far
# below anything a user sees and far above rounding noise.
NUMBER_TOLERANCE = {"relative": 1e-6, "absolute": 1e-9}


def _files(folder: Path, names: list[str] | None) -> list[str]:
    if names is None:
        names = [p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()]
    return sorted(names)


def digests(folder: Path, names: list[str] | None = None) -> dict[str, str]:
    """SHA-256 (hex) of ``names`` (paths relative to ``folder``), or of every file under
    ``folder`` when None, keyed by the relative POSIX path, in sorted order."""
    return {
        name: hashlib.sha256((folder / name).read_bytes()).hexdigest()
        for name in _files(folder, names)
    }


def numbers(folder: Path, names: list[str] | None = None) -> dict[str, dict]:
    """Like ``digests``, but each file pinned by ``{"structure": SHA-256 of the file with every
    number replaced by '#', every SHA-256 by '<sha256>' and every run of white space by one
    space (a YAML writer wraps its lines by the numbers' lengths), "numbers": [each number as
    written]}``."""
    pins = {}
    for name in _files(folder, names):
        data = _DIGEST.sub(b"<sha256>", (folder / name).read_bytes())
        written = [m.decode() for m in _NUMBER.findall(data)]
        masked = _WHITE_SPACE.sub(b" ", _NUMBER.sub(b"#", data))
        structure = hashlib.sha256(masked).hexdigest()
        pins[name] = {"structure": structure, "numbers": written}
    return pins


def _unit_in_last_place(written: str) -> float:
    mantissa, _, exponent = written.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 10.0 ** (int(exponent or 0) - decimals)


def _number_difference(actual: dict, pinned: dict) -> str | None:
    """None when the structure is the same and every number agrees within NUMBER_TOLERANCE."""
    if actual["structure"] != pinned["structure"]:
        return "its structure (the text with numbers masked) differs from its pin"
    a, p = actual["numbers"], pinned["numbers"]
    if len(a) != len(p):
        return f"{len(a)} numbers, pinned {len(p)}"
    for index, (x, y) in enumerate(zip(a, p, strict=True)):
        bound = (
            NUMBER_TOLERANCE["relative"] * abs(float(y))
            + NUMBER_TOLERANCE["absolute"]
            + _unit_in_last_place(y)
        )
        if abs(float(x) - float(y)) > bound:
            return f"number {index} is {x}, pinned {y} (tolerance {bound:.3g})"
    return None


def _difference(actual, pinned) -> str | None:
    if isinstance(actual, dict) and isinstance(pinned, dict) and "numbers" in pinned:
        return _number_difference(actual, pinned)
    return None if actual == pinned else f"{actual} (pinned {pinned})"


def first_difference(actual: dict, pinned: dict) -> str | None:
    """None when ``actual`` agrees with ``pinned`` (name -> digest, number pin or other value),
    else a message naming the first name, in ``actual``'s order then ``pinned``'s, whose value
    differs, is missing or is new, and how many differ in all."""
    names = list(actual) + [name for name in pinned if name not in actual]
    problems = {
        name: _difference(actual[name], pinned[name])
        for name in names
        if name in actual and name in pinned
    }
    differing = [n for n in names if n not in actual or n not in pinned or problems[n]]
    if not differing:
        return None
    name = differing[0]
    if name not in pinned:
        what = f"{name} is new (not pinned)"
    elif name not in actual:
        what = f"{name} is pinned but was not written"
    else:
        what = f"{name} differs from its pin: {problems[name]}"
    return f"{what}; {len(differing)} of {len(names)} differ: {', '.join(differing)}"
