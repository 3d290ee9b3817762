"""Plane and 3D circle fits: recovery from noisy synthetic points, residuals, refusals.

Tolerances are multiples of the noise sigma, set from measured worst cases with margin (1500
random cases each: circle centre 5.2 sigma, normal 4.3 sigma/r rad, radius 4.1 sigma; plane
normal 1.1 sigma/half-extent rad, offset 0.7 sigma, RMS residual 0.66..1.30 sigma).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from accugrid.infra.errors import InputError
from accugrid.kinematics.fitting import MIN_ARC_DEG, fit_circle, fit_plane, intersect_line_plane


def _angle_rad(u: np.ndarray, v: np.ndarray) -> float:
    """Angle between two lines (sign of the directions ignored)."""
    return float(np.arccos(min(1.0, abs(float(u @ v)))))


CLOSED_DEG = 359.0
"""Arcs at least this long are drawn as n points evenly around the full circle."""


def _circle_points(center, rot, radius, start_deg, arc_deg, n, noise, rng) -> np.ndarray:
    closed = arc_deg >= CLOSED_DEG
    theta = np.radians(start_deg + np.linspace(0.0, arc_deg, n, endpoint=not closed))
    local = np.column_stack([radius * np.cos(theta), radius * np.sin(theta), np.zeros(n)])
    return center + local @ rot.T + rng.normal(0.0, noise, (n, 3))


@given(
    seed=st.integers(0, 2**32 - 1),
    noise=st.floats(0.01, 0.05),
    radius=st.floats(50.0, 2000.0),
    arc=st.floats(90.0, 360.0),
)
def test_circle_fit_recovers_circle(seed, noise, radius, arc):
    rng = np.random.default_rng(seed)
    rot = Rotation.random(random_state=rng).as_matrix()
    center = rng.uniform(-5000.0, 5000.0, 3)
    pts = _circle_points(center, rot, radius, rng.uniform(0, 360), arc, 24, noise, rng)
    fit = fit_circle(pts)
    assert np.linalg.norm(fit.center - center) < 10.0 * noise
    assert _angle_rad(fit.normal, rot[:, 2]) < 10.0 * noise / radius
    assert abs(fit.radius_mm - radius) < 8.0 * noise
    assert fit.rms_mm < 3.0 * noise
    assert fit.rms_mm <= fit.max_mm < 8.0 * noise
    spacing = arc / 23 if arc < CLOSED_DEG else arc / 24
    covered = 360.0 - max(spacing, 360.0 - 23 * spacing)
    assert fit.arc_deg == pytest.approx(covered, abs=0.5)
    np.testing.assert_allclose(np.sqrt(np.mean(fit.distances(pts) ** 2)), fit.rms_mm)


@given(
    seed=st.integers(0, 2**32 - 1),
    noise=st.floats(0.01, 0.05),
    half=st.floats(200.0, 2000.0),
)
def test_plane_fit_recovers_plane(seed, noise, half):
    rng = np.random.default_rng(seed)
    rot = Rotation.random(random_state=rng).as_matrix()
    origin = rng.uniform(-5000.0, 5000.0, 3)
    local = np.column_stack([rng.uniform(-half, half, (40, 2)), np.zeros(40)])
    pts = origin + local @ rot.T + rng.normal(0.0, noise, (40, 3))
    fit = fit_plane(pts)
    assert _angle_rad(fit.normal, rot[:, 2]) < 3.0 * noise / half
    assert abs((fit.point - origin) @ rot[:, 2]) < 2.5 * noise
    assert 0.4 * noise < fit.rms_mm < 1.8 * noise
    assert fit.rms_mm <= fit.max_mm
    np.testing.assert_allclose(np.abs(fit.distances(pts)).max(), fit.max_mm)


def test_exact_circle_has_zero_residual():
    rot = Rotation.from_euler("xyz", [10.0, -20.0, 30.0], degrees=True).as_matrix()
    center = np.array([100.0, -200.0, 300.0])
    pts = _circle_points(center, rot, 80.0, 0.0, 300.0, 6, 0.0, np.random.default_rng(0))
    fit = fit_circle(pts)
    np.testing.assert_allclose(fit.center, center, atol=1e-9)
    assert fit.radius_mm == pytest.approx(80.0, abs=1e-9)
    assert fit.max_mm < 1e-9


@pytest.mark.parametrize("fit", [fit_plane, fit_circle])
def test_fewer_than_three_points_refused(fit):
    with pytest.raises(InputError, match=r"2 point\(s\), at least 3 are needed"):
        fit(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]), "test")


@pytest.mark.parametrize("fit", [fit_plane, fit_circle])
def test_collinear_points_refused(fit):
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 1000.0, 10)
    pts = np.outer(t, [0.6, 0.8, 0.0]) + rng.normal(0.0, 0.02, (10, 3))
    with pytest.raises(InputError, match="collinear"):
        fit(pts, "test")
    with pytest.raises(InputError, match="collinear"):
        fit(np.zeros((5, 3)), "test")


def test_short_arc_refused_long_enough_arc_accepted():
    rng = np.random.default_rng(4)
    rot = np.eye(3)
    short = _circle_points(np.zeros(3), rot, 1800.0, 0.0, MIN_ARC_DEG - 5.0, 24, 0.02, rng)
    with pytest.raises(
        InputError, match=rf"cover only 2\d\.\d° of arc.*at least {MIN_ARC_DEG:.0f}°"
    ):
        fit_circle(short, "A1 circle")
    ok = _circle_points(np.zeros(3), rot, 1800.0, 0.0, MIN_ARC_DEG + 5.0, 24, 0.02, rng)
    assert fit_circle(ok).arc_deg == pytest.approx(MIN_ARC_DEG + 5.0, abs=0.1)


def test_line_nearly_parallel_to_plane_refused():
    normal = np.array([0.0, 0.0, 1.0])
    steep = intersect_line_plane(np.array([1.0, 2.0, 10.0]), [0.0, 0.0, -1.0], np.zeros(3), normal)
    np.testing.assert_allclose(steep, [1.0, 2.0, 0.0])
    flat = [np.cos(np.radians(5.0)), 0.0, np.sin(np.radians(5.0))]
    with pytest.raises(InputError, match=r"makes 5\.00° with the plane, at least 10°"):
        intersect_line_plane(np.zeros(3), flat, np.array([0.0, 0.0, -5.0]), normal)
