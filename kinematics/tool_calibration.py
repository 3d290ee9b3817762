"""The drill's TCP and axis measured on the calibrated arm (``accugrid identify-tool``).

An SMR seated at the tool's point (a tip adapter) is measured by the tracker, in the robot frame,
at several orientations with the joints the controller logged. At joints q_i the calibrated arm
puts its flange at robot_T_flange_i = (R_i, p_i), so the SMR is at M_i = R_i t + p_i with t the
TCP in the flange frame (mm): t is the least-squares solution over the poses' means (repeats of
a pose are averaged first, so the arm's error at a pose counts once), and its 1 sigma per axis
comes from the residuals over 3P - 3 degrees of freedom (covariance s^2 (sum R_i^T R_i)^-1 =
s^2 / P I). A second SMR point on the drill axis (rows marked ``axis``) is fitted the same way:
the drill axis runs from it to the tip (the tool's Z, pointing into the part), and the tool's
rotation is the taught one tilted by the smallest rotation onto that axis
(``frames.orient_along_axes``); its 1 sigma (deg) per transverse axis is the two points'
sigmas over their distance.

``frame_sensitivity`` is the largest singular value of the mean flange rotation: the share of a
constant offset of the robot frame (a tracker moved since the arm was calibrated) that enters t;
0 for orientations spread evenly, 1 for one orientation. ``plan_tool_poses`` chooses
orientations that make it small.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import (
    abc_to_matrix,
    orient_along_axes,
    rotation_angle_deg,
    too_tilted,
)
from accugrid.kinematics.model import RobotModel

__all__ = [
    "MIN_AXIS_MM",
    "MIN_ORIENTATIONS",
    "DISTINCT_DEG",
    "PointFit",
    "ToolFit",
    "distinct_orientations",
    "fit_point",
    "fit_tool",
    "flange_poses_of",
    "frame_sensitivity",
    "plan_tool_poses",
]

MIN_ORIENTATIONS = 6  # distinct orientations a TCP fit needs
DISTINCT_DEG = 5.0  # flange orientations closer than this to an earlier one count as one
MIN_AXIS_MM = 10.0  # the axis point at least this far from the tip (the axis' lever)
_GROUP_DEG = 1e-3  # logged joints this close are repeats of one pose


@dataclass(frozen=True)
class PointFit:
    """One SMR point in the flange frame: ``point_mm`` (3,), its 1 sigma ``sigma_mm`` (3,), the
    residual noise ``noise_mm`` per axis over ``dof`` degrees of freedom, each pose's residual
    length ``residuals_mm`` (P,) with the first row of that pose ``first_rows`` (P,), and the
    ``frame_sensitivity`` of its orientations."""

    point_mm: np.ndarray
    sigma_mm: np.ndarray
    noise_mm: float
    dof: int
    residuals_mm: np.ndarray
    first_rows: np.ndarray
    frame_sensitivity: float
    orientations: int


@dataclass(frozen=True)
class ToolFit:
    """The measured tool: ``flange_T_tool`` (4, 4) mm, the tip's fit, the axis point's fit (None
    without axis rows) and the axis' 1 sigma in deg per transverse axis (None without)."""

    flange_T_tool: np.ndarray
    tip: PointFit
    axis: PointFit | None = None
    axis_sigma_deg: float | None = None


def flange_poses_of(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """robot_T_flange (N, 4, 4) mm of the calibrated arm (its DH errors and joint errors) at
    logged joints q (N, 6) rad."""
    arm = model.with_tool(np.eye(4))
    true = arm.true_robot()
    return (true or arm).fk(q)


def frame_sensitivity(rotations: np.ndarray) -> float:
    """Largest singular value of the mean of rotations (N, 3, 3): 0 (spread) .. 1 (one)."""
    return float(np.linalg.svd(rotations.mean(axis=0), compute_uv=False)[0])


def distinct_orientations(rotations: np.ndarray) -> int:
    """How many of rotations (N, 3, 3) differ by DISTINCT_DEG or more from every earlier one."""
    kept: list[np.ndarray] = []
    for rot in rotations:  # a handful of poses
        if not kept or rotation_angle_deg(np.array(kept), rot).min() >= DISTINCT_DEG:
            kept.append(rot)
    return len(kept)


def _pose_means(q: np.ndarray, measured: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Repeats (equal logged joints) averaged: joints (P, 6), measured (P, 3), first rows (P,)."""
    key = np.round(np.degrees(q) / _GROUP_DEG)
    _, first, group = np.unique(key, axis=0, return_index=True, return_inverse=True)
    group = group.reshape(-1)
    counts = np.bincount(group)
    means = np.zeros((len(first), 3))
    np.add.at(means, group, measured)
    order = np.argsort(first)
    return q[first][order], (means / counts[:, None])[order], first[order]


def fit_point(
    model: RobotModel,
    q: np.ndarray,
    measured: np.ndarray,
    labels: list[str] | None = None,
    path: str | None = None,
    what: str = "the tool's point",
) -> PointFit:
    """An SMR point fixed on the tool in the flange frame from its measured positions (N, 3) mm
    in the robot frame at logged joints q (N, 6) rad of the calibrated ``model``. InputError
    (naming the first row) for fewer than MIN_ORIENTATIONS distinct orientations."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    joints, means, first = _pose_means(q, np.asarray(measured, dtype=float).reshape(-1, 3))
    flange = flange_poses_of(model, joints)
    rot, origin = flange[:, :3, :3], flange[:, :3, 3]
    count = distinct_orientations(rot)
    if count < MIN_ORIENTATIONS:
        where = labels[int(first[0])] if labels else "row 0"
        raise InputError(
            f"{what} is measured at {count} distinct orientations ({len(first)} poses, "
            f"{where} first): the TCP needs at least {MIN_ORIENTATIONS} orientations "
            f"{DISTINCT_DEG:g} deg apart or more (accugrid plan tool plans them)",
            path,
        )
    # M_i = R_i t + p_i  =>  t = (sum R_i^T (M_i - p_i)) / P since sum R_i^T R_i = P I
    local = np.einsum("nji,nj->ni", rot, means - origin)
    point = local.mean(axis=0)
    residuals = means - origin - np.einsum("nij,j->ni", rot, point)
    dof = 3 * len(means) - 3
    noise = float(np.sqrt(np.sum(residuals**2) / dof))
    sigma = np.full(3, noise / np.sqrt(len(means)))
    return PointFit(
        point,
        sigma,
        noise,
        dof,
        np.linalg.norm(residuals, axis=1),
        first,
        frame_sensitivity(rot),
        count,
    )


def fit_tool(
    model: RobotModel,
    q: np.ndarray,
    measured: np.ndarray,
    is_axis: np.ndarray,
    taught_rotation: np.ndarray,
    labels: list[str] | None = None,
    path: str | None = None,
) -> ToolFit:
    """The tool from rows (N,) at logged joints q (N, 6) rad measured at (N, 3) mm, ``is_axis``
    (N,) bool the rows of the axis point; without axis rows the rotation stays
    ``taught_rotation`` (3, 3). InputError for too few orientations of either point, an axis
    point within MIN_AXIS_MM of the tip, or an axis more than 90 deg off the taught tool Z."""
    is_axis = np.asarray(is_axis, dtype=bool)
    labels = labels or [f"row {i}" for i in range(len(q))]
    tip_rows = np.flatnonzero(~is_axis)
    tip = fit_point(model, q[tip_rows], measured[tip_rows], [labels[i] for i in tip_rows], path)
    tool = np.eye(4)
    tool[:3, :3], tool[:3, 3] = taught_rotation, tip.point_mm
    if not is_axis.any():
        return ToolFit(tool, _located(tip, tip_rows))
    axis_rows = np.flatnonzero(is_axis)
    axis = fit_point(
        model,
        q[axis_rows],
        measured[axis_rows],
        [labels[i] for i in axis_rows],
        path,
        "the axis point",
    )
    lever = tip.point_mm - axis.point_mm
    length = float(np.linalg.norm(lever))
    if length < MIN_AXIS_MM:
        raise InputError(
            f"the axis point lies {length:.2f} mm from the tip, {labels[axis_rows[0]]} first: "
            f"seat it on the drill axis at least {MIN_AXIS_MM:g} mm away",
            path,
        )
    direction = lever / length
    if too_tilted(direction[None], taught_rotation)[0]:
        raise InputError(
            f"the measured drill axis is far from the taught tool Z ({labels[axis_rows[0]]} "
            "first): the axis runs from the axis point to the tip; are tip and axis swapped?",
            path,
        )
    tool[:3, :3] = orient_along_axes(direction[None], taught_rotation)[0]
    transverse = np.sqrt(tip.sigma_mm[0] ** 2 + axis.sigma_mm[0] ** 2)
    return ToolFit(
        tool,
        _located(tip, tip_rows),
        _located(axis, axis_rows),
        float(np.degrees(transverse / length)),
    )


def _located(fit: PointFit, rows: np.ndarray) -> PointFit:
    """``fit`` with its first rows as rows of the whole table."""
    return replace(fit, first_rows=rows[fit.first_rows])


def plan_tool_poses(
    model: RobotModel,
    flange_T_tool: np.ndarray,
    centre_mm: np.ndarray,
    count: int = 8,
    tilt_deg: float = 30.0,
    candidates: int = 400,
    seed: int = 0,
    status: int | None = None,
    joints_deg: np.ndarray | None = None,
    abc_deg: np.ndarray = (0.0, 90.0, 0.0),
) -> tuple[np.ndarray, np.ndarray]:
    """``count`` orientations of the tool whose point stays at ``centre_mm`` (3,) in the robot
    frame: ``abc_deg`` (KUKA deg) with the drill axis tilted up to ``tilt_deg`` about random
    azimuths and turned about itself, reachable by the nominal ``model`` with ``flange_T_tool``
    (4, 4) in KUKA ``status`` (None: the IK default) with joints inside ``joints_deg`` (6, 2) (the
    arm's calibrated ranges; None: the limits), chosen greedily to make ``frame_sensitivity``
    small (the first: the least tilted). Returns the TCP poses (count, 4, 4) and their joints
    (count, 6) rad. InputError when fewer than ``count`` candidates qualify."""
    rng = np.random.default_rng(seed)
    tilt = np.radians(tilt_deg) * np.sqrt(rng.random(candidates))
    azimuth = rng.uniform(0.0, 2 * np.pi, candidates)
    spin = rng.uniform(-180.0, 180.0, candidates)
    reference = abc_to_matrix(np.asarray(abc_deg, dtype=float))
    local = np.column_stack(
        [np.sin(tilt) * np.cos(azimuth), np.sin(tilt) * np.sin(azimuth), np.cos(tilt)]
    )
    rotations = orient_along_axes(local @ reference.T, reference)
    turn = abc_to_matrix(np.column_stack([spin, np.zeros((candidates, 2))]))
    poses = np.tile(np.eye(4), (candidates, 1, 1))
    poses[:, :3, :3] = rotations @ turn  # turned about the tool's own Z
    poses[:, :3, 3] = np.asarray(centre_mm, dtype=float).reshape(3)
    sol = model.with_tool(np.asarray(flange_T_tool, dtype=float)).ik(poses, status=status)
    inside = sol.ok.copy()
    if joints_deg is not None:
        deg = np.degrees(sol.q)
        inside &= np.all((deg >= joints_deg[:, 0]) & (deg <= joints_deg[:, 1]), axis=1)
    ok = np.flatnonzero(inside)
    if len(ok) < count:
        raise InputError(
            f"only {len(ok)} of {candidates} tool orientations within {tilt_deg:g} deg of "
            f"A B C {' '.join(f'{v:g}' for v in np.ravel(abc_deg))} are reachable at "
            f"{np.round(centre_mm, 1).tolist()} mm"
            + ("" if joints_deg is None else " inside the joint ranges the arm was calibrated in")
            + ": choose another --centre, --abc or a smaller --tilt"
        )
    flange = poses[ok, :3, :3] @ np.asarray(flange_T_tool)[:3, :3].T  # R_flange = R_tcp R_tool^T
    chosen = [int(np.argmin(tilt[ok]))]
    total = flange[chosen[0]].copy()
    for _ in range(count - 1):
        sums = total + flange
        score = np.linalg.norm(sums.reshape(len(ok), -1), axis=1)  # Frobenius of the sum
        score[chosen] = np.inf
        best = int(np.argmin(score))
        chosen.append(best)
        total = sums[best]
    rows = ok[chosen]
    return poses[rows], sol.q[rows]
