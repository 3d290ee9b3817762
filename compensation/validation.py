"""Validation after correction: how far the robot lands from its targets, measured at new points.

A validation row is a target P (the nominal position the corrected program aimed at, robot
frame, mm) and the position M the tracker measured there after correction. The **deviation** is
d = M - P (attained minus commanded, as ISO 9283 and metrology reports state it; the opposite
sign of the correction error e = P - M, docs/layout.md). Rows with the same target (to 0.001 mm)
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

__all__ = [
    "FRAME_FACTOR",
    "FRAME_FLOOR_MM",
    "MeanOffset",
    "ValidationResult",
    "mean_offset",
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


@dataclass(frozen=True)
class MeanOffset:
    """What the mean deviation of a validation says about the frame and the tool.

    ``mean_mm`` (3,) the mean deviation d (robot frame); ``limit_mm`` the length beyond which it
    is another base frame or tool (FRAME_FACTOR x the model's validated error, at least
    FRAME_FLOOR_MM); ``rms_mm`` the RMS of |d|, ``shift_rms_mm`` of what the mean offset leaves
    of it, ``rigid_rms_mm`` of what the best rotation with a shift leaves and ``rotation_deg``
    that rotation's angle; ``tool_mm`` (3,) the mean deviation in the tool frame (None: the
    file has no a,b,c)."""

    mean_mm: np.ndarray
    limit_mm: float
    rms_mm: float
    shift_rms_mm: float
    rigid_rms_mm: float
    rotation_deg: float
    tool_mm: np.ndarray | None

    @property
    def other_frame(self) -> bool:
        """The mean deviation is too long for the model's frame and tool."""
        return float(np.linalg.norm(self.mean_mm)) > self.limit_mm

    def words(self) -> str:
        """What the offset suggests, one sentence (robot frame, mm, deg)."""
        length = float(np.linalg.norm(self.mean_mm))
        shown = " ".join(f"{v:+.3f}" for v in self.mean_mm)
        text = (
            f"mean deviation (measured - target) {shown} mm, {length:.3f} mm long"
            f" (limit {self.limit_mm:.3f} mm)"
        )
        if not self.other_frame:
            return text + ": no sign of another base frame or tool"
        if self.rigid_rms_mm <= ROTATION_GAIN * self.shift_rms_mm:
            return text + (
                f"; a rotation of {self.rotation_deg:.3f} deg with a shift leaves "
                f"{self.rigid_rms_mm:.3f} mm RMS where the offset alone leaves "
                f"{self.shift_rms_mm:.3f} mm: the tracker points are in a base frame turned "
                "against the model's (map them into the robot frame: accugrid fit-frame, "
                "accugrid transform)"
            )
        if self.shift_rms_mm <= SHIFT_LEAVES * self.rms_mm:
            text += (
                f"; the offset leaves {self.shift_rms_mm:.3f} mm RMS of {self.rms_mm:.3f}: the "
                "base frame's origin or the tool (TCP) differs from the model's by about it"
            )
            if self.tool_mm is None:
                return text + " (a file without a,b,c cannot tell the two apart)"
            tool = " ".join(f"{v:+.3f}" for v in self.tool_mm)
            along = abs(self.tool_mm[2]) >= (1.0 - SHIFT_LEAVES) * float(
                np.linalg.norm(self.tool_mm)
            )
            return text + (
                f"; in the tool frame {tool} mm"
                + (", along the tool axis: a tool length" if along else "")
                + " (measure with the tool the program was corrected for)"
            )
        return text + (
            f"; neither the offset ({self.shift_rms_mm:.3f} mm RMS left of {self.rms_mm:.3f}) nor "
            f"a rotation with a shift ({self.rigid_rms_mm:.3f} mm left) explains the deviation: "
            "the robot does not move as the model says (another robot, a changed robot, or "
            "another model)"
        )


ROTATION_GAIN = 0.5  # a rotation that leaves at most this share of the offset's rest is told
SHIFT_LEAVES = 0.3  # an offset that leaves at most this share of the RMS: a frame origin or tool


def mean_offset(
    result: ValidationResult, validated_max_mm: np.ndarray | None, abc_deg: np.ndarray | None
) -> MeanOffset:
    """The mean offset of ``result`` against the model's validated error per axis (3,) mm
    (None: not recorded); ``abc_deg`` (N, 3) KUKA A, B, C of the rows (None: not in the file)."""
    from accugrid.kinematics.frames import abc_to_matrix
    from accugrid.kinematics.identification import rigid_fit

    d = result.deviation
    mean = d.mean(axis=0)
    validated = 0.0 if validated_max_mm is None else float(np.linalg.norm(validated_max_mm))
    shift_rms = _rms(d - mean)
    rigid_rms, angle = shift_rms, 0.0
    spread = np.linalg.svd(result.target - result.target.mean(axis=0), compute_uv=False)
    if len(d) >= 3 and spread[1] > 1e-3 * spread[0]:  # a rotation needs a spread in 2 directions
        measured_T_target = rigid_fit(result.target, result.measured)
        rest = result.measured - result.target @ measured_T_target[:3, :3].T
        rigid_rms = min(_rms(rest - measured_T_target[:3, 3]), shift_rms)
        cos = (np.trace(measured_T_target[:3, :3]) - 1.0) / 2.0
        angle = float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
    tool = None
    if abc_deg is not None:  # d_i = R_i u for one tool offset u: u = mean of R_i^T d_i
        tool = np.einsum("nji,nj->ni", abc_to_matrix(abc_deg), d).mean(axis=0)
    return MeanOffset(
        mean_mm=mean,
        limit_mm=max(FRAME_FACTOR * validated, FRAME_FLOOR_MM),
        rms_mm=_rms(d),
        shift_rms_mm=shift_rms,
        rigid_rms_mm=rigid_rms,
        rotation_deg=angle,
        tool_mm=tool,
    )


def _rms(vectors: np.ndarray) -> float:
    """RMS of the lengths of vectors (N, 3)."""
    return float(np.sqrt((vectors**2).sum(axis=1).mean()))
