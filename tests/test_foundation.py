"""The shared plumbing: CSV tables, safe text, fixed-point numbers, atomic writes, KUKA ABC."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from accugrid.app.cli import main
from accugrid.codegen.krl.names import krl_identifier
from accugrid.infra.atomic import write_files
from accugrid.infra.csvtable import parse_table
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import comment_text, fixed, fixed_many, fixed_same
from accugrid.kinematics import frames


def test_table_skips_comments_and_tracks_lines():
    text = "# made by hand\nX,y,Z\n\n1,2,3\n# note\n4,5,6\n"
    table = parse_table(text, "p.csv")
    assert table.lines == [4, 6]
    np.testing.assert_array_equal(table.floats(["x", "Y", "z"]), [[1, 2, 3], [4, 5, 6]])


def test_table_reports_file_line_column_of_bad_number():
    with pytest.raises(InputError) as err:
        parse_table("x,y,z\n1,2,3\n1,abc,3\n", "p.csv").floats(["x", "y", "z"])
    assert str(err.value).startswith("p.csv:3:2: 'abc' in column 'y'")


@pytest.mark.parametrize("cell", ["nan", "inf", "-Infinity"])
def test_table_rejects_non_finite(cell):
    with pytest.raises(InputError, match="p.csv:2:1"):
        parse_table(f"x\n{cell}\n", "p.csv").floats(["x"])


def test_table_quoted_newline_is_one_record():
    table = parse_table('id,x\n"a\nb",1\n2,3\n', "p.csv")
    assert table.text("id") == ["a\nb", "2"]
    assert table.lines == [2, 4]


def test_table_ragged_row_and_duplicate_header():
    with pytest.raises(InputError, match="p.csv:3: 2 fields"):
        parse_table("x,y,z\n1,2,3\n1,2\n", "p.csv")
    with pytest.raises(InputError, match="p.csv:1:2: column 'X' appears twice"):
        parse_table("x,X\n1,2\n", "p.csv")


@given(st.floats(-1e6, 1e6), st.integers(0, 6))
def test_fixed_is_fixed_point_and_round_trips(value, decimals):
    text = fixed(value, decimals)
    assert "e" not in text.lower()
    assert len(text.partition(".")[2]) == decimals
    assert abs(float(text) - value) <= 0.5 * 10**-decimals + 1e-9 * abs(value)
    assert not (text.startswith("-") and float(text) == 0)


def test_fixed_refuses_nan():
    with pytest.raises(ValueError):
        fixed(float("nan"))


@given(st.text(max_size=300))
def test_comment_text_cannot_break_out(text):
    safe = comment_text(text)
    assert len(safe) <= 60
    assert not set(safe) & set("\r\n;()%&{}'\"\t\x00")


@given(st.text(max_size=100))
def test_krl_identifier_is_valid(text):
    name = krl_identifier(text)
    assert 1 <= len(name) <= 24
    assert name[0].isalpha() or name[0] == "_"
    assert all(ch.isascii() and (ch.isalnum() or ch == "_") for ch in name)


def test_write_files_refuses_existing_and_inputs(tmp_path):
    out = tmp_path / "a.txt"
    write_files({out: "one\r\n"})
    assert out.read_bytes() == b"one\r\n"
    with pytest.raises(InputError, match="exists"):
        write_files({out: "two"})
    with pytest.raises(InputError, match="input"):
        write_files({out: "two"}, inputs=[out], force=True)
    write_files({out: "two"}, force=True)
    assert out.read_text() == "two"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"]


def test_write_files_is_all_or_nothing(tmp_path):
    existing = tmp_path / "b.txt"
    existing.write_text("keep")
    with pytest.raises(InputError):
        write_files({tmp_path / "a.txt": "new", existing: "x"})
    assert not (tmp_path / "a.txt").exists()
    assert existing.read_text() == "keep"


@given(
    st.floats(-180, 180),
    st.floats(-89, 89),
    st.floats(-180, 180),
)
def test_kuka_abc_is_zyx_intrinsic(a, b, c):
    def rz(t):
        t = np.radians(t)
        return np.array([[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, 1]])

    def ry(t):
        t = np.radians(t)
        return np.array([[np.cos(t), 0, np.sin(t)], [0, 1, 0], [-np.sin(t), 0, np.cos(t)]])

    def rx(t):
        t = np.radians(t)
        return np.array([[1, 0, 0], [0, np.cos(t), -np.sin(t)], [0, np.sin(t), np.cos(t)]])

    rot = frames.abc_to_matrix([a, b, c])
    np.testing.assert_allclose(rot, rz(a) @ ry(b) @ rx(c), atol=1e-12)
    np.testing.assert_allclose(frames.abc_to_matrix(frames.matrix_to_abc(rot)), rot, atol=1e-9)


@given(st.lists(st.floats(-1000, 1000), min_size=6, max_size=6))
def test_pose_inverse_round_trip(xyzabc):
    pose = frames.pose_from_xyzabc(np.array(xyzabc))
    np.testing.assert_allclose(frames.invert(pose) @ pose, np.eye(4), atol=1e-9)
    pts = np.array([[1.0, 2.0, 3.0], [-5.0, 0.0, 7.0]])
    back = frames.transform_points(frames.invert(pose), frames.transform_points(pose, pts))
    np.testing.assert_allclose(back, pts, atol=1e-9)


def test_cli_version_and_unknown_command(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["--version"])
    assert exit_info.value.code == 0
    assert "accugrid" in capsys.readouterr().out
    with pytest.raises(SystemExit) as exit_info:
        main(["no-such-command"])
    assert exit_info.value.code == 2


@given(
    st.lists(st.floats(-1e6, 1e6) | st.sampled_from([0.0, -0.0, -1e-9, 5e-4, -5e-4]), max_size=50),
    st.integers(0, 6),
)
def test_fixed_many_equals_fixed(values, decimals):
    assert fixed_many(np.array(values), decimals) == [fixed(v, decimals) for v in values]


@given(
    st.lists(
        st.tuples(
            st.floats(-1e4, 1e4) | st.sampled_from([0.0, -0.0, 0.0625, -0.0625, 2.5, 1.0005]),
            # the second number: equal, within a unit of the last place (ties among them), or far
            st.sampled_from([0.0, 1e-12, -1e-12, 5e-4, -5e-4, 1e-3, -1e-3, 0.05, 0.5, 1.0])
            | st.floats(-2e-3, 2e-3),
        ),
        max_size=40,
    ),
    st.integers(0, 4),
)
def test_fixed_same_is_whether_the_texts_are_equal(pairs, decimals):
    a = np.array([p[0] for p in pairs])
    b = a + np.array([p[1] * 10.0 ** (3 - decimals) for p in pairs])
    expected = [fixed(x, decimals) == fixed(y, decimals) for x, y in zip(a, b, strict=True)]
    assert fixed_same(a, b, decimals).tolist() == expected


def test_fixed_same_broadcasts_and_formats_only_the_close_pairs():
    a = np.array([[1.0, 1.0004], [-0.0004, 7.0]])
    b = np.array([1.0, 1.0006])  # one row: compared with both rows of a
    assert fixed_same(a, b, 3).tolist() == [[True, False], [False, False]]
    assert fixed_same(np.array([-0.0004, 0.0004]), 0.0, 3).tolist() == [True, True]  # "0.000"


def test_fixed_many_refuses_nan():
    with pytest.raises(ValueError):
        fixed_many(np.array([1.0, float("inf")]), 3)


@given(
    st.floats(-179.9, 179.9),
    st.one_of(st.floats(-89.99, 89.99), st.sampled_from([-90.0, 90.0])),
    st.floats(-179.9, 179.9),
)
def test_kuka_abc_matches_scipy_zyx_including_gimbal_lock(a, b, c):
    """The numpy ABC conversions agree with scipy's Rotation (ZYX intrinsic), the usual peer;
    at B = ±90 both put the whole vertical rotation into A and set C = 0."""
    import warnings

    from scipy.spatial.transform import Rotation

    peer = Rotation.from_euler("ZYX", [a, b, c], degrees=True)
    np.testing.assert_allclose(frames.abc_to_matrix([a, b, c]), peer.as_matrix(), atol=1e-12)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # scipy warns at gimbal lock
        expected = peer.as_euler("ZYX", degrees=True)
    got = frames.matrix_to_abc(peer.as_matrix())
    np.testing.assert_allclose(got, expected, atol=1e-6)
    if abs(b) == 90.0:
        assert got[2] == 0.0


@given(
    st.lists(
        st.tuples(
            st.floats(-179.9, 179.9),
            st.one_of(st.floats(-89.99, 89.99), st.sampled_from([-90.0, 90.0])),
            st.floats(-179.9, 179.9),
        ),
        min_size=1,
        max_size=20,
    )
)
def test_abc_of_a_batch_is_the_abc_of_each_matrix(angles):
    """matrix_to_abc over (N, 3, 3) with gimbal-locked and free rotations mixed: number for
    number each matrix's own A, B, C (the locked rule only where it applies)."""
    rot = frames.abc_to_matrix(np.array(angles))
    batch = frames.matrix_to_abc(rot)
    single = np.array([frames.matrix_to_abc(r) for r in rot])
    np.testing.assert_array_equal(batch, single)
    np.testing.assert_array_equal(frames.matrix_to_abc(rot[None])[0], batch)


@settings(max_examples=15, deadline=None)
@given(
    st.integers(0, 3 * frames.BLAS_ROWS + 5),
    st.floats(-3.0, 3.0),
    st.sampled_from(["n", "t"]),
    st.integers(0, 2**32 - 1),
)
def test_rows_times_is_one_product_in_blocks(n, scale, order, seed):
    """rows_times gives the numbers of one (N, 3) @ (3, 3) product, above and below one block,
    for a matrix given as is or transposed (a view), for one row, and for a vector (3,)."""
    rng = np.random.default_rng(seed)
    rows = rng.normal(size=(n, 3)) * 10.0**scale
    matrix = rng.normal(size=(3, 3))
    matrix = matrix.T if order == "t" else matrix
    np.testing.assert_array_equal(frames.rows_times(rows, matrix), rows @ matrix)
    np.testing.assert_array_equal(frames.rows_times(rows, matrix[:, 1]), rows @ matrix[:, 1])
    if n:
        np.testing.assert_array_equal(frames.rows_times(rows[0], matrix), rows[0] @ matrix)
