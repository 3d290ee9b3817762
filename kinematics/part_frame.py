"""The part frame from datums: ``robot_T_base`` by least squares from datum features (tooling
balls, reference holes) measured in the robot frame and their CAD coordinates in the part frame.

The model of datum i (CAD point ``p_i`` in the part frame, measured ``m_i`` in the robot frame,
both mm): ``m_i = R (s p_i) + t + noise``, with ``s`` 1 (rigid), a given scale (a part at another
temperature) or fitted. The rotation is independent of the scale (Umeyama); the fitted scale is
the least-squares one given the rotation.

The frame's uncertainty: the per-axis noise sigma is estimated from the residuals with
``3 N - k`` degrees of freedom (k = 6, 7 with a fitted scale); the covariance of the frame's
parameters about the datums' centroid (translation mm, rotation rad, scale) follows from the
Jacobian. At any point of the part the error is Gaussian with covariance ``J C J^T``; its 95 %
bound on the length uses the Satterthwaite approximation of the norm (|e|^2 ~ g chi^2_h) and,
since sigma is estimated, the F distribution (|e|^2 / (g h) ~ F(h, dof)).

A moved datum: the fit without datum i predicts it; when that prediction misses it by more than
``MOVED_RATIO`` times the miss the others' residuals lead to expect there (their noise and their
frame's uncertainty at datum i) and by more than ``MOVED_MIN_MM``, datum i is named as moved
(4 datums or more; with 3 no datum can be told from the others).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from accugrid.infra.bounds import length_bound_95
from accugrid.infra.errors import InputError
from accugrid.kinematics.identification import rigid_fit
from accugrid.kinematics.model import RobotModel

__all__ = [
    "COLLINEAR_RATIO",
    "MIN_DATUMS",
    "MOVED_MIN_MM",
    "MOVED_RATIO",
    "REFERENCE_TEMPERATURE_C",
    "PartFit",
    "fit_part_frame",
    "frame_jacobian",
    "reach_mm",
    "thermal_scale",
]

MIN_DATUMS = 3
COLLINEAR_RATIO = 0.05
"""Datums whose RMS spread across their best line is below this share of the spread along it lie
on one line: the rotation about that line is not defined."""
MOVED_RATIO = 10.0
MOVED_MIN_MM = 0.1
"""A datum is called moved when its prediction by the others misses it by ``MOVED_RATIO`` times
the expected miss and by at least this much (a tracker's noise is a few 0.01 mm)."""
REFERENCE_TEMPERATURE_C = 20.0  # ISO 1: CAD dimensions hold at 20 degC


def frame_jacobian(points: np.ndarray, centroid: np.ndarray) -> np.ndarray:
    """(N, 3, 6) derivative of robot-frame points (N, 3) mm carried by a frame by its
    translation at ``centroid`` (3,) mm and its small rotation (rad)."""
    lever = np.asarray(points, dtype=float).reshape(-1, 3) - centroid
    jac = np.zeros((len(lever), 3, 6))
    jac[:, :, :3] = np.eye(3)
    jac[:, 0, 4], jac[:, 0, 5] = lever[:, 2], -lever[:, 1]  # -[lever]x : d(w x lever)/dw
    jac[:, 1, 3], jac[:, 1, 5] = -lever[:, 2], lever[:, 0]
    jac[:, 2, 3], jac[:, 2, 4] = lever[:, 1], -lever[:, 0]
    return jac


def thermal_scale(cte_per_k: float, temperature_c: float) -> float:
    """The isotropic scale of a part at ``temperature_c`` (degC) with expansion coefficient
    ``cte_per_k`` (1/K) against its CAD dimensions at 20 degC."""
    return 1.0 + cte_per_k * (temperature_c - REFERENCE_TEMPERATURE_C)


@dataclass(frozen=True)
class PartFit:
    """A fitted part frame.

    ``robot_T_base`` (4, 4) mm, rigid; ``scale`` the part's isotropic scale (1: rigid);
    ``fitted`` (N, 3) mm: the datums' CAD points mapped into the robot frame; ``residuals_mm``
    (N,) the length of measured minus fitted; ``loo_mm`` (N,) how far the fit without each datum
    misses it and ``loo_ratio`` (N,) that over the miss the others' residuals lead to expect
    (NaN with 3 datums);
    ``sigma_mm`` the per-axis noise estimated from the residuals with ``dof`` degrees of freedom;
    ``centroid`` (3,) mm the datums' mean in the robot frame and ``nominal_centroid`` (3,) their
    CAD mean; ``covariance`` (k, k) of (translation at the centroid mm, rotation rad[, scale]).
    """

    robot_T_base: np.ndarray
    scale: float
    scale_fitted: bool
    fitted: np.ndarray
    residuals_mm: np.ndarray
    loo_mm: np.ndarray
    loo_ratio: np.ndarray
    sigma_mm: float
    dof: int
    centroid: np.ndarray
    nominal_centroid: np.ndarray
    covariance: np.ndarray

    def _jacobian(self, nominal: np.ndarray) -> np.ndarray:
        """(N, 3, k) derivative of the robot-frame position of CAD points (N, 3) mm by the
        parameters."""
        x = self.robot_T_base[:3, :3] @ (self.scale * nominal.T) + self.robot_T_base[:3, 3:]
        jac = frame_jacobian(x.T, self.centroid)
        if self.scale_fitted:
            scale = (nominal - self.nominal_centroid) @ self.robot_T_base[:3, :3].T
            jac = np.concatenate([jac, scale[:, :, None]], axis=2)
        return jac

    def sigma_at(self, nominal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The frame's uncertainty at CAD points (N, 3) mm of the part: per-axis 1 sigma (N, 3)
        mm in the robot frame and the 95 % bound on the error's length ``u95_mm`` (N,)."""
        jac = self._jacobian(np.asarray(nominal, dtype=float).reshape(-1, 3))
        cov = jac @ self.covariance @ jac.transpose(0, 2, 1)
        per_axis = np.sqrt(np.clip(np.diagonal(cov, axis1=1, axis2=2), 0.0, None))
        return per_axis, length_bound_95(cov, self.dof)

    @property
    def moved(self) -> int | None:
        """The index of the datum the others call moved, None when there is none."""
        ratio = np.nan_to_num(self.loo_ratio, nan=0.0)
        worst = int(np.argmax(ratio)) if len(ratio) else 0
        if ratio.size and ratio[worst] >= MOVED_RATIO and self.loo_mm[worst] >= MOVED_MIN_MM:
            return worst
        return None


def _similarity(
    nominal: np.ndarray, measured: np.ndarray, scale: float | None
) -> tuple[np.ndarray, float]:
    """robot_T_base (4, 4) and scale: ``measured`` ~ R (s nominal) + t, (N, 3) mm; ``scale``
    None fits it."""
    pose = rigid_fit(nominal, measured)  # the rotation does not depend on the scale
    if scale is None:
        a = nominal - nominal.mean(axis=0)
        b = measured - measured.mean(axis=0)
        scale = float(np.sum(b * (a @ pose[:3, :3].T)) / np.sum(a * a))
    pose[:3, 3] = measured.mean(axis=0) - scale * pose[:3, :3] @ nominal.mean(axis=0)
    return pose, scale


def _apply(pose: np.ndarray, scale: float, nominal: np.ndarray) -> np.ndarray:
    return scale * nominal @ pose[:3, :3].T + pose[:3, 3]


def _check_geometry(nominal: np.ndarray, ids: Sequence[str], where: Sequence[tuple]) -> None:
    """InputError for fewer than 3 datums, or datums on one line (located at the first)."""
    if len(nominal) < MIN_DATUMS:
        raise InputError(
            f"{len(nominal)} datum(s) ({', '.join(ids)}): the part frame needs at least "
            f"{MIN_DATUMS} datums not on one line",
            *(where[0] if where else ()),
        )
    spread = np.linalg.svd(nominal - nominal.mean(axis=0), compute_uv=False)
    if spread[1] <= COLLINEAR_RATIO * spread[0]:
        across = spread[1] / np.sqrt(len(nominal))
        raise InputError(
            f"datums {', '.join(ids)} lie on one line (RMS {across:.3f} mm across it): the "
            "rotation about it is not defined; measure a datum off that line",
            *where[0],
        )


def _fit(nominal: np.ndarray, measured: np.ndarray, scale: float | None) -> PartFit:
    """The least-squares frame of datums (N, 3) mm with its covariance; no moved-datum test."""
    pose, fitted_scale = _similarity(nominal, measured, scale)
    fitted = _apply(pose, fitted_scale, nominal)
    residual = measured - fitted
    k = 6 if scale is not None else 7
    dof = 3 * len(nominal) - k
    sigma = float(np.sqrt(np.sum(residual**2) / dof))
    nan = np.full(len(nominal), np.nan)
    fit = PartFit(
        robot_T_base=pose,
        scale=fitted_scale,
        scale_fitted=scale is None,
        fitted=fitted,
        residuals_mm=np.linalg.norm(residual, axis=1),
        loo_mm=nan,
        loo_ratio=nan,
        sigma_mm=sigma,
        dof=dof,
        centroid=fitted.mean(axis=0),
        nominal_centroid=nominal.mean(axis=0),
        covariance=np.zeros((k, k)),
    )
    jac = fit._jacobian(nominal).reshape(-1, k)
    return replace(fit, covariance=sigma**2 * np.linalg.inv(jac.T @ jac))


def fit_part_frame(
    nominal: np.ndarray,
    measured: np.ndarray,
    ids: Sequence[str],
    scale: float | None = 1.0,
    where: Sequence[tuple] = (),
) -> PartFit:
    """Fit ``robot_T_base`` from CAD points ``nominal`` (N, 3) mm in the part frame and the same
    datums ``measured`` (N, 3) mm in the robot frame, matched row by row; ``ids`` name them and
    ``where`` locates each (path, line[, column]) for errors. ``scale``: the part's scale, None
    to fit it. InputError for fewer than 3 datums, datums on one line or a moved datum."""
    nominal = np.asarray(nominal, dtype=float)
    measured = np.asarray(measured, dtype=float)
    where = list(where) or [()] * len(nominal)
    _check_geometry(nominal, ids, where)
    loo_mm, loo_ratio = _leave_one_out(nominal, measured, scale)
    fit = replace(_fit(nominal, measured, scale), loo_mm=loo_mm, loo_ratio=loo_ratio)
    moved = fit.moved
    if moved is not None:
        raise InputError(
            f"datum {ids[moved]} is {loo_mm[moved]:.3f} mm from where the other datums put it, "
            f"{loo_ratio[moved]:.0f}x what their residuals lead to expect: it moved, or is not "
            "the CAD point of that id; remeasure it or leave it out",
            *where[moved],
        )
    return fit


def _leave_one_out(
    nominal: np.ndarray, measured: np.ndarray, scale: float | None
) -> tuple[np.ndarray, np.ndarray]:
    """For each datum: how far the fit of the others misses it (N,) mm, and that over the miss
    their residuals lead to expect (N,): sqrt(3 sigma^2 + the trace of their frame's covariance
    at the datum), sigma from their residuals. NaN where the others cannot define a frame."""
    n = len(nominal)
    miss, ratio = np.full(n, np.nan), np.full(n, np.nan)
    if n <= MIN_DATUMS:
        return miss, ratio
    for i in range(n):  # a handful of datums: one small fit each
        keep = np.arange(n) != i
        spread = np.linalg.svd(nominal[keep] - nominal[keep].mean(axis=0), compute_uv=False)
        if spread[1] <= COLLINEAR_RATIO * spread[0]:
            continue
        others = _fit(nominal[keep], measured[keep], scale)
        predicted = _apply(others.robot_T_base, others.scale, nominal[i : i + 1])[0]
        miss[i] = float(np.linalg.norm(measured[i] - predicted))
        per_axis = others.sigma_at(nominal[i : i + 1])[0][0]
        expected = np.sqrt(3.0 * others.sigma_mm**2 + np.sum(per_axis**2))
        ratio[i] = miss[i] / expected if expected > 0.0 else np.inf
    return miss, ratio


def reach_mm(robot: RobotModel, samples: int = 4096) -> float:
    """The largest distance (mm) of the robot's TCP from the robot frame's origin over
    ``samples`` joint positions spread within its joint limits (a fixed sample: same answer
    every call)."""
    limits = np.radians(robot.joint_limits_deg)
    rng = np.random.default_rng(0)
    q = limits[:, 0] + rng.random((samples, len(limits))) * (limits[:, 1] - limits[:, 0])
    return float(np.linalg.norm(robot.fk(q)[:, :3, 3], axis=1).max())
