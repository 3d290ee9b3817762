"""The fast paths of the readers and writers against the slow, obvious ones they replace: the
byte-buffer CSV reader against the csv module, the vectorized decimal parser against ``float``,
``fixed_many``'s %-ready values, ``fixed_bytes`` and ``correct``'s byte-built lines against
``fixed``, ``comment_texts`` against ``comment_text``."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from accugrid.app.jobs.correct import DECIMALS, _plain_lines
from accugrid.infra.csvtable import (
    _Cells,
    _parse_csv,
    _parse_simple,
    parse_number,
    parse_table,
)
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import _ready, comment_text, comment_texts, fixed, fixed_bytes

_CELL = st.one_of(
    st.text(st.sampled_from(list("0123456789.+-eE _#abcXYZ\t")), max_size=8),
    st.sampled_from(["nan", "inf", "1_0", "1e999", " 7 ", "-0", ".5", "5."]),
)


def _table_text(header, rows, ending, lead):
    lines = [*lead, ",".join(header), *(",".join(r) for r in rows)]
    return ending.join(lines) + ending


def _same(fast, slow, columns):
    assert fast.header == slow.header and fast.lines == slow.lines and fast.rows == slow.rows
    for name in columns:
        assert fast.text(name) == slow.text(name)
        for allow_empty in (False, True):
            try:
                expected = slow.floats([name], allow_empty)
            except InputError as exc:
                with pytest.raises(InputError) as info:
                    fast.floats([name], allow_empty)
                assert str(info.value) == str(exc)
                continue
            np.testing.assert_array_equal(fast.floats([name], allow_empty), expected)


@given(
    st.integers(1, 4).flatmap(
        lambda width: st.tuples(
            st.just([f"c{i}" for i in range(width)]),
            st.lists(st.lists(_CELL, min_size=width, max_size=width), max_size=6),
        )
    ),
    st.sampled_from(["\n", "\r\n"]),
    st.lists(st.sampled_from(["# note", "", ",", "  "]), max_size=2),
)
def test_the_byte_buffer_reader_reads_what_the_csv_module_reads(table, ending, lead):
    """Any unquoted ASCII table: the same header, lines, cells, numbers and errors, whichever
    reader takes it (the fast one hands odd files to the csv module)."""
    header, rows = table
    text = _table_text(header, rows, ending, lead)
    slow = _parse_csv(text, "t.csv")
    fast = _parse_simple(text, "t.csv")
    if fast is None:  # odd file (blank or comment rows, leading blanks): the csv module's
        fast = parse_table(text, "t.csv")
    _same(fast, slow, header)


@given(
    st.integers(1, 4).flatmap(
        lambda width: st.lists(st.lists(_CELL, min_size=width, max_size=width), min_size=1)
    ),
    st.sampled_from(["\n", "\r\n"]),
    st.data(),
)
def test_row_bytes_are_the_rows_and_the_corrected_lines_follow_them(rows, ending, data):
    """``Table.row_bytes`` holds each row's cells joined by commas; ``correct``'s byte-built
    lines are each row as read, its numbers as ``fixed`` gives them, its flag (any text without
    what csv quotes, UTF-8)."""
    header = [f"c{i}" for i in range(len(rows[0]))]
    table = _parse_simple(_table_text(header, rows, ending, []), "t.csv")
    if table is None or table.row_bytes(0, 0) is None:  # odd or empty: no bytes kept
        return
    lo = data.draw(st.integers(0, len(table) - 1))
    hi = data.draw(st.integers(lo + 1, len(table)))
    texts = [bytes(row).rstrip(b"\0").decode() for row in table.row_bytes(lo, hi)]
    assert texts == [",".join(cells) for cells in table.rows[lo:hi]]
    n = hi - lo
    numbers = np.array(
        data.draw(st.lists(st.lists(_NUMBER, min_size=6, max_size=6), min_size=n, max_size=n))
    )
    flag_text = st.text(st.characters(blacklist_characters=',"\r\n\x00'), max_size=12)
    flags = data.draw(st.lists(st.just("") | flag_text, min_size=n, max_size=n))
    expected = "".join(
        row + "," + ",".join(fixed(v, DECIMALS) for v in values) + "," + flag + "\n"
        for row, values, flag in zip(texts, numbers.tolist(), flags, strict=True)
    )
    assert _plain_lines(table.row_bytes(lo, hi), numbers, flags).decode() == expected


@given(
    st.lists(
        st.tuples(st.sampled_from(["", "-", "+"]), st.integers(0, 10**16), st.integers(0, 17)),
        min_size=1,
        max_size=40,
    )
)
def test_plain_decimals_are_exactly_what_float_reads(numbers):
    cells = []
    for sign, digits, point in numbers:
        text = str(digits)
        point = min(point, len(text))
        cells.append(sign + text[: len(text) - point] + "." + text[len(text) - point :])
    table = parse_table("v\n" + "\n".join(cells) + "\n", "t.csv")
    values = table.floats(["v"])[:, 0]
    expected = [parse_number(c) for c in cells]
    np.testing.assert_array_equal(values, expected)
    assert (np.signbit(values) == np.signbit(expected)).all()  # -0.0 stays -0.0


@given(
    st.lists(st.floats(allow_nan=False, allow_infinity=False, width=64), max_size=30),
    st.integers(0, 6),
)
def test_ready_values_print_what_fixed_prints(values, places):
    ready = _ready(np.array(values), places)
    assert [f"%.{places}f" % v for v in ready.tolist()] == [fixed(v, places) for v in values]


_NUMBER = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False, width=64),
    st.floats(-1e7, 1e7),
    st.integers(-(10**12), 10**12).map(lambda i: (i + 0.5) / 10**4),  # halves at 4 places
    st.integers(-(2**40), 2**40).map(lambda i: i / 2**10),  # exact binary ties
    st.sampled_from([0.0, -0.0, -0.00004, -0.00005, 9.99995, -9.99995, 2.5, 1e15, 5e-324]),
)


@given(st.lists(_NUMBER, min_size=1, max_size=40), st.integers(0, 15))
def test_fixed_bytes_print_what_fixed_prints_and_give_its_value(values, places):
    cells, printed = fixed_bytes(np.array(values), places)
    texts = [fixed(v, places) for v in values]
    assert [bytes(row).lstrip(b"\0").decode() for row in cells] == texts
    assert printed.tolist() == [float(t) for t in texts]


def test_fixed_bytes_refuse_nan():
    with pytest.raises(ValueError, match="non-finite"):
        fixed_bytes(np.array([1.0, np.inf]), 3)


def test_ready_values_keep_the_shape_and_refuse_nan():
    values = np.array([[-0.0004, 1.0], [-0.0, 2.5]])[:, [1, 0]]  # not C-contiguous
    places = 3
    assert [f"%.{places}f" % v for v in _ready(values, places).ravel()] == [
        "1.000",
        "0.000",
        "2.500",
        "0.000",
    ]
    with pytest.raises(ValueError):
        _ready(np.array([1.0, np.nan]), 3)


@given(st.lists(st.text(max_size=80), max_size=20), st.sampled_from(["", "hole "]))
def test_comment_texts_is_comment_text_of_each(texts, prefix):
    assert comment_texts(texts, prefix=prefix) == [comment_text(prefix + t) for t in texts]


@given(
    st.lists(st.text(alphabet="Az09 _.#\n", max_size=70), max_size=20),
    st.sampled_from(["", "hole "]),
    st.sampled_from(["", ";", "é", "\n", " "]),
)
def test_comment_texts_near_the_fast_path_is_comment_text_of_each(texts, prefix, odd):
    """Safe characters and line breaks, and at most one odd character: the bulk check must still
    catch a line break inside a text, a space at either end, an unsafe or a non-ASCII one."""
    texts = texts + [f"X{odd}Y"] if odd else texts
    assert comment_texts(texts, prefix=prefix) == [comment_text(prefix + t) for t in texts]


def test_comment_texts_of_safe_ids_cuts_at_the_limit():
    ids = ["B000001 depth 6.000", "X" * 70]
    assert comment_texts(ids) == [ids[0], "X" * 60]


@given(st.binary(min_size=1, max_size=40).filter(lambda b: b"\0" not in b), st.data())
def test_cut_cells_are_the_byte_slices_nul_padded(data, draw):
    """``_Cells.cut`` (a word at a time, the cells at the buffer's end byte by byte): each cell
    is ``data[start:end]``, NUL-padded to one width for all, from buffers shorter than a word
    to cells that end at the buffer's last byte."""
    cells = _Cells(data, 1)
    spans = draw.draw(
        st.lists(
            st.integers(0, len(data)).flatmap(
                lambda s: st.tuples(st.just(s), st.integers(s, len(data)))
            ),
            min_size=1,
            max_size=10,
        )
    )
    start = np.array([s for s, _ in spans], np.int32)
    end = np.array([e for _, e in spans], np.int32)
    cut = cells.cut(start, end)
    assert cut.dtype.itemsize >= max(e - s for s, e in spans)
    raw = cut.view(np.uint8).reshape(len(spans), -1)
    for row, (s, e) in zip(raw.tolist(), spans, strict=True):
        assert bytes(row) == data[s:e] + b"\0" * (len(row) - (e - s))
