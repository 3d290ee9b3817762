"""The array paths of the KRL rewrite against the obvious ones they replace: literals formatted
with array operations against ``fixed`` and ``float``, the byte splice against string slicing,
and the rigid-layout reader against the statement reader on programs in (and near) the controller's
layout (its numbers read by ``infra.decimals``, tested in ``test_decimals.py``)."""

from __future__ import annotations

from unittest import mock

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rewrite_helpers import rewrite_krl

from accugrid.codegen import splice
from accugrid.codegen.bytescan import PAD, text_bytes
from accugrid.codegen.krl import parse
from accugrid.codegen.krl import rewrite as krl_rewrite
from accugrid.codegen.plugin_types import Options
from accugrid.codegen.program_text import splice as splice_text
from accugrid.compensation import GridModel
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import fixed

VALUES = st.one_of(
    st.floats(-1e6, 1e6, allow_nan=False),
    st.integers(-(10**7), 10**7).map(lambda k: k / 2000),  # halfway cases at 3 decimals
    st.integers(-(10**7), 10**7).map(lambda k: k / 20),  # and at 1
    st.sampled_from([0.0, -0.0, -0.0004, -0.0005, 0.0005, 5e-324, -1e-300, 1e15, -3e17]),
)


def _pieces(data: np.ndarray, lengths: np.ndarray) -> list[str]:
    text = bytes(data).decode("ascii")
    ends = np.cumsum(lengths).tolist()
    return [text[a:b] for a, b in zip([0, *ends[:-1]], ends, strict=True)]


@given(st.lists(VALUES, min_size=1, max_size=40), st.integers(0, 9))
def test_literals_are_fixed_and_read_back_as_float_reads_them(values, places):
    data, lengths, written = splice.literals(np.array(values), places)
    texts = [fixed(v, places) for v in values]
    assert _pieces(data, lengths) == texts
    expected = np.array([float(t) for t in texts])
    np.testing.assert_array_equal(written, expected)
    assert (np.signbit(written) == np.signbit(expected)).all()  # "0.000" reads as +0.0


def test_literals_refuse_nan_like_fixed():
    with pytest.raises(ValueError):
        splice.literals(np.array([1.0, np.nan]), 3)


@given(
    st.text(st.sampled_from("ab,;{} \n0123456789."), min_size=0, max_size=80),
    st.lists(st.tuples(st.integers(0, 80), st.integers(0, 4), st.text("xyz-.9", max_size=6))),
    st.booleans(),
)
def test_byte_splicer_is_slicing(text, edits, few_at_a_time):
    cuts, last = [], 0
    for at, size, new in sorted(edits):
        if at >= last and at + size <= len(text):
            cuts.append((at, at + size, new))
            last = at + size + 1 if size == 0 else at + size
    expected = bytes(splice_text(text, list(cuts)))
    starts = np.array([a for a, _, _ in cuts], np.int64)
    ends = np.array([b for _, b, _ in cuts], np.int64)
    new = np.frombuffer("".join(n for _, _, n in cuts).encode(), np.uint8)
    lengths = np.array([len(n) for _, _, n in cuts], np.int64)
    edits = splice._EDITS
    try:
        splice._EDITS = 3 if few_at_a_time else edits
        out, cut = splice.ByteSplicer(text), len(cuts) // 2  # two blocks of edits
        out.add(starts[:cut], ends[:cut], new[: lengths[:cut].sum()], lengths[:cut])
        out.add(starts[cut:], ends[cut:], new[lengths[:cut].sum() :], lengths[cut:])
        got = out.finish()
    finally:
        splice._EDITS = edits
    assert bytes(got) == expected


NUMBER = st.one_of(
    st.floats(-5000, 5000, allow_nan=False).map(lambda v: f"{v:.3f}"),
    st.sampled_from(["0", "-0.0", "1.", ".5", "+2", "1e3", "123456789.5", "1234567890123456"]),
    st.sampled_from(["12345678.12345678", "-.5", "007", "1.2.3", "9e999", "", "-"]),
)
NAME = st.sampled_from(["XP1", "xp2", "P_3", "_a", "A" * 33, "X1Y", "1X", "XP1[2]", "Xé"])
TAIL = st.sampled_from(
    [
        "",
        ",S 'B010',T 'B000010'",
        ",S 'B010',T 'B000010',E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0",
        ",E1 12.5,E2 3",
        ",S 6,T 27  ",
        ",A 5",
        ",X 1",
        ",S 'B01{0'",
        ',S "x"',
        ",S 'Q1'",
        ",E1 foo",
        " ,S 2",
        ",S 2;",
    ]
)


@st.composite
def rigid_lines(draw) -> str:
    """Lines in the controller's layout and small departures from it."""
    lead = draw(st.sampled_from(["", "", " ", "\t", "  "]))
    end = draw(st.sampled_from(["", "", " ", " ; c"]))
    if draw(st.booleans()):
        kind = draw(st.sampled_from(["E6POS", "POS", "FRAME", "E6POS", "AXIS", "e6pos"]))
        body = f"X {draw(NUMBER)},Y {draw(NUMBER)},Z {draw(NUMBER)}"
        if draw(st.booleans()):
            body += f",A {draw(NUMBER)},B {draw(NUMBER)},C {draw(NUMBER)}"
        space = draw(st.sampled_from(["", "", " "]))
        return f"{lead}DECL {kind} {draw(NAME)}={space}{{{body}{draw(TAIL)}}}{end}"
    motion = draw(st.sampled_from(["LIN", "PTP", "SLIN", "SPTP", "LIN", "CIRC", "lin"]))
    clause = draw(st.sampled_from(["", "", " C_DIS", " C_PTP", " C_VEL", " C_ORI", " C_SPL"]))
    return f"{lead}{motion} {draw(NAME)}{clause}{end}"


def _scan(text: str):
    try:
        scan = parse.scan_krl(text, "p.src")
    except InputError as exc:
        return str(exc)
    t, u = scan.table, scan.use_table
    arrays = (t.line, t.column, t.kind, t.agg, t.span, t.places, u.line, u.column)

    def bases(index: np.ndarray) -> list:
        """Each row's base (None: none); ``scan.bases`` is the lookup table the rows index,
        which may hold a base no row uses."""
        return [scan.bases[i] if i >= 0 else None for i in index.tolist()]

    return (
        [a.tolist() for a in arrays],
        np.nan_to_num(t.xyz, nan=1e300).tolist(),
        np.nan_to_num(t.abc, nan=1e300).tolist(),
        np.signbit(t.xyz).tolist(),
        (t.type, t.name, t.reason, t.external, u.motion, u.name, u.text, u.reason),
        (bases(t.base), bases(u.base)),
        (scan.declared, scan.fdats, scan.frame_uses, scan.assigned),
    )


@given(
    st.lists(
        st.one_of(rigid_lines(), st.sampled_from(["DEF p( )", "END", "BAS (#BASE,1)", ""])),
        max_size=25,
    ),
    st.sampled_from(["\n", "\r\n"]),
)
def test_rigid_reader_reads_as_the_statement_reader(lines, ending):
    """The same text read with the rigid lane and with the statement reader alone (the lane
    off)."""
    text = ending.join(lines)
    fast = _scan(text)
    original = parse.text_bytes
    try:
        parse.text_bytes = lambda _: None
        slow = _scan(text)
    finally:
        parse.text_bytes = original
    assert fast == slow


def test_rigid_reader_takes_the_controller_layout():
    """The layout of a controller-written pair is read by the rigid lane."""
    text = (
        "DECL E6POS XP1={X 1.5,Y -2,Z 3.25,A -90.000,B 0.000,C 180.000,S 'B010',T 'B000010',"
        "E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}\r\nLIN XP1 C_DIS\r\n"
    )
    buf = text_bytes(text)
    assert len(buf) == len(text) + PAD
    starts = np.array([0, text.index("LIN")])
    ends = np.array([text.index("\r"), text.rindex("\r")])
    found = parse._rigid_plain(buf, text, starts, ends, 2)
    assert found.plain.tolist() == [True, True]
    assert found.xyz.tolist() == [[1.5, -2.0, 3.25]] and found.abc.tolist() == [[-90, 0, 180]]
    assert found.names == ["XP1"] and found.texts == ["XP1"] and found.places.tolist() == [2]


def _grid_model():
    axes = [np.arange(-600.0, 601.0, 200.0)] * 3
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    return GridModel.from_measurements((pts, pts - 0.001 * pts[:, [1, 2, 0]] - 0.2))


PAIR_MODEL = _grid_model()


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(st.integers(0, 6), st.integers(-700, 700), st.sampled_from(["XP", "xp", "P"])),
        min_size=1,
        max_size=10,
    ),
    st.permutations(range(10)),
    st.booleans(),
)
def test_pair_read_in_order_as_by_name(rows, order, shuffled):
    """A .src whose motions use the .dat's positions in their order, each once (the common
    layout, matched row for row) is rewritten as when every name is looked up (and so are pairs
    out of order, names used twice or missing, lower case)."""
    dat = ["DEFDAT t"]
    for i, (k, v, prefix) in enumerate(rows):
        dat.append(f"DECL E6POS {prefix}{k}={{X {v}.5,Y {i * 10}.25,Z 100.0,A 0.0,B 90.0,C 0.0}}")
    names = [f"{prefix}{k}" for k, _, prefix in rows]
    if shuffled:
        names = [names[j] for j in order if j < len(names)]
    src = ["DEF t( )", "$BASE = BASE_DATA[1]"] + [f"LIN {n}" for n in names] + ["END"]
    texts = {"t.src": "\n".join(src) + "\n", "t.dat": "\n".join(dat + ["ENDDAT"]) + "\n"}
    opts = Options(model=PAIR_MODEL, allow_partial=True)
    fast = rewrite_krl(texts, opts, {1: np.eye(4)})
    init = krl_rewrite._Context.__init__

    def by_name(self, *args):
        init(self, *args)
        if self.aligned is not None:  # every name looked up instead
            self.aligned = None
            names = self.use_names
            self.used_twice = {n for i, n in enumerate(names) if n and self.use_of[n] != i}

    with mock.patch.object(krl_rewrite._Context, "__init__", by_name):
        slow = rewrite_krl(texts, opts, {1: np.eye(4)})
    assert fast.data == slow.data
    assert [repr(r) for r in fast.rows] == [repr(r) for r in slow.rows]
