"""The error budget of every corrected position: how far from its target the position may land,
per axis (1 sigma) and as a 95 % bound on the error's length (``u95``), all in mm, robot frame.

Each term is a covariance (N, 3, 3) mm²; the terms are independent and add:

(a) **the calibrated model** (``ModelBudget``): at joints q the model's prediction varies with its
    parameters by s² H(q), H(q) = J(q) (Jᵀ J)⁺ J(q)ᵀ the prediction leverage of the measured rows
    (``kinematics.support``; J(q) (3, p) the Jacobian in every identified parameter, joint-error
    terms included, ⁺ in the identifiable directions), and a position lands off by the part of
    the error no parameter holds (what the model leaves, with the robot's repeatability and the
    scatter of the calibration rows): s² I. So C_a(q) = D (I + H(q)) D, D = diag(s) with s (3,)
    the residual RMS per axis scaled by k. ``accugrid identify`` chooses k on its own held-out
    folds (never on later holes): the held-out rows' mean square per axis against what the
    formula predicts for a row left out of its fit, H (I − H)⁻¹ per pose:
    k² = Σ_axes held_out_rms² / Σ_axes s² (1 + mean H_loo). ``budget_section`` writes
    ``identification.budget`` of the calibrated YAML; ``ModelBudget.from_doc`` reads it.
    A position the model's DH-only fallback corrects (a target without the model's support,
    ``kinematics.support``) carries that fit's own term instead (``ModelBudget.of_fallback``):
    D_fb (I + H_fb(q)) D_fb, D_fb = diag(s_fb) with s_fb its k-fold held-out RMS per axis (a
    held-out RMS already holds a left-out pose's leverage: a few per cent high where the poses
    are, p / n) and H_fb its prediction leverage among the same poses; and no grid term (the
    fallback adds no grid).
(b) **the grid** where one corrects (``grid_variance``, diagonal): the interpolated vertex means
    carry the rows' noise σ_n² Σ w_i² / repeats (w the trilinear weights of the 8 vertices), and
    the interpolation misses the error's curvature by ½ Δ² t (1 − t) per grid axis (Δ² the RMS
    second difference of the vertex errors along that axis, the noise's share removed; t the local
    coordinate in the cell): 0 at the vertices, largest at a cell's centre.
(c) **the tool and the part frame** (``FrameBudget``): the TCP's σ of a tool file (isotropic: its
    per-axis variances' mean) and the part frame's covariance of a part file carried to the
    position, J C Jᵀ (``kinematics.part_frame.frame_jacobian``).
(d) **the repeatability**: a model's floor s² I holds it (the calibration rows' scatter); a grid
    alone adds its rows' scatter σ_n² I.

The bound: |e|² ≈ g χ²_h (Satterthwaite, ``infra.bounds``).
``Budget.assess`` fills a verdict's numbers ``sigma_x``, ``sigma_y``, ``sigma_z`` and ``u95``
(N,) mm for its corrected positions (NaN elsewhere, and where a term is unknown: a model file
without the section).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from accugrid.compensation.interpolation import locate
from accugrid.infra.bounds import bound_from_moments, length_bound_95

if TYPE_CHECKING:  # a grid-only job never loads the robot modules
    from accugrid.compensation.grid import GridModel
    from accugrid.infra.yamlfile import YamlDoc
    from accugrid.kinematics.robot import Robot
    from accugrid.kinematics.support import Structure, Support

__all__ = [
    "COVERAGE_RANGE",
    "coverage_range",
    "SECTION",
    "Budget",
    "FrameBudget",
    "ModelBudget",
    "budget_section",
    "coverage",
    "grid_variance",
]

SECTION = ("identification", "budget")
BUDGET_SCHEMA = {
    "parameters": None,
    "joints_deg": None,
    "repeats": None,
    "residual_rms_mm": dict.fromkeys("xyz"),
    "held_out_rms_mm": dict.fromkeys("xyz"),
    "scale": None,
    "sigma_mm": dict.fromkeys("xyz"),
}
COVERAGE_RANGE = (0.90, 0.98)  # a 95 % bound is called calibrated when it holds this share
_BLOCK = 4096  # positions per Jacobian block


@dataclass(frozen=True)
class ModelBudget:
    """Term (a) of a calibrated model (module docstring): its ``structure`` and ``robot`` (the
    Jacobian's), the leverage map W (k, p) of its measured rows (|W J(q)ᵀ|² = H(q)) and the
    scaled residual ``sigma_mm`` (3,) per axis."""

    structure: Structure
    robot: Robot
    leverage_map: np.ndarray
    sigma_mm: np.ndarray

    def covariance(self, q: np.ndarray) -> np.ndarray:
        """C_a (N, 3, 3) mm² at the controller's joints q (N, 6) rad, in blocks of ``_BLOCK``."""
        from accugrid.kinematics.support import hat_blocks

        q = np.atleast_2d(np.asarray(q, dtype=float))
        out = np.empty((len(q), 3, 3))
        scale = np.outer(self.sigma_mm, self.sigma_mm)
        for lo in range(0, len(q), _BLOCK):
            jac = self.structure.jacobian(self.robot, q[lo : lo + _BLOCK])
            out[lo : lo + _BLOCK] = (np.eye(3) + hat_blocks(self.leverage_map, jac)) * scale
        return out

    @classmethod
    def of_fallback(cls, support: Support) -> ModelBudget | None:
        """The term of the positions a model's DH-only fallback corrects (module docstring);
        None where its file records no ``sigma_mm``."""
        if support.fallback_sigma_mm is None:
            return None
        structure, robot = support.fallback_structure, support.robot
        return cls(structure, robot, support.fallback_map, support.fallback_sigma_mm)

    @classmethod
    def from_doc(cls, doc: YamlDoc, robot: Robot, structure: Structure) -> ModelBudget | None:
        """The ``identification.budget`` section of a calibrated file (``robot`` loaded from it,
        ``structure`` its terms); None without one; InputError at a bad key or value."""
        from accugrid.kinematics.support import number_rows, whitened

        if not doc.has(*SECTION):
            return None
        doc.check_keys(BUDGET_SCHEMA, *SECTION)
        names = [str(n) for n in doc.sequence(*SECTION, "parameters")]
        if names != structure.names:
            raise doc.error(
                f"{doc.keyname(*SECTION, 'parameters')} are not the parameters of the model's "
                "terms: the file was edited or written by another version",
                *SECTION,
                "parameters",
            )
        repeats = doc.number(*SECTION, "repeats")
        sigma = np.array([doc.number(*SECTION, "sigma_mm", k) for k in "xyz"])
        if not (repeats >= 1 and (sigma >= 0).all()):
            raise doc.error("repeats must be >= 1 and sigma_mm >= 0", *SECTION)
        joints = np.radians(number_rows(doc, (*SECTION, "joints_deg"), 6))
        jac = structure.jacobian(robot, joints)
        w = whitened(jac.reshape(-1, jac.shape[2])) / np.sqrt(repeats)
        return cls(structure, robot, w, sigma)


def budget_section(
    calibrated: Robot,
    q: np.ndarray,
    group: np.ndarray,
    structure: Structure,
    residuals: np.ndarray,
    held_out_rms_mm: np.ndarray,
) -> dict:
    """The ``identification.budget`` mapping of a model ``calibrated`` (nominal DH, identified
    TCP) identified with ``structure`` from rows with joints q (N, 6) rad of distinct poses
    ``group`` (N,) int, its fit's ``residuals`` (N, 3) mm and its k-fold held-out RMS (3,) mm;
    plain YAML data (module docstring, term (a))."""
    from accugrid.kinematics.calibrated import axes_dict
    from accugrid.kinematics.support import hat_blocks, row_texts, whitened

    _, first = np.unique(group, return_index=True)
    joints = np.round(np.degrees(q[first]), 3)  # as the file holds them
    jac = structure.jacobian(calibrated, np.radians(joints))
    hat = hat_blocks(whitened(jac.reshape(-1, jac.shape[2])), jac)  # per pose
    loo = np.diagonal(hat @ np.linalg.inv(np.eye(3) - hat), axis1=1, axis2=2)  # (n, 3)
    repeats = len(q) / len(first)
    rms = np.sqrt(np.mean(np.asarray(residuals) ** 2, axis=0))
    held = np.asarray(held_out_rms_mm, dtype=float)
    predicted = rms**2 * (1.0 + loo.mean(axis=0) / repeats)
    scale = float(np.sqrt(np.sum(held**2) / np.sum(predicted)))
    return {
        "parameters": structure.names,
        "joints_deg": row_texts(joints, ".3f"),
        "repeats": float(repeats),
        "residual_rms_mm": axes_dict(rms),
        "held_out_rms_mm": axes_dict(held),
        "scale": scale,
        "sigma_mm": axes_dict(scale * rms),
    }


def grid_variance(grid: GridModel, points: np.ndarray) -> np.ndarray:
    """Term (b) (N, 3) mm², the diagonal of its covariance, of a grid at points (N, 3) mm robot
    frame (clamped into its box), from its rows' noise (0 without repeats) and its vertex errors'
    curvature."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    noise = 0.0 if grid.noise_mm is None else grid.noise_mm
    repeats = 1.0 if grid.repeats is None else float(np.mean(grid.repeats))
    _, frac = locate(points.T, grid.origin, grid.step, grid.counts)
    np.clip(frac, 0.0, 1.0, out=frac)
    mean_noise = noise**2 / repeats
    spread = frac * (1.0 - frac)  # (3, N) t (1 - t)
    weights = 1.0 - 2.0 * spread  # per axis t² + (1 - t)²: Σ w² of the 8 trilinear weights is
    share = weights[0] * weights[1] * weights[2]  # their product (N,)
    curvature = np.zeros((3, 3))  # (grid axis, error component) RMS second difference
    for axis in range(3):
        if grid.counts[axis] >= 3:
            d2 = np.diff(grid.errors, n=2, axis=axis).reshape(-1, 3)
            curvature[axis] = np.sqrt(np.clip(np.mean(d2**2, axis=0) - 6 * mean_noise, 0, None))
    miss = (0.5 * curvature).T @ spread  # (3, N): ½ Δ² t (1 - t) summed over the grid axes
    return (share * mean_noise + miss**2).T


@dataclass(frozen=True)
class FrameBudget:
    """Term (c): the TCP's 1 sigma per axis (3,) mm of a tool file (None: a taught tool, not
    counted) and a part file's frame: covariance (6, 6) of (translation mm at ``part_centroid``
    (3,) mm robot frame, rotation rad) (None: a typed-in base, not counted)."""

    tool_sigma_mm: np.ndarray | None = None
    part_covariance: np.ndarray | None = None
    part_centroid: np.ndarray | None = None

    def part_term(self, points: np.ndarray) -> np.ndarray | None:
        """The part frame's covariance (N, 3, 3) mm² at points (N, 3) mm robot frame (None:
        no part file)."""
        if self.part_covariance is None:
            return None
        from accugrid.kinematics.part_frame import frame_jacobian

        jac = frame_jacobian(points, self.part_centroid)
        return jac @ self.part_covariance @ jac.transpose(0, 2, 1)


@dataclass(frozen=True)
class Budget:
    """A job's budget (module docstring): the model's term (None: no model, or a model file
    without the section: unknown), whether a model corrects (``modelled``) and the tool's and
    part's term."""

    model: ModelBudget | None = None
    modelled: bool = False
    frames: FrameBudget = FrameBudget()

    def assess(
        self,
        numbers: dict,
        n: int,
        at: np.ndarray,
        points: np.ndarray,
        grid: GridModel | None,
        model: np.ndarray | None,
    ) -> None:
        """Write ``sigma_x``, ``sigma_y``, ``sigma_z`` and ``u95`` (n,) mm into a verdict's
        ``numbers`` for its positions ``at`` (k,) at ``points`` (k, 3) mm robot frame (NaN
        elsewhere): ``grid`` the grid that corrects them (None: none), ``model`` term (a) (k, 3,
        3) mm² already evaluated at their joints (None: no model's term); NaN where a model
        corrects without its term, or nothing corrects. Diagonal terms stay (k, 3): a grid
        alone costs no (k, 3, 3) arrays."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        diagonal = np.zeros((len(points), 3))
        if grid is not None:
            diagonal += grid_variance(grid, points)
            if not self.modelled and grid.noise_mm is not None:
                diagonal += grid.noise_mm**2  # (d): the rows' scatter, a hole's too
        if self.modelled and model is None or not self.modelled and grid is None:
            diagonal += np.nan  # a model without its term, or nothing corrects: unknown
        if self.frames.tool_sigma_mm is not None:
            diagonal += np.mean(np.asarray(self.frames.tool_sigma_mm) ** 2)
        full = self.frames.part_term(points)
        if model is not None:
            full = model if full is None else full + model
        if full is None:
            sigma = np.sqrt(diagonal)
            u95 = bound_from_moments(diagonal.sum(axis=1), (diagonal**2).sum(axis=1))
        else:
            np.einsum("naa->na", full)[:] += diagonal
            sigma = np.sqrt(np.clip(np.einsum("naa->na", full), 0.0, None))
            u95 = length_bound_95(full)
        for i, key in enumerate(("sigma_x", "sigma_y", "sigma_z")):
            numbers.setdefault(key, np.full(n, np.nan))[at] = sigma[:, i]
        numbers.setdefault("u95", np.full(n, np.nan))[at] = u95


def coverage_range(targets: int) -> tuple[float, float]:
    """The shares within their 95 % bounds that call the bounds calibrated when they were checked
    at ``targets`` distinct targets: ``COVERAGE_RANGE``, widened to three binomial standard
    errors of a 95 % share where the targets are too few to tell more (the repeats of one
    target share its error, so they are not counted apart)."""
    spread = 3.0 * np.sqrt(0.95 * 0.05 / max(targets, 1))
    lo, hi = COVERAGE_RANGE
    return min(lo, 0.95 - spread), min(1.0, max(hi, 0.95 + spread))


def coverage(deviations: np.ndarray, u95: np.ndarray) -> tuple[float, int]:
    """The share of deviations (N, 3) mm whose length lies within their bound ``u95`` (N,) mm,
    over the positions with a bound, and their count."""
    u95 = np.asarray(u95, dtype=float)
    known = np.isfinite(u95)
    if not known.any():
        return float("nan"), 0
    inside = np.linalg.norm(np.asarray(deviations)[known], axis=1) <= u95[known]
    return float(inside.mean()), int(known.sum())
