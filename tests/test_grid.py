"""Properties of the grid model's prediction and correction (issue 3), on synthetic grids."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import EXAMPLES
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from accugrid.compensation import GridModel
from accugrid.compensation.interpolation import (
    CORNERS,
    METHODS,
    corner_indices,
    idw_weights,
    locate,
    trilinear_weights,
)
from accugrid.compensation.settings import CorrectionSettings
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix

METHOD_POWERS = [("idw", 1.0), ("idw", 2.0), ("idw", 0.5), ("trilinear", 1.0)]

finite = st.floats(-5.0, 5.0, allow_nan=False, allow_infinity=False)


@st.composite
def grids(draw, max_error=5.0):
    """A GridModel with 2..4 vertices per axis, steps 1..400 mm, errors within +-max_error mm."""
    counts = draw(st.tuples(*[st.integers(2, 4)] * 3))
    step = np.array(draw(st.tuples(*[st.floats(1.0, 400.0)] * 3)))
    origin = np.array(draw(st.tuples(*[st.floats(-3000.0, 3000.0)] * 3)))
    errors = draw(arrays(float, (*counts, 3), elements=st.floats(-max_error, max_error)))
    return GridModel(origin, step, errors)


@st.composite
def inside_points(draw, model, n=20):
    """(n, 3) points inside the model's box, with some exactly on faces and vertices."""
    frac = draw(arrays(float, (n, 3), elements=st.floats(0.0, 1.0)))
    span = (model.counts - 1) * model.step
    points = model.origin + frac * span
    snap = draw(arrays(bool, (n, 3)))  # put some coordinates exactly on a grid plane
    idx = np.floor(frac * (model.counts - 1))
    return np.where(snap, model.origin + idx * model.step, points)


@given(grids(), st.sampled_from(METHOD_POWERS))
def test_exact_at_every_vertex(model, method):
    name, power = method
    vertices = model.vertices().reshape(-1, 3)
    predicted = model.predict(vertices, method=name, power=power)
    np.testing.assert_allclose(predicted, model.errors.reshape(-1, 3), rtol=0, atol=1e-9)


@given(
    arrays(float, (3, 50), elements=st.floats(0.0, 1.0)),
    st.tuples(*[st.floats(0.5, 500.0)] * 3),
    st.floats(0.25, 6.0),
)
def test_weights_are_non_negative_and_sum_to_one(frac, step, power):
    for weights in (idw_weights(frac, np.array(step), power), trilinear_weights(frac)):
        assert weights.shape == (8, 50)
        assert (weights >= 0).all()
        np.testing.assert_allclose(weights.sum(axis=0), 1.0, rtol=0, atol=1e-12)


@given(
    arrays(float, (3, 30), elements=st.sampled_from([0.0, 1.0]) | st.floats(0.0, 1.0)),
    st.tuples(*[st.floats(0.5, 500.0)] * 3),
    st.floats(0.25, 6.0),
)
def test_idw_weights_are_seed_eq_12(frac, step, power):
    """q_i = (1/s_i^p) / sum_j (1/s_j^p) from brute-force corner distances; one-hot within the
    documented 1e-9 steps of a vertex."""
    step = np.array(step)
    s = np.linalg.norm((frac.T * step)[:, None, :] - CORNERS * step, axis=2)  # (30, 8) mm
    at_vertex = s.min(axis=1) <= 1e-9 * step.min()
    s_far = s[~at_vertex]
    expected = np.zeros_like(s)
    expected[~at_vertex] = s_far**-power / (s_far**-power).sum(axis=1, keepdims=True)
    expected[at_vertex, s[at_vertex].argmin(axis=1)] = 1.0
    np.testing.assert_allclose(idw_weights(frac, step, power).T, expected, rtol=1e-9, atol=1e-15)


@given(st.data(), grids(), st.sampled_from(METHOD_POWERS))
def test_prediction_within_its_cells_vertex_range(data, model, method):
    name, power = method
    points = data.draw(inside_points(model))
    predicted = model.predict(points, method=name, power=power)
    cell, _ = locate(points.T.copy(), model.origin, model.step, model.counts)
    corner_errors = model.errors.reshape(-1, 3)[corner_indices(cell, model.counts)]  # (8, N, 3)
    assert (predicted >= corner_errors.min(axis=0) - 1e-9).all()
    assert (predicted <= corner_errors.max(axis=0) + 1e-9).all()


@given(st.data(), grids(), st.tuples(finite, finite, finite), st.sampled_from(METHOD_POWERS))
def test_constant_field_reproduced(data, model, value, method):
    name, power = method
    constant = GridModel(model.origin, model.step, np.broadcast_to(value, model.errors.shape))
    points = data.draw(inside_points(constant))
    predicted = constant.predict(points, method=name, power=power)
    np.testing.assert_allclose(predicted, np.broadcast_to(value, predicted.shape), atol=1e-12)


@given(
    st.data(),
    grids(),
    st.tuples(*[st.floats(-2000.0, 2000.0)] * 3),
    st.sampled_from(METHOD_POWERS),
)
def test_translating_grid_and_points_together_changes_nothing(data, model, shift, method):
    name, power = method
    shift = np.array(shift)
    # points in the middle of cells: a translation may move a point on a face by one rounding
    # error into the other cell, where IDW legitimately differs
    frac = data.draw(arrays(float, (20, 3), elements=st.floats(0.01, 0.99)))
    cells = data.draw(arrays(np.int64, (20, 3), elements=st.integers(0, 2)))
    cells = np.minimum(cells, model.counts - 2)
    points = model.origin + (cells + frac) * model.step
    moved = GridModel(model.origin + shift, model.step, model.errors)
    np.testing.assert_allclose(
        moved.predict(points + shift, method=name, power=power),
        model.predict(points, method=name, power=power),
        rtol=0,
        atol=1e-6,
    )


@given(st.data(), grids(max_error=2.0))
def test_iterated_correction_lands_on_target_for_a_robot_with_the_grid_error(data, model):
    """The true robot reaches M = C - e(C) for a command C, e being the grid's own (trilinear,
    continuous) prediction; 30 iterations of P' = P + e(P') must make it reach P."""
    steep = [np.abs(np.diff(model.errors, axis=i)).max() / model.step[i] for i in range(3)]
    lipschitz = math.sqrt(3) * max(steep)
    if lipschitz > 0.3:  # not a contraction fast enough for 30 iterations: shrink the errors
        model = GridModel(model.origin, model.step, model.errors * (0.3 / lipschitz))
    targets = data.draw(inside_points(model))
    command = model.correct(targets, iterations=30, method="trilinear", max_correction_mm=None)
    reached = command - model.predict(command, method="trilinear", outside="clamp")
    np.testing.assert_allclose(reached, targets, rtol=0, atol=1e-6)


@given(st.data(), grids(max_error=1.0), st.floats(0.5, 2.0))
def test_iterated_idw_correction_lands_on_target_inside_one_cell(data, model, power):
    """The same for IDW (discontinuous across faces): errors below 0.002 steps keep targets and
    all iterates inside one cell and away from its vertices, where IDW is a contraction."""
    small = GridModel(model.origin, model.step, model.errors * (0.002 * model.step.min()))
    frac = data.draw(arrays(float, (20, 3), elements=st.floats(0.1, 0.9)))
    cells = np.minimum(data.draw(arrays(np.int64, (20, 3), elements=st.integers(0, 2))), 1)
    targets = small.origin + (np.minimum(cells, small.counts - 2) + frac) * small.step
    command = small.correct(targets, iterations=40, power=power, max_correction_mm=None)
    reached = command - small.predict(command, power=power)
    np.testing.assert_allclose(reached, targets, rtol=0, atol=1e-6)


def unit_cell(errors_by_corner: np.ndarray, step=(2.0, 2.0, 2.0)) -> GridModel:
    """A one-cell grid at the origin; errors_by_corner (8, 3) in corner order c = 4bx + 2by + bz."""
    errors = np.empty((2, 2, 2, 3))
    for c, (bx, by, bz) in enumerate(CORNERS):
        errors[bx, by, bz] = errors_by_corner[c]
    return GridModel(np.zeros(3), np.array(step), errors)


def test_hand_computed_single_cell():
    corner_errors = np.array([[c, 10.0 * c, -c * c] for c in range(8)], dtype=float)
    model = unit_cell(corner_errors)
    mean = corner_errors.mean(axis=0)  # (3.5, 35, -17.5)
    for method in ("idw", "trilinear"):
        np.testing.assert_allclose(model.predict([[1.0, 1.0, 1.0]], method=method)[0], mean)
    # centre of the face x = 0 of a 2 mm cube: corners 0..3 at sqrt(2), corners 4..7 at sqrt(6)
    near, far = 1 / math.sqrt(2), 1 / math.sqrt(6)
    q_near, q_far = near / (4 * near + 4 * far), far / (4 * near + 4 * far)
    expected_x = q_near * (0 + 1 + 2 + 3) + q_far * (4 + 5 + 6 + 7)
    assert model.predict([[0.0, 1.0, 1.0]])[0, 0] == pytest.approx(expected_x, abs=1e-12)
    assert model.predict([[0.0, 1.0, 1.0]], method="trilinear")[0, 0] == pytest.approx(1.5)
    # on the edge x = 0, y = 0 at z = 0.5: corner 0 at 0.5, corner 1 at 1.5, the others further
    s = [math.dist((0, 0, 0.5), 2 * np.array(c)) for c in CORNERS]
    q = [1 / d / sum(1 / t for t in s) for d in s]
    assert model.predict([[0.0, 0.0, 0.5]])[0, 1] == pytest.approx(
        sum(10.0 * c * q[c] for c in range(8)), abs=1e-12
    )
    # power 2 at (0.5, 0.5, 0.5): squared distances 0.75 (corner 0), 0.75 + 2 * ... by hand
    d2 = [sum((0.5 - 2 * b) ** 2 for b in c) for c in CORNERS]  # 0.75, 2.75, 2.75, 4.75, ...
    q2 = [1 / d / sum(1 / t for t in d2) for d in d2]
    assert model.predict([[0.5, 0.5, 0.5]], power=2.0)[0, 0] == pytest.approx(
        sum(c * q2[c] for c in range(8)), abs=1e-12
    )


def test_shared_face_belongs_to_the_upper_cell_and_the_far_face_to_the_last():
    # 3 x 2 x 2 vertices: cells x 0..2 and 2..4; the lower cell's errors are 0, the upper's
    # far vertices 8: on the shared face x = 2, the upper cell's IDW weights give a nonzero value
    errors = np.zeros((3, 2, 2, 3))
    errors[2] = 8.0
    model = GridModel(np.zeros(3), np.full(3, 2.0), errors)
    on_face = model.predict([[2.0, 1.0, 1.0]])[0, 0]
    near, far = 1 / math.sqrt(2), 1 / math.sqrt(6)
    assert on_face == pytest.approx(8 * 4 * far / (4 * near + 4 * far), abs=1e-12)
    assert model.predict([[1.999999, 1.0, 1.0]])[0, 0] == pytest.approx(0.0)
    # the far face x = 4 is in the last cell (x 2..4): its face centre weighs x = 4 as "near"
    on_far_face = model.predict([[4.0, 1.0, 1.0]])[0, 0]
    assert on_far_face == pytest.approx(8 * 4 * near / (4 * near + 4 * far), abs=1e-12)


def test_trilinear_reproduces_an_affine_field_and_is_continuous_across_faces():
    rng = np.random.default_rng(3)
    matrix, offset = rng.normal(size=(3, 3)) * 1e-3, rng.normal(size=3)
    model = GridModel([100.0, -50.0, 0.0], [50.0, 40.0, 30.0], np.zeros((4, 3, 5, 3)))
    model = GridModel(model.origin, model.step, model.vertices() @ matrix.T + offset)
    points = model.origin + rng.random((500, 3)) * (model.upper - model.origin)
    np.testing.assert_allclose(
        model.predict(points, method="trilinear"), points @ matrix.T + offset, atol=1e-12
    )


def test_outside_points_are_named_or_clamped():
    model = unit_cell(np.arange(24.0).reshape(8, 3))
    points = np.array([[1.0, 1.0, 1.0], [2.5, 1.0, 1.0], [1.0, -0.1, 3.0]])
    with pytest.raises(InputError, match=r"2 point\(s\) outside .*point 1 \(2.500, 1.000"):
        model.predict(points)
    with pytest.raises(InputError, match="outside"):
        model.correct(points)
    clamped = model.predict(points, outside="clamp")
    nearest = np.array([[1.0, 1.0, 1.0], [2.0, 1.0, 1.0], [1.0, 0.0, 2.0]])
    np.testing.assert_allclose(clamped, model.predict(nearest))
    np.testing.assert_array_equal(model.contains(points), [True, False, False])
    assert model.contains([[2.0 + 1e-7, 0.0, 0.0]]).all()  # boundary tolerance 1e-6 mm


def test_safety_limit_refuses_the_whole_job():
    errors = np.zeros((8, 3))
    errors[7] = [6.0, 0.0, 0.0]
    model = unit_cell(errors)
    points = np.array([[0.1, 0.1, 0.1], [2.0, 2.0, 2.0]])
    with pytest.raises(InputError, match=r"6\.000 mm at point 1 .*safety limit of 5 mm"):
        model.correct(points)
    np.testing.assert_allclose(model.correct(points, max_correction_mm=7.0)[1], [8.0, 2.0, 2.0])


def test_check_reports_outside_too_long_and_orientation_as_index_arrays():
    errors = np.zeros((8, 3))
    errors[7] = [6.0, 0.0, 0.0]  # 6 mm at vertex (2, 2, 2): above the default 5 mm limit
    model = GridModel(np.zeros(3), np.full(3, 2.0), errors.reshape(2, 2, 2, 3), [0.0, 90.0, 0.0])
    points = np.array([[0.0, 0.0, 0.0], [2.0, 2.0, 2.0], [3.0, 2.0, 2.0]])
    tool_z = abc_to_matrix(np.array([0.0, 90.0, 0.0]))[:, 2]
    tilted = abc_to_matrix(np.array([0.0, 60.0, 0.0]))[:, 2]  # 30 deg from the grid's tool Z
    found = model.check(points, CorrectionSettings(), axes=np.stack([tool_z, tilted, tool_z]))
    np.testing.assert_array_equal(found.outside, [2])
    np.testing.assert_array_equal(found.too_long, [1, 2])  # the outside point is clamped to (2,2,2)
    np.testing.assert_allclose(found.angle, [0.0, 30.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(found.correction[1], [6.0, 0.0, 0.0])
    relaxed = model.check(points, CorrectionSettings(max_correction_mm=None))
    assert relaxed.too_long.size == 0 and relaxed.angle is None
    with pytest.raises(InputError, match="safety limit of 5 mm"):
        model.correct(points[:2])  # correct honours its own limit
    with pytest.raises(InputError, match="outside"):
        model.correct(points, max_correction_mm=None)


def test_settings_pass_the_method_through_and_the_registry_checks_names():
    model = unit_cell(np.random.default_rng(2).normal(size=(8, 3)))
    p = np.array([[0.3, 1.2, 1.9]])
    settings = CorrectionSettings(method="trilinear", iterations=2, max_correction_mm=None)
    once = p + model.predict(p, method="trilinear")
    np.testing.assert_allclose(
        model.correct(p, settings), p + model.predict(once, "trilinear", outside="clamp")
    )
    assert set(METHODS) == {"idw", "trilinear"}
    with pytest.raises(InputError, match="unknown method 'cubic' \\(choose idw or trilinear\\)"):
        CorrectionSettings(method="cubic")


def test_correction_adds_the_predicted_error_and_iterates():
    model = unit_cell(np.random.default_rng(1).normal(size=(8, 3)) * 0.1)
    p = np.array([[0.3, 1.2, 1.9], [1.0, 1.0, 1.0]])
    once = model.correct(p)
    np.testing.assert_allclose(once, p + model.predict(p))
    twice = model.correct(p, iterations=2)
    np.testing.assert_allclose(twice, p + model.predict(once))
    for bad in (0, 1.5, -1):
        with pytest.raises(InputError, match="iterations"):
            model.correct(p, iterations=bad)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"method": "cubic"}, "unknown method"),
        ({"outside": "ignore"}, "unknown outside"),
        ({"power": 0.0}, "power must be > 0"),
        ({"power": 17.0}, "power must be > 0 and <= 16"),
        ({"power": float("nan")}, "power"),
    ],
)
def test_bad_options_are_input_errors(kwargs, message):
    with pytest.raises(InputError, match=message):
        unit_cell(np.zeros((8, 3))).predict([[1.0, 1.0, 1.0]], **kwargs)


def test_bad_point_arrays_are_input_errors():
    model = unit_cell(np.zeros((8, 3)))
    with pytest.raises(InputError, match="shape"):
        model.predict(np.zeros((4, 2)))
    with pytest.raises(InputError, match="point 1 is not finite"):
        model.predict([[1.0, 1.0, 1.0], [np.nan, 1.0, 1.0]])
    assert model.predict(np.empty((0, 3))).shape == (0, 3)


def test_large_chunked_input_matches_small_blocks():
    rng = np.random.default_rng(7)
    model = GridModel([0, 0, 0], [10.0, 20.0, 30.0], rng.normal(size=(4, 5, 3, 3)))
    points = rng.random((200_001, 3)) * (model.upper - model.origin)
    whole = model.predict(points)
    np.testing.assert_allclose(whole[-5:], model.predict(points[-5:]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(whole[:5], model.predict(points[:5]), rtol=0, atol=1e-12)


@given(
    arrays(float, st.tuples(st.integers(0, 30), st.just(3)), elements=st.floats(-0.5, 2.5)),
    st.sampled_from([0.0, 1e-7, -1e-7, 2e-6]),
)
def test_contains_is_the_box_test_of_every_point(points, nudge):
    """Inside the box (1e-6 mm tolerance), point by point, whether all points are inside (the
    per-column shortcut) or not: the same answer as the coordinate comparison."""
    model = unit_cell(np.arange(24.0).reshape(8, 3))
    points = np.where(points > 2.0, 2.0 + nudge, points)  # some on or just past the far faces
    lo, hi = model.origin - 1e-6, model.upper + 1e-6
    expected = [bool(all(lo[a] <= p[a] <= hi[a] for a in range(3))) for p in points.tolist()]
    assert model.contains(points).tolist() == expected
    inside = points[expected]
    assert model.contains(inside).tolist() == [True] * len(inside)


def test_from_measurements_takes_a_file_a_measurements_or_the_arrays():
    """A file, its Measurements, the arrays (commanded, measured, abc) and their tuple are one
    grid; one array alone is a TypeError that says what is missing."""
    from accugrid.compensation.measurements import read_measurements

    path = EXAMPLES / "grid_200mm.csv"
    meas = read_measurements(path)
    by_file = GridModel.from_measurements(path)
    for other in (
        GridModel.from_measurements(meas),
        GridModel.from_measurements(meas.commanded, meas.measured, meas.abc),
        GridModel.from_measurements((meas.commanded, meas.measured, meas.abc)),
    ):
        assert np.array_equal(other.errors, by_file.errors)
        assert np.array_equal(other.orientation_abc, by_file.orientation_abc)
    assert "6x7x6 vertices" in repr(by_file) and "grid_200mm.csv" in repr(by_file)
    with pytest.raises(TypeError, match="measured"):
        GridModel.from_measurements(meas.commanded)
