"""Synthetic laser-tracker points for the base-frame procedure (seed Sec. 4.1), from a known frame.

The geometry, in the robot frame (mm), follows a KR 210 at mechanical zero
(A1..A6 = 0, -90, 90, 0, 0, 0), where the flange centre is at (1765, 0, 1784) and the flange
face points along +X:

- Flange: ISO 9409-1-160 pattern assumed, 6 holes of 10 mm on a 160 mm pitch circle, 60° apart.
  An SMR of radius r resting on a hole of diameter d has its centre sqrt(r² - (d/2)²) in front
  of the flange face (18.38 mm for the 38.1 mm SMR).
- Base plane: SMR centres r above the mounting surface z = 0, in a ring 600-900 mm around A1;
  the surface may be tilted slightly about a horizontal line through the origin.
- A1 circle: the SMR in flange hole 0 while A1 turns over an arc centred on A1 = 0.

Noise is Gaussian with the given standard deviation on each tracker coordinate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from accugrid.kinematics.frames import transform_points

__all__ = [
    "FLANGE_CENTER_MM",
    "HOLE_CIRCLE_DIAMETER_MM",
    "HOLE_DIAMETER_MM",
    "N_HOLES",
    "TrackerPoints",
    "flange_hole_points",
    "simulate_tracker_points",
    "smr_seat_height",
]

FLANGE_CENTER_MM = np.array([1765.0, 0.0, 1784.0])
HOLE_CIRCLE_DIAMETER_MM = 160.0
HOLE_DIAMETER_MM = 10.0
N_HOLES = 6


@dataclass(frozen=True)
class TrackerPoints:
    """The three measured point sets (each (N, 3) mm, tracker frame)."""

    base_plane: np.ndarray
    a1_circle: np.ndarray
    flange_holes: np.ndarray


def smr_seat_height(smr_radius_mm: float, hole_diameter_mm: float = HOLE_DIAMETER_MM) -> float:
    """Distance (mm) from a flat face to the centre of a ball resting on a round hole in it."""
    return float(np.sqrt(smr_radius_mm**2 - (hole_diameter_mm / 2.0) ** 2))


def flange_hole_points(smr_radius_mm: float) -> np.ndarray:
    """SMR centres (6, 3) mm, robot frame, on the flange holes at mechanical zero."""
    phi = np.radians(np.arange(N_HOLES) * 360.0 / N_HOLES)
    radius = HOLE_CIRCLE_DIAMETER_MM / 2.0
    pts = np.tile(FLANGE_CENTER_MM, (N_HOLES, 1))
    pts[:, 0] += smr_seat_height(smr_radius_mm)
    pts[:, 1] += radius * np.cos(phi)
    pts[:, 2] += radius * np.sin(phi)
    return pts


def simulate_tracker_points(
    tracker_T_robot: np.ndarray,
    noise_mm: float,
    seed: int = 0,
    smr_radius_mm: float = 19.05,
    n_plane: int = 40,
    n_arc: int = 24,
    arc_deg: float = 120.0,
    surface_tilt_deg: float = 0.0,
) -> TrackerPoints:
    """Points an operator would measure on a robot at ``tracker_T_robot`` (4, 4) mm."""
    rng = np.random.default_rng(seed)
    ang = rng.uniform(0.0, 2.0 * np.pi, n_plane)
    rad = rng.uniform(600.0, 900.0, n_plane)
    xy = np.column_stack([rad * np.cos(ang), rad * np.sin(ang)])
    tilt_dir = rng.uniform(0.0, 2.0 * np.pi)
    slope = np.tan(np.radians(surface_tilt_deg))
    normal = np.array([-slope * np.cos(tilt_dir), -slope * np.sin(tilt_dir), 1.0])
    normal /= np.linalg.norm(normal)
    surface = np.column_stack([xy, slope * (xy @ [np.cos(tilt_dir), np.sin(tilt_dir)])])
    plane = surface + smr_radius_mm * normal

    holes = flange_hole_points(smr_radius_mm)
    theta = np.radians(np.linspace(-arc_deg / 2.0, arc_deg / 2.0, n_arc))
    cos, sin = np.cos(theta), np.sin(theta)
    p0 = holes[0]
    arc = np.column_stack(
        [cos * p0[0] - sin * p0[1], sin * p0[0] + cos * p0[1], np.full(n_arc, p0[2])]
    )

    def measure(pts: np.ndarray) -> np.ndarray:
        return transform_points(tracker_T_robot, pts) + rng.normal(0.0, noise_mm, pts.shape)

    return TrackerPoints(measure(plane), measure(arc), measure(holes))
