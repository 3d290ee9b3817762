"""The Sec. 4.1 base-frame procedure on synthetic tracker points from known random frames.

Tolerances (noise sigma 0.01..0.05 mm, A1 arc 90..180°, 40 plane points, 24 arc points, 6 holes)
come from 600 measured random cases: worst origin error 9.4 sigma (mm), worst Z and X axis
errors 0.21 sigma (deg); the bounds below are about 1.6 times those.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from accugrid.infra.errors import InputError
from accugrid.kinematics.base_frame import MAX_AXIS_TILT_DEG, fit_robot_frame
from accugrid.kinematics.frames import invert, transform_points
from accugrid.kinematics.tracker_sim import simulate_tracker_points

ORIGIN_PER_SIGMA = 15.0  # mm of origin error per mm of noise sigma
AXIS_PER_SIGMA = 0.35  # deg of axis error per mm of noise sigma


def _random_frame(rng: np.random.Generator) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3] = Rotation.random(random_state=rng).as_matrix()
    pose[:3, 3] = rng.uniform(-6000.0, 6000.0, 3)
    return pose


def _angle_deg(u: np.ndarray, v: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip(u @ v, -1.0, 1.0))))


def _fit(pts, **kwargs):
    return fit_robot_frame(pts.base_plane, pts.a1_circle, pts.flange_holes, **kwargs)


@given(
    seed=st.integers(0, 2**32 - 1),
    noise=st.floats(0.01, 0.05),
    arc=st.floats(90.0, 180.0),
    tilt=st.floats(0.0, 0.5),
)
@settings(max_examples=40)
def test_recovers_known_frame(seed, noise, arc, tilt):
    rng = np.random.default_rng(seed)
    true = _random_frame(rng)
    pts = simulate_tracker_points(true, noise, seed=seed, arc_deg=arc, surface_tilt_deg=tilt)
    fit = _fit(pts)
    got = fit.tracker_T_robot
    np.testing.assert_allclose(got[:3, :3] @ got[:3, :3].T, np.eye(3), atol=1e-12)
    assert np.linalg.det(got[:3, :3]) == pytest.approx(1.0)
    assert np.linalg.norm(got[:3, 3] - true[:3, 3]) < ORIGIN_PER_SIGMA * noise
    # Signs: Z up (toward the robot), X toward the flange; errors are small angles, not 180°.
    assert _angle_deg(got[:3, 2], true[:3, 2]) < AXIS_PER_SIGMA * noise
    assert _angle_deg(got[:3, 0], true[:3, 0]) < AXIS_PER_SIGMA * noise
    assert fit.plane.rms_mm < 2.0 * noise
    assert fit.a1_circle.rms_mm < 3.0 * noise
    assert fit.a1_circle.arc_deg == pytest.approx(arc, abs=0.5)
    assert fit.axis_tilt_deg == pytest.approx(tilt, abs=0.05)


@given(seed=st.integers(0, 2**32 - 1))
@settings(max_examples=20)
def test_moving_the_tracker_moves_the_frame_with_it(seed):
    """Fitting points seen from a tracker moved by G gives G·tracker_T_robot (noise included)."""
    rng = np.random.default_rng(seed)
    pts = simulate_tracker_points(_random_frame(rng), 0.03, seed=seed)
    moved_by = _random_frame(rng)
    moved = [
        transform_points(moved_by, p) for p in (pts.base_plane, pts.a1_circle, pts.flange_holes)
    ]
    before = _fit(pts).tracker_T_robot
    after = fit_robot_frame(*moved).tracker_T_robot
    np.testing.assert_allclose(after, moved_by @ before, atol=1e-6)


def test_smr_radius_moves_origin_along_z():
    true = np.eye(4)
    pts = simulate_tracker_points(true, 0.0, smr_radius_mm=19.05)
    exact = _fit(pts).tracker_T_robot
    np.testing.assert_allclose(exact, true, atol=1e-8)
    thinner = _fit(pts, smr_radius_mm=6.35).tracker_T_robot
    np.testing.assert_allclose(thinner[:3, :3], true[:3, :3], atol=1e-9)
    np.testing.assert_allclose(thinner[:3, 3], [0.0, 0.0, 19.05 - 6.35], atol=1e-8)


def test_robot_frame_coordinates_of_the_flange_holes():
    """At mechanical zero the flange-hole centre lies on +X with Y = 0 in the fitted frame."""
    true = _random_frame(np.random.default_rng(7))
    pts = simulate_tracker_points(true, 0.02, seed=7)
    fit = _fit(pts)
    centre = transform_points(invert(fit.tracker_T_robot), fit.flange_holes.center[None])[0]
    assert centre[0] > 1700.0
    assert abs(centre[1]) < 1e-9
    assert centre[2] > 1700.0


def test_a1_arc_in_the_base_plane_refused():
    pts = simulate_tracker_points(np.eye(4), 0.02)
    flat = pts.a1_circle.copy()
    flat[:, 2] = 25.0
    with pytest.raises(InputError, match=r"only 6\.0 mm from the base plane") as err:
        fit_robot_frame(
            pts.base_plane, flat, pts.flange_holes, sources=("p.csv", "a1.csv", "h.csv")
        )
    assert err.value.path == "a1.csv"


def test_tilted_a1_axis_refused():
    pts = simulate_tracker_points(np.eye(4), 0.02)
    tilt = MAX_AXIS_TILT_DEG + 1.0
    rot = Rotation.from_euler("x", tilt, degrees=True).as_matrix()
    with pytest.raises(InputError, match=rf"A1 axis is tilted {tilt:.2f}° .*at most"):
        fit_robot_frame(pts.base_plane, pts.a1_circle @ rot.T, pts.flange_holes)


def test_flange_holes_on_the_a1_axis_refused():
    pts = simulate_tracker_points(np.eye(4), 0.02)
    on_axis = pts.flange_holes - [1765.0, 0.0, 0.0]
    with pytest.raises(InputError, match=r"from the A1 axis .*mechanical zero"):
        fit_robot_frame(pts.base_plane, pts.a1_circle, on_axis)


def test_too_few_points_and_short_arc_name_their_file():
    pts = simulate_tracker_points(np.eye(4), 0.02, arc_deg=20.0)
    srcs = ("p.csv", "a1.csv", "h.csv")
    with pytest.raises(InputError, match="A1 circle: .* of arc") as err:
        fit_robot_frame(pts.base_plane, pts.a1_circle, pts.flange_holes, sources=srcs)
    assert str(err.value).startswith("a1.csv: ")
    pts = simulate_tracker_points(np.eye(4), 0.02)
    with pytest.raises(InputError, match="flange-hole circle: 2 point") as err:
        fit_robot_frame(pts.base_plane, pts.a1_circle, pts.flange_holes[:2], sources=srcs)
    assert err.value.path == "h.csv"
    with pytest.raises(InputError, match="SMR radius"):
        fit_robot_frame(pts.base_plane, pts.a1_circle, pts.flange_holes, smr_radius_mm=-1.0)
