"""Least-squares plane and 3D circle fits for laser-tracker points, with their residuals.

Points are (N, 3) float64 mm. Every fit returns its residuals (RMS and max distance, mm) and
refuses input it cannot fit with an InputError: fewer than 3 points, (nearly) collinear points,
and for circles an arc shorter than ``MIN_ARC_DEG``. ``intersect_line_plane`` refuses a line
nearly parallel to the plane.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from accugrid.infra.errors import InputError

__all__ = [
    "COLLINEAR_RATIO",
    "MIN_ARC_DEG",
    "CircleFit",
    "PlaneFit",
    "fit_circle",
    "fit_plane",
    "intersect_line_plane",
]

MIN_ARC_DEG = 30.0
"""Shortest arc a circle fit accepts. The centre and normal errors of a circle fit grow roughly
as 1/arc²: for the A1 circle of a KR 210 (radius 1.8 m, 24 points, 0.02 mm tracker noise) the
robot origin is off by about 0.5 mm RMS (1.5 mm worst) at 30° of arc and 0.06 mm at 90°
(bench/frame_fit_noise.py); below 30° the frame is worse than the grid it is meant to carry
and the fit is refused. Operators should measure 90° or more."""

COLLINEAR_RATIO = 1e-3
"""Points whose RMS distance from their best line is below this fraction of their extent
(0.1 %, e.g. 1 mm over 1 m) are collinear: no plane and no circle passes through them in any
useful way. (A 30° arc is 2 % of its chord away from it, so short arcs reach the arc check.)"""


@dataclass(frozen=True)
class PlaneFit:
    """A fitted plane: ``point`` (3,) mm on it (the centroid), unit ``normal`` (3,), and the
    residuals (point-to-plane distances, mm)."""

    point: np.ndarray
    normal: np.ndarray
    rms_mm: float
    max_mm: float
    n_points: int

    def distances(self, points: np.ndarray) -> np.ndarray:
        """Signed distances (N,) mm of points (N, 3) from the plane, positive along ``normal``."""
        return (np.asarray(points, dtype=float) - self.point) @ self.normal


@dataclass(frozen=True)
class CircleFit:
    """A fitted 3D circle: ``center`` (3,) mm, unit ``normal`` (3,), ``radius_mm``, the arc its
    points cover (deg, 360 minus the largest angular gap) and the point-to-circle residuals (mm)."""

    center: np.ndarray
    normal: np.ndarray
    radius_mm: float
    arc_deg: float
    rms_mm: float
    max_mm: float
    n_points: int

    def distances(self, points: np.ndarray) -> np.ndarray:
        """Distances (N,) mm of points (N, 3) from the circle (not its disc)."""
        axial, radial = _circle_components(points, self.center, self.normal, self.radius_mm)
        return np.hypot(axial, radial)


def _as_points(points: np.ndarray, what: str) -> np.ndarray:
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise InputError(f"{what}: expected (N, 3) points, got shape {pts.shape}")
    if len(pts) < 3:
        raise InputError(f"{what}: {len(pts)} point(s), at least 3 are needed")
    if not np.all(np.isfinite(pts)):
        raise InputError(f"{what}: points must be finite numbers")
    return pts


def _principal_axes(pts: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centroid (3,), singular values (3,) and right singular vectors (3, 3) of the points;
    InputError when they are collinear."""
    centroid = pts.mean(axis=0)
    _, sing, vt = np.linalg.svd(pts - centroid, full_matrices=False)
    extent = float(np.ptp(pts @ vt[0]))
    off_line = float(np.hypot(sing[1], sing[2]) / np.sqrt(len(pts)))
    if extent == 0.0 or off_line <= COLLINEAR_RATIO * extent:
        raise InputError(
            f"{what}: the {len(pts)} points are collinear (or all the same point); "
            "a plane or a circle needs points spread in two directions"
        )
    return centroid, sing, vt


def fit_plane(points: np.ndarray, what: str = "plane fit") -> PlaneFit:
    """Total-least-squares plane through points (N, 3) mm, by SVD; ``what`` names the data in
    error messages. The normal's sign is arbitrary (callers orient it)."""
    pts = _as_points(points, what)
    centroid, _, vt = _principal_axes(pts, what)
    normal = vt[2] / np.linalg.norm(vt[2])
    dist = np.abs((pts - centroid) @ normal)
    return PlaneFit(
        centroid,
        normal,
        float(np.sqrt(np.mean(dist**2))),
        float(dist.max()),
        len(pts),
    )


def _circle_components(
    points: np.ndarray, center: np.ndarray, normal: np.ndarray, radius: float
) -> tuple[np.ndarray, np.ndarray]:
    """Axial offset (N,) and radial offset (N,) of points from a circle, mm."""
    d = np.asarray(points, dtype=float) - center
    axial = d @ normal
    radial = np.linalg.norm(d - np.outer(axial, normal), axis=1) - radius
    return axial, radial


def _algebraic_circle(uv: np.ndarray) -> tuple[np.ndarray, float]:
    """Kasa fit of a circle to 2D points (N, 2): u²+v² + D u + E v + F = 0 in least squares."""
    design = np.column_stack([uv, np.ones(len(uv))])
    rhs = -(uv**2).sum(axis=1)
    (d, e, f), *_ = np.linalg.lstsq(design, rhs, rcond=None)
    center = np.array([-d / 2.0, -e / 2.0])
    r2 = center @ center - f
    return center, float(np.sqrt(max(r2, 0.0)))


def _arc_deg(points: np.ndarray, center: np.ndarray, normal: np.ndarray) -> float:
    """Angular span (deg) covered by the points around the circle: 360 minus the largest gap."""
    e1 = np.cross(normal, [1.0, 0.0, 0.0])
    if np.linalg.norm(e1) < 0.5:
        e1 = np.cross(normal, [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(normal, e1)
    d = points - center
    ang = np.sort(np.arctan2(d @ e2, d @ e1))
    gaps = np.diff(np.concatenate([ang, ang[:1] + 2.0 * np.pi]))
    return float(np.degrees(2.0 * np.pi - gaps.max()))


def fit_circle(points: np.ndarray, what: str = "circle fit") -> CircleFit:
    """Geometric least-squares circle in 3D through points (N, 3) mm.

    Start: SVD plane, then the algebraic (Kasa) circle in that plane. Refinement: minimise the
    sum of squared point-to-circle distances over centre, normal and radius with
    ``scipy.optimize.least_squares``. InputError for fewer than 3 points, collinear points, or an
    arc under ``MIN_ARC_DEG``. The normal's sign is arbitrary (callers orient it).
    """
    # Imported here: scipy.optimize costs ~0.5 s, and every accugrid command imports this module.
    from scipy.optimize import least_squares

    pts = _as_points(points, what)
    centroid, _, vt = _principal_axes(pts, what)
    e1, e2, n0 = vt[0], vt[1], vt[2]
    uv = np.column_stack([(pts - centroid) @ e1, (pts - centroid) @ e2])
    c2, r0 = _algebraic_circle(uv)
    c0 = centroid + c2[0] * e1 + c2[1] * e2
    if r0 == 0.0 or not np.isfinite(r0):
        raise InputError(f"{what}: no circle fits these points")
    scale = r0

    def unpack(p: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        normal = n0 + p[3] * e1 + p[4] * e2
        return c0 + p[:3] * scale, normal / np.linalg.norm(normal), r0 + p[5] * scale

    def residuals(p: np.ndarray) -> np.ndarray:
        center, normal, radius = unpack(p)
        axial, radial = _circle_components(pts, center, normal, radius)
        return np.concatenate([axial, radial]) / scale

    sol = least_squares(residuals, np.zeros(6), method="lm", xtol=1e-14, ftol=1e-14, gtol=1e-14)
    center, normal, radius = unpack(sol.x)
    if not (np.all(np.isfinite(center)) and np.isfinite(radius) and radius > 0.0):
        raise InputError(f"{what}: the circle fit did not converge")
    arc = _arc_deg(pts, center, normal)
    if arc < MIN_ARC_DEG:
        raise InputError(
            f"{what}: the {len(pts)} points cover only {arc:.1f}° of arc (radius "
            f"{radius:.1f} mm); at least {MIN_ARC_DEG:.0f}° is needed for a usable circle fit"
        )
    dist = np.hypot(*_circle_components(pts, center, normal, radius))
    return CircleFit(
        center,
        normal,
        float(radius),
        arc,
        float(np.sqrt(np.mean(dist**2))),
        float(dist.max()),
        len(pts),
    )


def intersect_line_plane(
    point: np.ndarray,
    direction: np.ndarray,
    plane_point: np.ndarray,
    plane_normal: np.ndarray,
    min_angle_deg: float = 10.0,
    what: str = "line-plane intersection",
) -> np.ndarray:
    """Point (3,) mm where the line ``point + t·direction`` meets the plane.

    InputError when the line is within ``min_angle_deg`` of being parallel to the plane (the
    intersection is then ill-conditioned or absent).
    """
    direction = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    plane_normal = np.asarray(plane_normal, dtype=float) / np.linalg.norm(plane_normal)
    cos = float(direction @ plane_normal)
    angle = float(np.degrees(np.arcsin(min(abs(cos), 1.0))))
    if angle < min_angle_deg:
        raise InputError(
            f"{what}: the line makes {angle:.2f}° with the plane, "
            f"at least {min_angle_deg:g}° is needed"
        )
    t = float((np.asarray(plane_point, dtype=float) - point) @ plane_normal) / cos
    return np.asarray(point, dtype=float) + t * direction
