"""The number pins of tests/pins.py: a change of structure or of any number beyond the stated
tolerance fails; the last digits another BLAS kernel changes, a rounding flip in the last written
place and a YAML line wrapped elsewhere pass."""

from __future__ import annotations

import pytest
from pins import first_difference, numbers

PINNED = "tool: {x: 0.0015642867566478293, z: 250.0450988033121}\nX 1200.125 id P12 k40\n"


def _pin(folder, text: str) -> dict:
    folder.mkdir(exist_ok=True)
    (folder / "f.yaml").write_text(text)
    return numbers(folder)


@pytest.mark.parametrize(
    "text",
    [
        PINNED.replace("0.0015642867566478293", "0.0015642867197487337"),  # BLAS kernel
        PINNED.replace("250.0450988033121", "250.04509880323553"),
        PINNED.replace("1200.125", "1200.126"),  # a value on a rounding boundary
        PINNED.replace(", z: ", ",\n  z: "),  # wrapped elsewhere
    ],
)
def test_what_another_cpu_changes_passes(tmp_path, text):
    assert first_difference(_pin(tmp_path / "a", text), _pin(tmp_path / "b", PINNED)) is None


@pytest.mark.parametrize(
    ("text", "why"),
    [
        (PINNED.replace("250.0450988033121", "250.046"), "number 1 is 250.046"),
        (PINNED.replace("1200.125", "1200.128"), "number 2 is 1200.128"),
        (PINNED.replace("k40", "k41"), "structure"),
        (PINNED.replace("P12", "P13"), "structure"),
        (PINNED.replace("z: ", "y: "), "structure"),
        (PINNED + "1\n", "structure"),
    ],
)
def test_a_real_change_fails_naming_it(tmp_path, text, why):
    problem = first_difference(_pin(tmp_path / "a", text), _pin(tmp_path / "b", PINNED))
    assert problem is not None and why in problem
