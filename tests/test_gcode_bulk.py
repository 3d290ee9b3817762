"""The G-code reader's and rewriter's bulk paths agree with the line-by-line ones.

Reader: ``gcode_moves`` reads a text with ``\\n`` endings by the whole-text scanner (runs of plain
lines in bulk, every other line by the line reader, ``_Reader.line``); reading every line with
``_Reader.line`` must give the same moves, column by column, and each shape of line, read once,
must give every line of that shape its ``_ROW_RE`` head and number offsets. Rewriter:
``_bulk_block`` (a block of absolute moves in bulk) must make the edits and leave the walk's
state as ``_walk_block``, the move-by-move walk, does, and the whole walk (stretches of absolute
moves in bulk between the others) must write what walking every move writes. Numbers:
``literal_values`` reads every literal as ``float`` does, with its decimals, and the file's
precision the readers keep is ``precision`` of the literals.
"""

from __future__ import annotations

from types import SimpleNamespace
from unittest import mock

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from accugrid.codegen.gcode import parse, rewrite
from accugrid.codegen.gcode.numbers import literal_values
from accugrid.codegen.gcode.parse import gcode_moves
from accugrid.codegen.gcode.rewrite import _bulk_block, _Commanded, _file_precision, _walk_block
from accugrid.codegen.plugin_types import CORRECTED, Rows
from accugrid.codegen.program_text import decimals_of, precision, split_lines
from accugrid.infra.errors import InputError

NUMBER = st.one_of(
    st.floats(-900, 900, allow_nan=False).map(lambda v: f"{v:.3f}"),
    st.sampled_from(["0", "-0.0", "1.", ".5", "+2", "12", "007", "9" * 400]),
)
CODES = st.sampled_from(
    ["", "G0 ", "G1 ", "G00 ", "G01 ", "G99 G81 ", "G98 G83 ", "G73 ", "G98 ", "G99 ", "G82 "]
)
MODAL = st.sampled_from(
    [
        "G90",
        "G91",
        "G20",
        "G21",
        "G80",
        "G18",
        "G17",
        "G55",
        "G54",
        "G2 X1 Y2 I3 J4",
        "G3 X1 Y2 I3 J4",
        "G28",
        "G92 X0",
        "G92.1",
        "G38.2 Z-5",
        "M6 T2",
        "#1 = 5",
        "G1 X#1 Y2 Z3",
        "(comment)",
        "",
        "  ",
        "%",
        "G53 Z0",
        "G0 Z500",
        "X5 Y6",
        "A30 X1 Y2 Z3",
        "G41 D1",
        "G40",
        "O100 sub",
        "/G1 X1 Y2 Z3",
        "G1 X1 Y2 Z3 (a(b)",
    ]
)


@st.composite
def plain_lines(draw) -> str:
    """A line the whole-text scanner takes (or nearly: odd spacing sends it to the line reader)."""
    n = draw(st.sampled_from(["", "N10 ", "N7  "]))
    x, y, z = draw(NUMBER), draw(NUMBER), draw(NUMBER)
    gap = draw(st.sampled_from([" ", " ", " ", "  ", "\t"]))
    r = draw(st.sampled_from(["", "", f" R{draw(NUMBER)}", "  R1"]))
    tail = draw(st.sampled_from(["", " F300", " (move 1)", " F3000 (m)", "\t", " ;x", "\r"]))
    lead = draw(st.sampled_from(["", "", " "]))
    return f"{lead}{n}{draw(CODES)}X{x}{gap}Y{y} Z{z}{r}{tail}"


@st.composite
def partial_lines(draw) -> str:
    """A plain line that writes one or two of X, Y, Z (or a near miss)."""
    words = [f"{k}{draw(NUMBER)}" for k in "XYZ" if draw(st.booleans())]
    if draw(st.booleans()):
        words.append(f"R{draw(NUMBER)}")
    gap = draw(st.sampled_from([" ", " ", " ", "  ", ""]))
    tail = draw(st.sampled_from(["", " F300", " (move X1 Y2)", " (R)", "\r", " ;X1"]))
    return f"{draw(st.sampled_from(['', 'N5 ']))}{draw(CODES)}{gap.join(words)}{tail}"


PROGRAMS = st.lists(
    st.one_of(plain_lines(), plain_lines(), partial_lines(), partial_lines(), MODAL), max_size=60
)
COLUMNS = (
    "line column start target end scale r_mm incremental is_cycle setters word_start word_end "
    "word_value rotary_index resets g99"
).split()


def _read(text: str, bulk: bool):
    try:
        if bulk:
            return gcode_moves(text, "p.ngc")
        reader, offset = parse._Reader("p.ngc", text), 0
        reader.moves = parse.GcodeMoves("p.ngc", text, 1)  # its arrays grown as rows come
        for lineno, raw in enumerate(split_lines(text), start=1):
            reader.line(raw, lineno, offset)
            offset += len(raw) + 1
        return reader.moves.finish()
    except InputError as exc:
        return str(exc)


@settings(max_examples=300, deadline=None)
@given(
    lines=PROGRAMS,
    chunk=st.sampled_from([1, 40, 1 << 18]),
    final=st.booleans(),
    bom=st.sampled_from(["", "", "\xef\xbb\xbf"]),
)
def test_bulk_reader_reads_as_the_line_reader(lines, chunk, final, bom):
    """The same moves (or the same error) by the whole-text scanner, in chunks of any size, and
    line by line."""
    text = bom + "\n".join(lines) + ("\n" if final else "")
    with mock.patch.object(parse, "_CHUNK", chunk):
        bulk = _read(text, True)
    one_by_one = _read(text, False)
    if isinstance(bulk, str) or isinstance(one_by_one, str):
        assert bulk == one_by_one
        return
    assert len(bulk) == len(one_by_one)
    for name in COLUMNS:
        a, b = getattr(bulk, name), getattr(one_by_one, name)
        assert np.array_equal(a, b, equal_nan=True), name
    assert bulk.motion == one_by_one.motion
    assert bulk.reason == one_by_one.reason
    assert bulk.retract == one_by_one.retract
    assert bulk.rotaries == one_by_one.rotaries


def test_bulk_reader_takes_plain_runs():
    """A program of plain lines is read in bulk: the line reader is not called for them."""
    text = "G21 G90\nG99 G81 X1 Y2 Z-3 R2 F300\nX4 Y5\nG1 X4 Y5 Z6 (m)\nN3 X7 Y8 Z9\nG0 Z50\n"
    with mock.patch.object(parse._Reader, "line", autospec=True, wraps=parse._Reader.line) as line:
        moves = gcode_moves(text)
    assert [c.args[2] for c in line.call_args_list] == [1, 7]  # "G21 G90" and the empty last
    assert moves.motion == ["G81", "G81", "G1", "G1", "G0"]
    assert moves.target.tolist() == [[1, 2, -3], [4, 5, -3], [4, 5, 6], [7, 8, 9], [7, 8, 50]]
    assert moves.end.tolist() == [[1, 2, 2], [4, 5, 2], [4, 5, 6], [7, 8, 9], [7, 8, 50]]
    assert moves.setters.tolist() == [[-1, -1, -1], [0, 0, 0], [1, 1, 1], [2, 2, 2], [3, 3, 3]]
    assert moves.word_start[4].tolist() == [-1, -1, text.index("Z50") + 1, -1]


PARTIAL = st.one_of(
    st.tuples(
        st.sampled_from(["", "G0 ", "G1 ", "G81 ", "G98 G82 ", "G99 ", "G80 "]), NUMBER, NUMBER
    ).map(lambda t: f"{t[0]}X{t[1]} Y{t[2]}"),
    NUMBER.map(lambda z: f"G0 Z{z}"),
    NUMBER.map(lambda z: f"Z{z} R{z}"),
    st.tuples(NUMBER, NUMBER).map(lambda t: f"Y{t[0]} X{t[1]} Z-1 R2"),
    st.sampled_from(["G17", "G18", "G98", "G99", "G2 X1 Y2 I3 J4", "A30 X1", "G55 X1 Y2 Z3"]),
)


@st.composite
def cases(draw):
    """An absolute program (plain lines and lines that write some axes, cycles with and without
    R, G98 and G99), what is corrected, where to, and the corrected R planes."""
    lines = draw(
        st.lists(st.one_of(plain_lines(), plain_lines(), PARTIAL), min_size=1, max_size=40)
    )
    head = draw(st.sampled_from(["G21", "G20", "G21 G99", "G21 G81 X0 Y0 Z0 R5"]))
    text = head + "\n" + "\n".join(lines) + "\n"
    try:
        moves = gcode_moves(text)
    except InputError:
        return None
    n = len(moves)
    corrected = np.array(draw(st.lists(st.booleans(), min_size=n, max_size=n)), dtype=bool)
    shift = draw(st.sampled_from([0.0, 1e-4, 0.0123, -2.5]))
    desired = moves.target + shift
    r_planes = np.where(corrected, moves.r_mm + shift / 2, np.nan)
    places = np.full(n, draw(st.sampled_from([2, 3, 4])))
    return text, moves, corrected, desired, r_planes, places


def _walked(step, case):
    text, moves, corrected, desired, r_planes, places = case
    read = np.array([not r for r in moves.reason], bool)
    walk = _Commanded(moves.is_cycle & read, {})  # may get Z, R words added
    walk.cmd, walk.r_cmd = [1.0, 2.0, 50.0], 7.0  # as a previous block may leave it
    found = step(text, moves, slice(0, len(moves)), corrected, desired, r_planes, places, walk)
    edits = [np.asarray(column).tolist() for column in found]  # starts, ends, bytes, lengths
    reached = np.frombuffer(walk.reached_rows, float).reshape(-1, 3)
    carried = np.array([*walk.cmd, walk.cycle_z, walk.r_cmd])
    return edits, carried, reached, walk.reached_at.tolist()


@settings(max_examples=300, deadline=None)
@given(case=cases())
def test_bulk_walk_walks_as_the_move_by_move_walk(case):
    """Same edits, same commanded end, cycle depth, R plane and reached points."""
    if case is None:
        return
    moves = case[1]
    walked = moves.incremental.any() or (moves.cycle_axis != 2).any()  # G91, G18/G19 cycles
    if not len(moves) or walked or {"G28", "G30", "G53"} & set(moves.motion):
        return  # no block, or one _gcode_edits walks move by move
    bulk, slow = _walked(_bulk_block, case), _walked(_walk_block, case)
    assert bulk[0] == slow[0]
    assert np.array_equal(bulk[1], slow[1], equal_nan=True)
    assert np.array_equal(bulk[2], slow[2], equal_nan=True)
    assert bulk[3] == slow[3]


@given(st.lists(st.one_of(NUMBER, st.text("0123456789", min_size=1, max_size=30)), max_size=30))
def test_literal_values_are_float_of_each_literal(literals):
    """Every literal's value, sign of zero included, is ``float`` of its text; its decimals
    are those written."""
    text = " ".join(literals).encode("latin-1")
    starts = np.cumsum([0] + [len(t) + 1 for t in literals[:-1]]).astype(np.int64)
    ends = starts + [len(t) for t in literals]
    values, decimals = literal_values(text, starts[: len(literals)], ends)
    assert decimals.tolist() == [decimals_of(t) for t in literals]
    expected = np.array([float(t) for t in literals])
    assert np.array_equal(values, expected)
    assert np.array_equal(np.signbit(values), np.signbit(expected))


@given(
    st.lists(st.one_of(plain_lines(), partial_lines(), MODAL), min_size=0, max_size=20),
    st.sampled_from(["\n", "\r"]),
)
def test_file_precision_is_the_precision_of_the_literals(lines, newline):
    """The precision the readers keep (the whole-text one, or the line reader alone for lone
    CR endings) is ``precision`` of the X, Y, Z literals of the moves."""
    try:
        moves = gcode_moves(newline.join(["G21", *lines]))
    except InputError:
        return
    starts, ends = moves.word_start[:, :3], moves.word_end[:, :3]
    literals = [
        moves.text[s:e] for s, e in zip(starts.ravel(), ends.ravel(), strict=True) if s >= 0
    ]
    assert _file_precision(moves) == precision(literals)


@settings(max_examples=200, deadline=None)
@given(
    lines=PROGRAMS,
    data=st.data(),
    min_bulk=st.sampled_from([1, 3, 256]),
    decimals=st.sampled_from([None, 4]),
)
def test_edits_in_stretches_are_the_move_by_move_edits(lines, data, min_bulk, decimals):
    """The whole walk, stretches of absolute moves in bulk between G91 moves and G28/G53 resets,
    writes the same bytes and reports the same reached points (and the same moves too far from
    their corrections) as walking every move."""
    text = "\n".join(lines) + "\n"
    try:
        moves = gcode_moves(text)
    except InputError:
        return
    n = len(moves)
    status = data.draw(st.lists(st.booleans(), min_size=n, max_size=n))
    shift = data.draw(st.sampled_from([1e-4, 0.0123, -2.5]))
    desired, r_planes = moves.target + shift, moves.r_mm + shift / 2
    # a tolerance the uniform shift may exceed where a line does not write an axis
    opts = SimpleNamespace(decimals=decimals, tolerance_mm=data.draw(st.sampled_from([0.3, 9.0])))
    results = []
    for whole in (False, True):
        rows = Rows(["p"], np.zeros(n, np.int64), moves.line, moves.motion, [""] * n, moves.target)
        rows.status[np.array(status, bool)] = CORRECTED
        stretches = (lambda m, b, w: [(b, _walk_block)]) if whole else rewrite._stretches
        with (
            mock.patch.object(rewrite, "_stretches", stretches),
            mock.patch.object(rewrite, "_MIN_BULK", min_bulk),
        ):
            goals = (desired, desired)
            out = rewrite._gcode_edits(text, moves, rows, goals, r_planes, opts, {})
        results.append((bytes(out), rows.new, rows.residual_mm, rows.rounding_mm, rows.status))
    (a, *columns_a), (b, *columns_b) = results
    assert a == b
    for x, y in zip(columns_a, columns_b, strict=True):
        assert np.array_equal(x, y, equal_nan=True)


LINE_PIECES = st.sampled_from(
    ["N12 ", "N7\t", "G0 ", "G00 ", "G01 ", "G1 ", "G10 ", "G010 ", "G81 ", "G89 ", "G80 "]
    + ["G73 ", "G98 ", "G99 ", "G100 ", "G0.5 ", "g1 ", "G", "X", "Y", "Z", "R", "F", "N"]
    + ["12", "3", "0", "99", "-", "+", ".", "1.5", " ", "  ", "\t", "(", ")", "(move 12)"]
    + [";", "\r", "9", "#1", "\u0663", "\u03a9", "\xe9", "\x0b"]  # Arabic-Indic 3 is \\d too
)


ANY_LINE = st.one_of(
    plain_lines(),
    st.tuples(plain_lines(), LINE_PIECES, st.integers(0, 40)).map(  # one piece put in a plain one
        lambda t: t[0][: t[2]] + t[1] + t[0][t[2] :]
    ),
    st.lists(LINE_PIECES, max_size=10).map("".join),
)


def _spans_in(line: str) -> list[list[int]]:
    """Where the numbers after the first X, Y, Z, R before any "(" are in ``line``, read
    character by character (-1: none)."""
    words_end = line.find("(") if "(" in line else len(line)
    spans = []
    for letter in "XYZR":
        at = line.find(letter, 0, words_end) + 1
        if not at:
            spans.append([-1, -1])
            continue
        end = at
        while end < len(line) and line[end] in "0123456789.+-":
            end += 1
        spans.append([at, end])
    return spans


@settings(max_examples=400)
@given(st.lists(ANY_LINE, min_size=1, max_size=12), st.lists(ANY_LINE, max_size=6), st.booleans())
def test_line_shapes_read_as_every_line(lines, before, few_kept):
    """Reading each distinct shape of line once (the shapes of the lines read ``before`` known
    already, or forgotten when more than the reader keeps) gives every line the head
    ``_ROW_RE`` finds in it and the number offsets it has."""
    shapes = parse._Shapes()
    with mock.patch.object(parse, "_SHAPES_KEPT", 3 if few_kept else parse._SHAPES_KEPT):
        for part in (before, lines):
            chunk = "\n".join(part)
            try:
                data = chunk.encode("latin-1")
            except UnicodeEncodeError:
                data = None
            ids = shapes.ids(parse._shapes(chunk, data, len(part)))
            heads = parse._ROW_RE.findall(chunk)[: len(part)]
            assert shapes.codes[ids].tolist() == [parse._plain_codes(head) for head in heads]
            assert shapes.spans[ids].tolist() == [_spans_in(line) for line in part]
