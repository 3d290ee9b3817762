"""``textsafe.fixed_bytes`` (the numpy-built texts of ``fixed``) against ``fixed`` itself: the
texts, their values, the cell width, ties, negative zero, values too long for its integers, the
blocks it works in, NaN and infinity."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from accugrid.infra.textsafe import _CHUNK, fixed, fixed_bytes

_NUMBER = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False, width=64),
    st.floats(-1e4, 1e4),
    st.floats(-1e-3, 1e-3),  # -0.000 and friends
    st.integers(-(10**17), 10**17).map(lambda i: i / 10.0 ** (i % 17)),  # every length
    st.integers(-(2**31), 2**31).map(float),  # around the int32 digits
    st.sampled_from([0.0, -0.0, 0.5, -0.5, 9.5, 99.5, 999.5, 9999.5, 1e15, -1e16, 2.0**50]),
)


def _check(values: list[float], places: int) -> None:
    """The cells and values of ``fixed_bytes`` are those of ``fixed``, row by row, and the width
    is 1 + the digits of the largest whole part + the point and decimals (a text too long for
    the integer digits: the longest text)."""
    cells, printed = fixed_bytes(np.array(values, dtype=float), places)
    texts = [fixed(v, places) for v in values]
    assert cells.dtype == np.uint8 and cells.flags.c_contiguous
    assert cells.shape[0] == printed.shape[0] == len(values)
    rows = [bytes(row) for row in cells]
    assert [row.lstrip(b"\0").decode() for row in rows] == texts
    assert all(b"\0" not in row.lstrip(b"\0") for row in rows)  # NUL only on the left
    assert printed.tolist() == [float(t) for t in texts]
    assert not np.signbit(printed[printed == 0]).any()  # "0.000" reads as 0.0, not -0.0
    short = places <= 15 and all(abs(v) * 10.0**places < 2.0**50 for v in values)
    if short:
        wholes = max((len(t.lstrip("-").split(".")[0]) for t in texts), default=1)
        assert cells.shape[1] == 1 + wholes + (1 + places if places else 0)
    else:
        assert cells.shape[1] == max(map(len, texts))


@given(st.lists(_NUMBER, min_size=1, max_size=60), st.integers(0, 15))
def test_fixed_bytes_rows_are_the_texts_of_fixed(values, places):
    _check(values, places)


@given(st.lists(st.integers(-(10**9), 10**9), min_size=1, max_size=60), st.integers(0, 8))
def test_exact_ties_round_half_to_even(odd, places):
    # (2j + 1) / 2**(places + 1) times 10**places is (2j + 1) 5**places / 2: an exact half
    values = [(2 * j + 1) / 2.0 ** (places + 1) for j in odd]
    _check(values, places)


@given(st.lists(st.floats(-1.0, 0.0), min_size=1, max_size=30), st.integers(0, 6))
def test_small_negatives_print_without_sign_when_zero(fractions, places):
    values = [f * 0.5 * 10.0**-places for f in fractions] + [-0.0]
    cells, printed = fixed_bytes(np.array(values), places)
    zero = fixed(0.0, places)
    texts = [bytes(row).lstrip(b"\0").decode() for row in cells]
    assert texts == [fixed(v, places) for v in values]
    assert texts[-1] == zero and printed[-1] == 0.0 and not np.signbit(printed[-1])


@settings(max_examples=6)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(-3, 3),
    st.integers(2, 3),
    st.sampled_from([0, 1, 3, 4]),
    st.integers(-4, 7),
)
def test_blocks_of_rows_join_up(seed, extra, blocks, places, exponent):
    # more values than one block: each row's leftmost group starts over the row before it,
    # across the edges of the blocks too
    rng = np.random.default_rng(seed)
    n = blocks * _CHUNK + extra
    values = rng.uniform(-1.0, 1.0, n) * 10.0 ** rng.integers(
        exponent - 6, exponent, n, endpoint=True
    )
    values[rng.integers(0, n, 50)] = 10.0**exponent - 0.5 * 10.0**-places  # the widest
    _check(values.tolist(), places)


@pytest.mark.parametrize("places", [0, 3, 16])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("where", [0, 5, _CHUNK + 1])
def test_fixed_bytes_refuse_nan_and_infinity_anywhere(places, bad, where):
    values = np.linspace(-100.0, 100.0, _CHUNK + 2)
    values[where] = bad
    with pytest.raises(ValueError, match="non-finite"):
        fixed_bytes(values, places)


def test_fixed_bytes_of_nothing_and_of_any_shape():
    cells, printed = fixed_bytes(np.zeros(0), 3)
    assert cells.shape == (0, 6) and printed.shape == (0,)
    values = np.array([[1.25, -3.5], [1e6, -0.0]])[:, ::-1]  # 2-D, not C-contiguous
    cells, printed = fixed_bytes(values, 1)
    assert [bytes(r).lstrip(b"\0") for r in cells] == [b"-3.5", b"1.2", b"0.0", b"1000000.0"]
    assert printed.tolist() == [-3.5, 1.2, 0.0, 1e6]
