"""Points CSV parsing (errors located by file/line/column) and the i,j,k orientation rule."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from accugrid.codegen.points import parse_points, read_points
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix, orient_along_axes, too_tilted


def test_parse_abc_with_extra_columns():
    pts = parse_points(
        "# a comment\nID,X,Y,Z,A,B,C,Diameter,depth,feed,note\n"
        "H1,1,2,3,0,90,0,4.83,6,,first\nH2,4,5,6,10,80,5,,,2.5,second\n",
        "p.csv",
    )
    assert pts.ids == ["H1", "H2"] and pts.lines == [3, 4] and pts.orientation == "abc"
    np.testing.assert_array_equal(pts.xyz, [[1, 2, 3], [4, 5, 6]])
    np.testing.assert_allclose(pts.axis, abc_to_matrix(pts.abc)[:, :, 2])
    np.testing.assert_allclose(pts.axis[0], [1, 0, 0], atol=1e-12)
    assert pts.diameter[0] == 4.83 and np.isnan(pts.diameter[1])
    assert np.isnan(pts.feed[0]) and pts.feed[1] == 2.5
    assert pts.table.text("note") == ["first", "second"]
    assert pts.label(1) == "hole 'H2' (p.csv:4)"


def test_ijk_normalised_and_default_ids():
    pts = parse_points("x,y,z,i,j,k\n0,0,0,0,0,-2\n1,1,1,3,4,0\n")
    assert pts.ids == ["1", "2"] and pts.orientation == "ijk" and pts.abc is None
    np.testing.assert_allclose(pts.axis, [[0, 0, -1], [0.6, 0.8, 0]])


def test_no_orientation():
    pts = parse_points("x,y,z\n0,0,0\n")
    assert pts.orientation is None and pts.axis is None


@pytest.mark.parametrize(
    "text, message, line, column",
    [
        ("x,y,z\n1,2,abc\n", "'abc' in column 'z' is not a number", 2, 3),
        ("x,y,z\n1,nan,3\n", "not a finite number", 2, 2),
        ("x,y,z\n1,,3\n", "empty cell", 2, 2),
        ("id,x,y,z\nA,1,2,3\nB,1,2,3\nA,1,2,3\n", "duplicate id 'A' (first on line 2)", 4, 1),
        ("id,x,y,z\n ,1,2,3\n", "empty id", 2, 1),
        ("x,y,z,i,j,k\n1,2,3,0,0,1\n1,2,3,0,0,0\n", "zero length", 3, 4),
        ("x,y,z,i,j,k\n1,2,3,0,inf,1\n", "not a finite number", 2, 5),
        ("x,y,z,a,b,c\n1,2,3,0,x,1\n", "'x' in column 'b' is not a number", 2, 5),
        ("x,y,z,depth\n1,2,3,-1\n", "depth must be positive", 2, 4),
        ("x,y,z,feed\n1,2,3,0\n", "feed must be positive", 2, 4),
        ("x,y,z,a,b\n1,2,3,0,0\n", "missing column(s) c", 1, None),
        ("x,y,z,a,b,c,i,j,k\n1,2,3,0,0,0,0,0,1\n", "either as a,b,c or as i,j,k", 1, None),
        ("x,y\n1,2\n", "missing column(s) z", 1, None),
        ("x,y,z\n1,2,3,4\n", "4 fields", 2, None),
    ],
)
def test_errors_are_located(text, message, line, column):
    with pytest.raises(InputError) as info:
        parse_points(text, "pts.csv")
    err = info.value
    assert message in err.message
    assert (err.path, err.line, err.column) == ("pts.csv", line, column)


def test_read_points_file(tmp_path):
    path = tmp_path / "p.csv"
    path.write_bytes("\ufeffx,y,z\n1,2,3\n".encode())
    assert read_points(path).xyz.tolist() == [[1, 2, 3]]
    with pytest.raises(InputError, match="cannot read"):
        read_points(tmp_path / "missing.csv")


unit = st.tuples(*[st.floats(-1, 1)] * 3).map(np.array).filter(lambda v: np.linalg.norm(v) > 0.1)
angles = st.tuples(st.floats(-180, 180), st.floats(-89, 89), st.floats(-180, 180))


@given(unit, angles)
def test_orientation_rule_is_the_nearest_rotation_about_the_axis(axis, abc):
    reference = abc_to_matrix(np.array(abc))
    axis = axis / np.linalg.norm(axis)
    if too_tilted(axis[None], reference)[0]:
        return
    rot = orient_along_axes(axis[None], reference)[0]
    # a rotation whose tool Z is the drill axis
    np.testing.assert_allclose(rot @ rot.T, np.eye(3), atol=1e-9)
    assert np.linalg.det(rot) == pytest.approx(1.0)
    np.testing.assert_allclose(rot[:, 2], axis, atol=1e-9)

    # no other rotation about the drill axis is closer to the reference
    def angle_to_ref(r):
        return np.arccos(np.clip((np.trace(reference.T @ r) - 1) / 2, -1, 1))

    best = angle_to_ref(rot)
    for phi in np.radians(np.arange(-180, 180, 7.5)):
        c, s = np.cos(phi), np.sin(phi)
        spun = rot @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
        assert angle_to_ref(spun) >= best - 1e-9
    # the relative rotation is exactly the tilt between the tool axes
    tilt = np.arccos(np.clip(axis @ reference[:, 2], -1, 1))
    assert best == pytest.approx(tilt, abs=1e-6)


@given(unit, angles, st.tuples(*[st.floats(-1e-3, 1e-3)] * 3))
def test_orientation_rule_is_stable_hole_to_hole(axis, abc, nudge):
    reference = abc_to_matrix(np.array(abc))
    a = axis / np.linalg.norm(axis)
    b = a + np.array(nudge)
    b /= np.linalg.norm(b)
    if too_tilted(np.stack([a, b]), reference).any():
        return
    ra, rb = orient_along_axes(np.stack([a, b]), reference)
    change = np.arccos(np.clip((np.trace(ra.T @ rb) - 1) / 2, -1, 1))
    step = np.arccos(np.clip(a @ b, -1, 1))
    # a small change of axis is a comparably small change of orientation (the map is smooth
    # away from the refused opposite axis: factor 1/cos(75 deg) at most at 150 deg tilt)
    assert change <= 4.0 * step + 1e-7


def test_too_tilted_axes_flagged():
    reference = abc_to_matrix(np.array([0.0, 90.0, 0.0]))  # tool Z = robot +X
    flags = too_tilted(np.array([[1.0, 0, 0], [0, 1.0, 0], [-1.0, 0, 0]]), reference)
    assert flags.tolist() == [False, False, True]


numbers = st.floats(-1e6, 1e6, allow_nan=False).map(lambda v: repr(v))
odd_text = st.sampled_from(
    ["1_000", " 2.5 ", "1e3", "+4", "-0", ".5", "5.", "0x10", "1,5", "", "1 2"]
)


@given(st.lists(st.tuples(numbers, numbers, st.one_of(numbers, odd_text)), min_size=1, max_size=8))
def test_fast_number_path_agrees_with_the_table_reader(rows):
    from accugrid.infra.csvtable import parse_table

    text = "x,y,z\n" + "".join(f'{a},{b},"{c}"\n' for a, b, c in rows)
    try:
        expected = parse_table(text, "p.csv").floats(["x", "y", "z"])
    except InputError as err:
        with pytest.raises(InputError) as info:
            parse_points(text, "p.csv")
        assert str(info.value) == str(err)
        return
    np.testing.assert_array_equal(parse_points(text, "p.csv").xyz, expected)
