"""Validation after correction: how far the robot lands from its targets, measured at new points.

A validation row is a target P (the nominal position the corrected program aimed at, robot
frame, mm) and the position M the tracker measured there after correction. The **deviation** is
d = M - P (attained minus commanded, as ISO 9283 and metrology reports state it; the opposite
sign of the correction error e = P - M of DESIGN.md). Rows with the same target (to 0.001 mm)
are repeats of one pose.

Per pose j with n_j rows x_ji (ISO 9283:1998, 7.2.1 and 7.2.2):

- positional accuracy AP_j = |x̄_j - P_j|, the distance from the barycentre of the attained
  positions to the command (mm), and its components AP_x, AP_y, AP_z;
- positional repeatability RP_j = l̄_j + 3 S_j with l_ji = |x_ji - x̄_j|, l̄_j their mean and
  S_j = sqrt(sum (l_ji - l̄_j)^2 / (n_j - 1)); defined where n_j >= 2 (ISO asks for 30 cycles).

The verdict: PASS when every row's deviation lies within +-tolerance on every axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM
from accugrid.infra.errors import InputError

__all__ = [
    "FRAME_FACTOR",
    "FRAME_FLOOR_MM",
    "ValidationResult",
    "check_same_frame",
    "validate_positions",
]

FRAME_FACTOR = 10.0  # a mean deviation this many times the model's validated error ...
FRAME_FLOOR_MM = 2.0  # ... and at least this long (mm) is another base frame or another tool
_POSE_DECIMALS = 3  # targets equal to 0.001 mm are one pose


@dataclass(frozen=True)
class ValidationResult:
    """Validation of N rows at P poses. target, measured, deviation (N, 3) mm (d = M - P);
    labels (N,) where each row is ('file:line id'); pose (N,) int the pose of each row;
    ap_xyz (P, 3) mm barycentre minus command, ap_mm (P,), rp_mm (P,) (NaN: one row),
    repeats (P,) int; tolerance_mm per axis."""

    target: np.ndarray
    measured: np.ndarray
    deviation: np.ndarray
    labels: tuple[str, ...]
    pose: np.ndarray
    ap_xyz: np.ndarray
    ap_mm: np.ndarray
    rp_mm: np.ndarray
    repeats: np.ndarray
    tolerance_mm: float

    @property
    def distance_mm(self) -> np.ndarray:
        """|d| (N,) mm per row."""
        return np.linalg.norm(self.deviation, axis=1)

    @property
    def axis_stats(self) -> dict[str, np.ndarray]:
        """min, max, max_abs, mean, std (sample, ddof 1; 0 for one row) per axis (3,) mm."""
        d = self.deviation
        return {
            "min": d.min(axis=0),
            "max": d.max(axis=0),
            "max_abs": np.abs(d).max(axis=0),
            "mean": d.mean(axis=0),
            "std": d.std(axis=0, ddof=1) if len(d) > 1 else np.zeros(3),
        }

    @property
    def distance_stats(self) -> dict[str, float]:
        """max, mean, std (ddof 1) of |d|, mm."""
        n = self.distance_mm
        return {
            "max": float(n.max()),
            "mean": float(n.mean()),
            "std": float(n.std(ddof=1)) if len(n) > 1 else 0.0,
        }

    @property
    def outside(self) -> np.ndarray:
        """(N,) bool: a row with an axis deviation beyond +-tolerance."""
        return (np.abs(self.deviation) > self.tolerance_mm).any(axis=1)

    @property
    def passed(self) -> bool:
        """Every row within +-tolerance on every axis."""
        return not bool(self.outside.any())

    def worst(self, count: int = 10) -> np.ndarray:
        """Indices of the ``count`` rows with the largest axis deviation |d_x|, |d_y|, |d_z|,
        largest first."""
        key = np.abs(self.deviation).max(axis=1)
        return np.argsort(-key, kind="stable")[:count]


def validate_positions(
    target: np.ndarray,
    measured: np.ndarray,
    labels: list[str] | tuple[str, ...],
    tolerance_mm: float = DEFAULT_TOLERANCE_MM,
) -> ValidationResult:
    """Deviations, ISO 9283 AP and RP per pose, verdict; target, measured (N, 3) mm robot frame,
    ``labels`` (N,) where each row is."""
    target = np.asarray(target, dtype=float).reshape(-1, 3)
    measured = np.asarray(measured, dtype=float).reshape(-1, 3)
    if len(target) == 0 or len(target) != len(measured) or len(labels) != len(target):
        raise ValueError("target, measured and labels must be non-empty and of one length")
    _, first, pose = np.unique(
        np.round(target, _POSE_DECIMALS), axis=0, return_index=True, return_inverse=True
    )
    pose = pose.reshape(-1)
    order = np.argsort(first)  # poses numbered in the order of their first row
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    pose = rank[pose]
    count = len(order)
    repeats = np.bincount(pose, minlength=count)
    command = target[first[order]]
    barycentre = np.zeros((count, 3))
    np.add.at(barycentre, pose, measured)
    barycentre /= repeats[:, None]
    ap_xyz = barycentre - command
    spread = np.linalg.norm(measured - barycentre[pose], axis=1)
    l_mean = np.bincount(pose, spread, minlength=count) / repeats
    squares = np.bincount(pose, (spread - l_mean[pose]) ** 2, minlength=count)
    with np.errstate(invalid="ignore", divide="ignore"):
        s_l = np.sqrt(squares / (repeats - 1))
    rp = np.where(repeats >= 2, l_mean + 3.0 * s_l, np.nan)
    return ValidationResult(
        target=target,
        measured=measured,
        deviation=measured - target,
        labels=tuple(labels),
        pose=pose,
        ap_xyz=ap_xyz,
        ap_mm=np.linalg.norm(ap_xyz, axis=1),
        rp_mm=rp,
        repeats=repeats,
        tolerance_mm=float(tolerance_mm),
    )


def check_same_frame(
    result: ValidationResult, validated_max_mm: np.ndarray | None, path: str | None
) -> None:
    """InputError when the mean deviation (3,) is longer than FRAME_FACTOR times the model's
    validated error (per axis (3,) mm; None: not recorded) and than FRAME_FLOOR_MM: the file was
    measured in another base frame or with another tool than the model's."""
    mean = result.deviation.mean(axis=0)
    validated = 0.0 if validated_max_mm is None else float(np.linalg.norm(validated_max_mm))
    limit = max(FRAME_FACTOR * validated, FRAME_FLOOR_MM)
    if np.linalg.norm(mean) > limit:
        shown = " ".join(f"{v:+.3f}" for v in mean)
        raise InputError(
            f"mean deviation (measured - target) {shown} mm is {np.linalg.norm(mean):.3f} mm "
            f"long, more than {limit:.3f} mm ({FRAME_FACTOR:g} x the model's validated error "
            f"{validated:.3f} mm, at least {FRAME_FLOOR_MM:g}): measured in another base frame "
            "or with another tool than the model? map the tracker points into the robot frame "
            "(accugrid transform) and measure with the tool the program was corrected for",
            path,
        )
