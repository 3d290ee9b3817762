"""Group sparse Bayesian learning (automatic relevance determination) over candidate groups.

The linear model y = X·b + C·w + e, e ~ N(0, σ² I), with a flat prior on b (the DH errors, TCP
and pinned terms: columns X (M, r)) and for each candidate group g of columns C_g (M, d_g) the
prior w_g ~ N(0, I / α_g), one precision per group. The flat prior is integrated out by
projecting y and C on the orthogonal complement of X (the restricted likelihood); the
precisions α (and σ² unless given) maximise the marginal likelihood of what is left, by
MacKay's fixed-point updates for groups (Tipping 2001; Wipf & Nagarajan 2008):

    Σ = (CᵀC / σ² + diag(α))⁻¹,  μ = Σ·Cᵀy / σ²,
    γ_g = d_g − α_g·tr(Σ_gg),  α_g ← γ_g / |μ_g|²,
    σ² ← |y − C·μ|² / (M − r − Σ γ_g).

A group whose precision passes ``PRUNE`` / σ² (prior RMS effect below 1 % of the noise per unit
RMS column) is pruned. Maximising the evidence over many candidates keeps a few that fit the
noise (the best of m is always a little lucky), so each group may carry a prior against its
inclusion, ``penalty`` (log prior odds, e.g. log m for one true group among m candidates): when
the fit has converged, the group whose own log-evidence gain (Tipping & Faul 2003: the marginal
likelihood with it at its α against without it, the others as they are) falls furthest below its
penalty is pruned and the fit continues, until every group kept pays its way. Everything runs on
the sufficient statistics CᵀC, Cᵀy, yᵀy of the projected problem. Deterministic (no random
start). Columns should have comparable scales (the structure search gives every candidate column
unit RMS).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import LinAlgError, cho_factor, cho_solve

__all__ = ["PRUNE", "GroupArd", "ard_choice", "group_ard", "projected_statistics"]

PRUNE = 1e4  # α·σ² beyond this: the group's prior RMS effect < 1 % of the noise, pruned
_MAX_ITER = 500  # fixed-point iterations per convergence
_TOL = 1e-4  # convergence: largest change of a posterior mean weight, in noise sigmas (and σ²)


@dataclass(frozen=True)
class GroupArd:
    """The maximum-evidence fit: precision ``alpha`` (G,) per group (inf: pruned), posterior
    mean ``mean`` (m,) of the candidate weights (0 on pruned groups), ``gamma`` (G,) the
    well-determined parameters per group (0..d_g), ``gain`` (G,) each kept group's log-evidence
    gain (0 where pruned), ``noise_var`` σ² (residual units squared), ``relevant`` (G,) bool (not
    pruned) and the fixed-point ``iterations`` used."""

    alpha: np.ndarray
    mean: np.ndarray
    gamma: np.ndarray
    gain: np.ndarray
    noise_var: float
    relevant: np.ndarray
    iterations: int


def projected_statistics(
    y: np.ndarray, x: np.ndarray, c: np.ndarray
) -> tuple[np.ndarray, np.ndarray, float, int]:
    """Sufficient statistics of residuals y (M,) and candidate columns c (M, m) beyond the
    flat-prior columns x (M, r): (CᵀC (m, m), Cᵀy (m,), yᵀy, degrees of freedom M − rank x),
    all of the projections on the orthogonal complement of x."""
    q, r = np.linalg.qr(x)
    diag = np.abs(np.diag(r))
    q = q[:, diag > 1e-10 * max(float(diag.max(initial=0.0)), 1e-300)]
    yp = y - q @ (q.T @ y)
    cp = c - q @ (q.T @ c)
    return cp.T @ cp, cp.T @ yp, float(yp @ yp), len(y) - q.shape[1]


class _Fit:
    """The fixed-point state on projected statistics (``group_ard``)."""

    def __init__(self, gram, rhs, yy, dof, groups, noise_var, noise_floor) -> None:
        self.gram, self.rhs, self.yy, self.dof, self.groups = gram, rhs, yy, dof, groups
        self.size = np.array([len(g) for g in groups])
        self.column_group = np.full(gram.shape[0], -1)
        for i, g in enumerate(groups):
            self.column_group[g] = i
        self.estimate = noise_var is None
        self.floor = max(float(noise_floor), 1e-300)
        self.sigma2 = (
            float(noise_var) if noise_var is not None else max(yy / max(dof, 1), self.floor)
        )
        # start: each group's prior RMS effect per unit column equal to the noise
        self.alpha = np.where(self.size > 0, 1.0 / self.sigma2, np.inf)
        self.mean = np.zeros(gram.shape[0])
        self.gamma = np.zeros(len(groups))
        self.iterations = 0

    def posterior(self):
        """Active columns (a,), their group (a,), Σ (a, a) and μ (a,); sets mean and gamma."""
        active = np.isfinite(self.alpha)
        cols = np.flatnonzero((self.column_group >= 0) & active[np.maximum(self.column_group, 0)])
        g_of = self.column_group[cols]
        precision = self.gram[np.ix_(cols, cols)] / self.sigma2
        precision[np.diag_indices_from(precision)] += self.alpha[g_of]
        sigma = cho_solve(_cholesky(precision), np.eye(cols.size))
        mu = sigma @ self.rhs[cols] / self.sigma2
        self.mean[:] = 0.0
        self.mean[cols] = mu
        trace = np.bincount(g_of, np.diag(sigma), minlength=len(self.groups))
        self.gamma = np.zeros(len(self.groups))
        self.gamma[active] = np.clip(
            self.size[active] - self.alpha[active] * trace[active], 0, None
        )
        return cols, g_of, sigma, mu

    def converge(self) -> None:
        """Fixed-point updates until the posterior mean moves less than ``_TOL`` noise sigmas."""
        previous = np.full(self.gram.shape[0], np.inf)
        for _ in range(_MAX_ITER):
            if not np.isfinite(self.alpha).any():
                self.mean[:] = 0.0
                self.gamma[:] = 0.0
                return
            self.iterations += 1
            cols, g_of, _, mu = self.posterior()
            active = np.isfinite(self.alpha)
            power = np.bincount(g_of, mu**2, minlength=len(self.groups))
            new = self.alpha.copy()
            new[active] = self.gamma[active] / np.maximum(power[active], 1e-300)
            new[active & (new * self.sigma2 > PRUNE)] = np.inf
            change = float(np.abs(self.mean - previous).max() / np.sqrt(self.sigma2))
            if self.estimate:
                explained = mu @ self.rhs[cols]
                fitted = self.yy - 2 * explained + mu @ self.gram[np.ix_(cols, cols)] @ mu
                new_sigma2 = max(float(fitted) / max(self.dof - self.gamma.sum(), 1.0), self.floor)
                change = max(change, abs(new_sigma2 - self.sigma2) / self.sigma2)
                self.sigma2 = new_sigma2
            pruned = bool(np.any(active & ~np.isfinite(new)))
            previous = self.mean.copy()
            self.alpha = new
            if not pruned and change < _TOL:
                break
        if np.isfinite(self.alpha).any():
            self.posterior()

    def gains(self) -> np.ndarray:
        """Each active group's log-evidence gain (G,) at its α against without it (others as they
        are): ½ Σ_i [log(α / (α + λ_i)) + q_i² / (α + λ_i)] over the eigenpairs of the group's
        S_g = C_gᵀ B⁻¹ C_g and q = Uᵀ C_gᵀ B⁻¹ y, B the covariance without it (-inf pruned)."""
        out = np.full(len(self.groups), -np.inf)
        active = np.isfinite(self.alpha)
        if not active.any():
            return out
        cols, g_of, sigma, mu = self.posterior()
        s2 = self.sigma2
        cross = self.gram[:, cols] / s2  # (m, a)
        for i in np.flatnonzero(active):
            g = self.groups[i]
            s_bar = self.gram[np.ix_(g, g)] / s2 - cross[g] @ sigma @ cross[g].T
            q_bar = self.rhs[g] / s2 - cross[g] @ mu
            lam_bar, u = np.linalg.eigh(s_bar)
            alpha = self.alpha[i]
            lam_bar = np.clip(lam_bar, 0.0, alpha * (1 - 1e-12))
            lam = alpha * lam_bar / (alpha - lam_bar)
            q = (alpha + lam) * (u.T @ q_bar) / alpha
            out[i] = 0.5 * float(np.sum(np.log(alpha / (alpha + lam)) + q**2 / (alpha + lam)))
        return out


def _cholesky(precision: np.ndarray):
    """The Cholesky factor of a posterior precision (a, a). Where columns of the candidates are
    (nearly) dependent and their groups' α tiny, rounding leaves it not quite positive definite:
    then a jitter of 1e-12, 1e-10, .. 1e-6 × its mean diagonal is added, as Gaussian-process
    codes do; the posterior moves by far less than the noise."""
    try:
        return cho_factor(precision)
    except LinAlgError:
        scale = float(np.mean(np.diag(precision)))
        for jitter in (1e-12, 1e-10, 1e-8, 1e-6):
            try:
                return cho_factor(precision + jitter * scale * np.eye(len(precision)))
            except LinAlgError:
                continue
        raise


def group_ard(
    gram: np.ndarray,
    rhs: np.ndarray,
    yy: float,
    dof: int,
    groups: list[np.ndarray],
    noise_var: float | None = None,
    penalty: np.ndarray | None = None,
    noise_floor: float = 0.0,
) -> GroupArd:
    """Group ARD on projected statistics (``projected_statistics``): ``gram`` CᵀC (m, m),
    ``rhs`` Cᵀy (m,), ``yy`` yᵀy, ``dof`` the equations left after the flat-prior columns,
    ``groups`` the column indices (into m) of each group (empty: never relevant).
    ``noise_var``: σ² fixed (e.g. from repeated poses), else estimated with the precisions, never
    below ``noise_floor`` (e.g. what the repeats' scatter alone puts in a mean of them).
    ``penalty`` (G,): log prior odds against each group (default 0: plain ARD); groups whose
    log-evidence gain stays below it are pruned one at a time, the smallest margin first."""
    fit = _Fit(gram, rhs, yy, dof, groups, noise_var, noise_floor)
    fit.converge()
    gain = fit.gains()
    if penalty is not None:
        while np.isfinite(fit.alpha).any():
            margin = gain - penalty
            worst = int(np.argmin(np.where(np.isfinite(fit.alpha), margin, np.inf)))
            if margin[worst] >= 0:
                break
            fit.alpha[worst] = np.inf
            fit.converge()
            gain = fit.gains()
    relevant = np.isfinite(fit.alpha)
    return GroupArd(
        fit.alpha,
        fit.mean.copy(),
        fit.gamma.copy(),
        np.where(relevant, gain, 0.0),
        fit.sigma2,
        relevant,
        fit.iterations,
    )


def ard_choice(
    y: np.ndarray,
    x: np.ndarray,
    c: np.ndarray,
    groups: list[np.ndarray],
    noise_var: float | None = None,
    penalty: np.ndarray | None = None,
    noise_floor: float = 0.0,
) -> tuple[list[int], GroupArd]:
    """The groups (indices into ``groups``) group ARD keeps for residuals y (M,), flat-prior
    columns x (M, r) and candidate columns c (M, m) (``group_ard``), largest posterior effect
    |μ_g|² first, with the fit (``noise_floor``: ``group_ard``)."""
    fit = group_ard(*projected_statistics(y, x, c), groups, noise_var, penalty, noise_floor)
    power = np.array([float(fit.mean[g] @ fit.mean[g]) for g in groups])
    chosen = [int(i) for i in np.flatnonzero(fit.relevant)]
    return sorted(chosen, key=lambda i: (-power[i], i)), fit
