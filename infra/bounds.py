"""The 95 % bound on the length of a Gaussian error in 3-D, from its covariance (mm², any frame).

|e|² of an error e ~ N(0, C) is a sum of the eigenvalues λ_i of C times independent chi²_1; by
Satterthwaite's approximation it is g chi²_h with the same mean and variance: g h = Σ λ = tr C and
h = (Σ λ)² / Σ λ² (1 for one direction, 3 for an isotropic error; Σ λ² = |C|²_F, so no eigenvalues
are needed). The bound is sqrt(g · chi²_h's 95 % quantile). With C's scale estimated from ``dof``
degrees of freedom, |e|² / (g h) ~ F(h, dof) instead (``kinematics.part_frame``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["bound_from_moments", "length_bound_95"]

_COVERAGE = 0.95


def length_bound_95(cov: np.ndarray, dof: float = np.inf) -> np.ndarray:
    """The 95 % bound (N,) mm on the length of Gaussian errors of covariances (N, 3, 3) mm²
    (Satterthwaite's |e|² ~ g chi²_h, module docstring; ``dof``: the degrees of freedom of an
    estimated scale, F(h, dof); inf: known). NaN covariances give NaN."""
    cov = np.asarray(cov, dtype=float).reshape(-1, 3, 3)
    return bound_from_moments(np.einsum("naa->n", cov), np.einsum("nab,nab->n", cov, cov), dof)


# chi²_h's 95 % quantile over h at h = 1.0, 1.1, .., 3.0 (scipy.stats.chi2.ppf(0.95, h) / h):
# interpolated, within 0.05 % of it, without loading scipy in a job that needs no more of it
_CHI2_95_OVER_H = np.array([
    3.841459, 3.712725, 3.598353, 3.495984, 3.403743, 3.320130, 3.243930, 3.174146, 3.109957,
    3.050677, 2.995732, 2.944634, 2.896967, 2.852376, 2.810553, 2.771230, 2.734177, 2.699187,
    2.666082, 2.634703, 2.604909,
])  # fmt: skip
_H = np.linspace(1.0, 3.0, len(_CHI2_95_OVER_H))


def bound_from_moments(total: np.ndarray, square: np.ndarray, dof: float = np.inf) -> np.ndarray:
    """``length_bound_95`` from the covariances' eigenvalue sums (N,) mm², their trace, and
    squared sums (N,) mm⁴, their squared Frobenius norm (for diagonal covariances: the sums of
    the variances and of their squares)."""
    total, square = np.asarray(total, dtype=float), np.asarray(square, dtype=float)
    safe = np.where(square > 0.0, square, 1.0)
    h = np.clip(np.where(square > 0.0, total**2 / safe, 3.0), 1.0, 3.0)  # effective dof
    if np.isinf(dof):
        factor = np.interp(h, _H, _CHI2_95_OVER_H)
    else:
        from scipy.special import fdtri

        factor = fdtri(h, dof, _COVERAGE)
    return np.sqrt(np.clip(total, 0.0, None) * factor)  # g h F with g h = total
