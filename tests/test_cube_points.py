"""Test points of a cube (GB/T 12642-2001 / ISO 9283, seed Sec. 4.3) against hand-computed
coordinates and the geometric rules they must obey."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from accugrid.compensation.cube_points import (
    TEST_LABELS,
    VERTEX_LABELS,
    cube_test_points,
    cube_vertices,
)
from accugrid.infra.errors import InputError

CENTRE = np.array([[100.0, 200.0, 300.0]])
STEP = 50.0

# Written out by hand for the cube of edge 50 mm around (100, 200, 300).
HAND_VERTICES = {
    "C1": (75, 175, 275),
    "C2": (125, 175, 275),
    "C3": (125, 225, 275),
    "C4": (75, 225, 275),
    "C5": (75, 175, 325),
    "C6": (125, 175, 325),
    "C7": (125, 225, 325),
    "C8": (75, 225, 325),
}
# L = 50 * sqrt(3); 0.1 * L along a space diagonal moves 5 mm on every axis towards the centre.
HAND_TESTS = {
    "P1": (100, 200, 300),
    "P2": (80, 180, 280),  # near C1 on C1-C7
    "P3": (120, 180, 280),  # near C2 on C2-C8
    "P4": (120, 220, 320),  # near C7 on C1-C7
    "P5": (80, 220, 320),  # near C8 on C2-C8
    "P6": (120, 220, 280),  # near C3 on C3-C5
    "P7": (80, 220, 280),  # near C4 on C4-C6
    "P8": (80, 180, 320),  # near C5 on C3-C5
    "P9": (120, 180, 320),  # near C6 on C4-C6
}


def test_vertices_match_hand_computed():
    got = cube_vertices(CENTRE, STEP)[0]
    want = np.array([HAND_VERTICES[k] for k in VERTEX_LABELS], dtype=float)
    np.testing.assert_allclose(got, want)


def test_test_points_match_hand_computed():
    got = cube_test_points(CENTRE, STEP)[0]
    want = np.array([HAND_TESTS[k] for k in TEST_LABELS], dtype=float)
    np.testing.assert_allclose(got, want)


def _coplanar(points):
    centred = points - points.mean(axis=0)
    return np.linalg.svd(centred, compute_uv=False)[-1] < 1e-9


def test_seed_measuring_planes_are_diagonal_planes():
    v = dict(zip(VERTEX_LABELS, cube_vertices(CENTRE, STEP)[0], strict=True))
    p = dict(zip(TEST_LABELS, cube_test_points(CENTRE, STEP)[0], strict=True))
    planes = [
        ("C1", "C2", "C7", "C8"),
        ("C2", "C3", "C8", "C5"),
        ("C3", "C4", "C5", "C6"),
        ("C4", "C1", "C6", "C7"),
    ]
    for plane in planes:
        corners = np.array([v[k] for k in plane])
        assert _coplanar(np.vstack([corners, CENTRE])), plane  # through the centre: diagonal
        a, b, c, d = corners  # first two and last two are opposite parallel edges
        assert np.isclose(np.linalg.norm(a - b), STEP) and np.isclose(np.linalg.norm(c - d), STEP)
    # P2..P5 in the standard's plane C1-C2-C7-C8, P6..P9 in the opposite diagonal plane.
    first = np.array([v[k] for k in ("C1", "C2", "C7", "C8")] + [p[f"P{i}"] for i in (2, 3, 4, 5)])
    other = np.array([v[k] for k in ("C3", "C4", "C5", "C6")] + [p[f"P{i}"] for i in (6, 7, 8, 9)])
    assert _coplanar(first) and _coplanar(other)


finite = st.floats(-3000, 3000, allow_nan=False)


@given(st.tuples(finite, finite, finite), st.floats(1.0, 1000.0))
def test_test_points_at_tenth_of_diagonal_from_a_corner(centre, step):
    c = np.array([centre])
    verts = cube_vertices(c, step)[0]
    tests = cube_test_points(c, step)[0]
    np.testing.assert_allclose(tests[0], c[0], atol=1e-9)
    dist = np.linalg.norm(tests[1:, None, :] - verts[None, :, :], axis=2)
    nearest = dist.min(axis=1)
    np.testing.assert_allclose(nearest, 0.1 * np.sqrt(3) * step, rtol=1e-9, atol=1e-9)
    # every corner has exactly one test point near it
    assert sorted(dist.argmin(axis=1)) == list(range(8))
    assert np.all(np.abs(tests - c[0]) <= 0.5 * step + 1e-9)


def test_vectorized_over_cubes():
    centres = np.array([[0.0, 0, 0], [10, 20, 30]])
    got = cube_test_points(centres, np.array([10.0, 20.0]))
    assert got.shape == (2, 9, 3)
    np.testing.assert_allclose(got[1], cube_test_points(centres[1:], 20.0)[0])


@pytest.mark.parametrize("step", [0.0, -5.0, np.nan])
def test_bad_step_is_input_error(step):
    with pytest.raises(InputError, match="step|finite"):
        cube_vertices(CENTRE, step)


def test_bad_centre_shape_is_input_error():
    with pytest.raises(InputError, match="centres"):
        cube_test_points(np.zeros(3), 10.0)
