"""The bulk decimal reader (infra.decimals) against Python's own ``float`` on the literal."""

from __future__ import annotations

import re

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from accugrid.infra.decimals import _BLOCK, read_decimals

PLAIN = re.compile(r"[+-]?(\d{0,8})(?:\.(\d{0,7}))?")

digits = st.text("0123456789", max_size=10)
decimal_literals = st.builds(
    lambda sign, whole, point, part: sign + whole + point + part,
    st.sampled_from(["", "-", "+"]),
    digits,
    st.sampled_from(["", "."]),
    digits,
)
any_literals = decimal_literals | st.text("0123456789.+-e E,x", max_size=12)


def read(literals: list[str], separator: str = ",") -> tuple:
    """Each literal's reading, the literals joined by ``separator`` in one buffer."""
    text = separator.join(literals).encode("ascii")
    lengths = np.array([len(s) for s in literals], np.int64)
    start = np.cumsum(np.concatenate([[0], lengths[:-1] + len(separator)]))
    return read_decimals(np.frombuffer(text, np.uint8), start, start + lengths)


def is_plain(literal: str) -> bool:
    match = PLAIN.fullmatch(literal)
    return bool(match) and len(match[1] + (match[2] or "")) >= 1


@given(st.lists(any_literals, min_size=1, max_size=30))
def test_plain_literals_read_as_float_reads_them_and_others_are_refused(literals):
    values, decimals, plain = read(literals)
    for literal, value, places, ok in zip(literals, values, decimals, plain, strict=True):
        assert ok == is_plain(literal), literal
        if ok:
            expected = float(literal)
            assert value == expected and np.signbit(value) == np.signbit(expected), literal
            assert places == len(literal.partition(".")[2]), literal


@given(st.floats(-1e7, 1e7, allow_nan=False), st.integers(0, 7))
def test_formatted_floats_read_back_exactly(value, places):
    literal = f"{value:.{places}f}"
    values, decimals, plain = read([literal, literal], separator="\n")
    assert plain.all() and (values == float(literal)).all() and (decimals == places).all()


def test_a_buffer_shorter_than_a_word_and_literals_at_its_start():
    values, _, plain = read(["7"])
    assert plain.tolist() == [True] and values.tolist() == [7.0]
    values, _, plain = read(["-0", "1.5", ""])
    assert plain.tolist() == [True, True, False]
    assert values[0] == 0 and np.signbit(values[0]) and values[1] == 1.5


@settings(max_examples=3)
@given(st.integers(0, 2**32 - 1), st.integers(-2, 2))
def test_literals_in_more_than_one_block(seed, extra):
    rng = np.random.default_rng(seed)
    n = 2 * _BLOCK + extra
    places = rng.integers(0, 8, n)
    numbers = rng.uniform(-1.0, 1.0, n) * 10.0 ** rng.integers(-3, 8, n)
    literals = [f"{v:.{p}f}" for v, p in zip(numbers.tolist(), places.tolist(), strict=True)]
    literals[rng.integers(0, n)] = "1e5"  # not plain, somewhere
    values, decimals, plain = read(literals)
    assert plain.tolist() == [is_plain(s) for s in literals]
    assert values[plain].tolist() == [float(s) for s in literals if is_plain(s)]
    assert decimals[plain].tolist() == [len(s.partition(".")[2]) for s in literals if is_plain(s)]
