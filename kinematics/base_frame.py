"""The robot base frame from laser-tracker points (seed Sec. 4.1).

1. Base plane: an SMR scanned over the robot's mounting surface; the fitted plane through the SMR
   centres, moved by the SMR radius toward the surface, is the base plane.
2. A1 circle: an SMR on the flange while only A1 turns traces a circle about the A1 axis; its
   normal is Z, oriented up (away from the mounting surface, toward the robot). The origin is
   where that axis meets the base plane.
3. Flange holes at mechanical zero (A1..A6 = 0, -90, 90, 0, 0, 0): the centre of the circle
   through the SMR seated on the flange holes lies on the robot's ZX plane, on the +X side.
   (The SMR seat lifts every point by the same amount along the flange axis, which at mechanical
   zero is horizontal and in the ZX plane, so the centre stays in that plane.)
4. X is the direction from the origin to that centre, made perpendicular to Z; Y = Z × X.

Input points are (N, 3) mm in the tracker frame; the result is ``tracker_T_robot`` (4, 4).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from accugrid.infra.errors import InputError
from accugrid.kinematics.fitting import (
    CircleFit,
    PlaneFit,
    fit_circle,
    fit_plane,
    intersect_line_plane,
)

__all__ = [
    "MAX_AXIS_TILT_DEG",
    "MIN_ARM_MM",
    "MIN_HEIGHT_MM",
    "PLANE_STRAY_MM",
    "SMR_RADIUS_MM",
    "RobotFrameFit",
    "fit_robot_frame",
]

SMR_RADIUS_MM = 19.05
"""Default SMR radius: a 1.5-inch (38.1 mm) spherically mounted reflector."""

MAX_AXIS_TILT_DEG = 2.0
"""Largest angle accepted between the A1 axis and the base-plane normal. A robot standing on its
mounting surface has A1 perpendicular to it within a small fraction of a degree; more means the
files are not the surface and an A1-only rotation of the same robot."""

MIN_HEIGHT_MM = 100.0
"""The A1 circle must lie at least this far from the base plane, or 'up' is not defined."""

MIN_ARM_MM = 100.0
"""The flange-hole centre must lie at least this far from the A1 axis, or X is not defined."""

PLANE_STRAY_MM = 1.0
"""A base-plane point this far from the fitted plane is a stray (a scanned surface is flat to a
few 0.01 mm): when the A1 checks fail, the base-plane file is blamed for it, not the A1 file."""


@dataclass(frozen=True)
class RobotFrameFit:
    """The fitted robot frame and the fits it came from.

    ``tracker_T_robot`` (4, 4) mm; ``plane`` is the fit through the SMR centres (normal oriented
    up), ``base_offset_mm`` the SMR radius it was moved down by; ``axis_tilt_deg`` the angle
    between the A1 axis and the base-plane normal; ``flange_axis_deg`` the angle between the
    flange-hole circle's normal and robot X (about 0 at mechanical zero).
    """

    tracker_T_robot: np.ndarray
    plane: PlaneFit
    base_offset_mm: float
    a1_circle: CircleFit
    flange_holes: CircleFit
    axis_tilt_deg: float
    flange_axis_deg: float


def _located(fit, points: np.ndarray, what: str, source: str | None):
    """Run a fit; an InputError it raises names ``source`` (the file) when given."""
    try:
        return fit(points, what)
    except InputError as err:
        raise InputError(err.message, source) from None


def _refuse_stray_plane_point(plane: PlaneFit, points: np.ndarray, source: str | None) -> None:
    """InputError naming the base-plane file when one of its points (N, 3) mm lies more than
    ``PLANE_STRAY_MM`` off the plane: the A1 checks that follow would blame the A1 file."""
    if plane.max_mm > PLANE_STRAY_MM:
        worst = int(np.argmax(np.abs(plane.distances(points))))
        raise InputError(
            f"base plane: point {worst + 1} lies {plane.max_mm:.3f} mm off the plane fitted "
            f"through the others' (rms {plane.rms_mm:.3f} mm; at most {PLANE_STRAY_MM:g} mm): "
            "a stray point?",
            source,
        )


def fit_robot_frame(
    base_plane: np.ndarray,
    a1_circle: np.ndarray,
    flange_holes: np.ndarray,
    smr_radius_mm: float = SMR_RADIUS_MM,
    sources: tuple[str | None, str | None, str | None] = (None, None, None),
) -> RobotFrameFit:
    """Fit tracker_T_robot from the three point sets (each (N, 3) mm, tracker frame).

    ``sources`` names the file of each set for error messages. InputError on degenerate or
    inconsistent input (see the module constants).
    """
    src_plane, src_a1, src_holes = sources
    if not (np.isfinite(smr_radius_mm) and smr_radius_mm >= 0.0):
        raise InputError(f"SMR radius must be a finite number >= 0 mm, got {smr_radius_mm}")
    plane = _located(fit_plane, base_plane, "base plane", src_plane)
    a1 = _located(fit_circle, a1_circle, "A1 circle", src_a1)
    holes = _located(fit_circle, flange_holes, "flange-hole circle", src_holes)

    height = float(plane.distances(a1.center[None])[0])
    if abs(height) < MIN_HEIGHT_MM:
        _refuse_stray_plane_point(plane, base_plane, src_plane)
        raise InputError(
            f"the A1 circle's centre is only {abs(height):.1f} mm from the base plane (at least "
            f"{MIN_HEIGHT_MM:g} mm needed to tell up from down): are these the flange points?",
            src_a1,
        )
    up = plane.normal * np.sign(height)
    plane = PlaneFit(plane.point, up, plane.rms_mm, plane.max_mm, plane.n_points)
    z_axis = a1.normal * np.sign(a1.normal @ up)
    tilt = float(np.degrees(np.arccos(np.clip(z_axis @ up, -1.0, 1.0))))
    if tilt > MAX_AXIS_TILT_DEG:
        _refuse_stray_plane_point(plane, base_plane, src_plane)
        raise InputError(
            f"the A1 axis is tilted {tilt:.2f}° from the base-plane normal (at most "
            f"{MAX_AXIS_TILT_DEG:g}° is accepted): are these points of the same robot, the base "
            "plane scanned on its mounting surface and the arc traced by A1 alone?",
            src_a1,
        )
    origin = intersect_line_plane(a1.center, z_axis, plane.point - smr_radius_mm * up, up)

    arm = holes.center - origin
    arm -= (arm @ z_axis) * z_axis
    reach = float(np.linalg.norm(arm))
    if reach < MIN_ARM_MM:
        raise InputError(
            f"the flange-hole circle's centre is only {reach:.1f} mm from the A1 axis (at least "
            f"{MIN_ARM_MM:g} mm needed to define X): is the robot at mechanical zero?",
            src_holes,
        )
    x_axis = arm / reach
    y_axis = np.cross(z_axis, x_axis)
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([x_axis, y_axis, z_axis])
    pose[:3, 3] = origin
    flange_axis = float(np.degrees(np.arccos(min(abs(holes.normal @ x_axis), 1.0))))
    return RobotFrameFit(pose, plane, float(smr_radius_mm), a1, holes, tilt, flange_axis)
