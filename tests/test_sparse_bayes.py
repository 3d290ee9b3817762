"""Group sparse Bayesian learning: the evidence gains it prunes by are the marginal likelihood's,
dominant groups are kept, noise alone keeps nothing once each group pays log m, and the same
input gives the same fit."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from accugrid.kinematics.sparse_bayes import _Fit, ard_choice, projected_statistics

GROUPS = [np.arange(2 * i, 2 * i + 2) for i in range(8)] + [np.arange(16, 20)]
M, R = 120, 4


def problem(seed: int, weights: dict[int, float], noise: float = 0.5):
    """Random flat-prior columns x (M, R), candidate columns c (M, 20) of unit RMS, y with the
    groups ``weights`` (group: amplitude of each of its weights) and normal noise."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(M, R))
    c = rng.normal(size=(M, 20))
    c /= np.sqrt(np.mean(c**2, axis=0))
    w = np.zeros(20)
    for g, amplitude in weights.items():
        w[GROUPS[g]] = amplitude * rng.choice([-1.0, 1.0], len(GROUPS[g]))
    y = x @ rng.normal(0, 3, R) + c @ w + rng.normal(0, noise, M)
    return y, x, c


def log_evidence(y, x, c, alpha, noise_var) -> float:
    """The restricted log marginal likelihood (up to a constant) by dense matrices: y and c
    projected on an orthonormal basis of the complement of x, covariance σ² I + Σ C_g C_gᵀ / α_g."""
    u = np.linalg.svd(np.eye(M) - x @ np.linalg.pinv(x))[0][:, : M - R]
    yp, cp = u.T @ y, u.T @ c
    cov = noise_var * np.eye(M - R)
    for i, g in enumerate(GROUPS):
        if np.isfinite(alpha[i]):
            cov += cp[:, g] @ cp[:, g].T / alpha[i]
    return -0.5 * (np.linalg.slogdet(cov)[1] + yp @ np.linalg.solve(cov, yp))


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 10_000), st.floats(0.2, 1.5))
def test_a_groups_gain_is_the_log_evidence_it_adds(seed, amplitude):
    """For every group kept, the gain the pruning compares with its penalty equals the dense
    log marginal likelihood with the group at its precision minus without it."""
    y, x, c = problem(seed, {0: amplitude, 3: amplitude / 2, 8: amplitude})
    fit = _Fit(*projected_statistics(y, x, c), GROUPS, 0.25)
    fit.converge()
    gains = fit.gains()
    whole = log_evidence(y, x, c, fit.alpha, 0.25)
    for i in np.flatnonzero(np.isfinite(fit.alpha)):
        without = fit.alpha.copy()
        without[i] = np.inf
        np.testing.assert_allclose(
            gains[i], whole - log_evidence(y, x, c, without, 0.25), rtol=1e-6, atol=1e-8
        )


@settings(max_examples=25, deadline=None)
@given(
    st.integers(0, 10_000),
    st.sets(st.integers(0, 8), min_size=1, max_size=3),
    st.booleans(),
)
def test_dominant_groups_are_kept_and_noise_alone_keeps_nothing(seed, true, known_noise):
    """Groups whose weights are 3x the noise on unit-RMS columns (120 equations) are all kept
    with the log(9) penalty, with the noise known or estimated; from noise alone none is."""
    penalty = np.full(len(GROUPS), np.log(len(GROUPS)))
    noise_var = 0.25 if known_noise else None
    y, x, c = problem(seed, dict.fromkeys(true, 1.5))
    chosen, fit = ard_choice(y, x, c, GROUPS, noise_var, penalty)
    assert set(true) <= set(chosen)
    assert fit.relevant[list(true)].all()
    y, x, c = problem(seed, {})
    chosen, fit = ard_choice(y, x, c, GROUPS, noise_var, penalty)
    assert chosen == []
    assert not fit.mean.any()


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 10_000))
def test_the_same_input_gives_the_same_fit_and_the_posterior_mean_is_near_the_truth(seed):
    rng = np.random.default_rng(seed)
    y, x, c = problem(seed, {1: 2.0, 5: 1.0}, noise=0.1 + rng.random() * 0.2)
    first, fit = ard_choice(y, x, c, GROUPS)
    again, same = ard_choice(y, x, c, GROUPS)
    assert first == again
    np.testing.assert_array_equal(fit.mean, same.mean)
    np.testing.assert_array_equal(fit.alpha, same.alpha)
    # the kept weights: the true amplitudes within a few standard errors of 0.3 / sqrt(120)
    np.testing.assert_allclose(np.abs(fit.mean[GROUPS[1]]), 2.0, atol=0.2)
    np.testing.assert_allclose(np.abs(fit.mean[GROUPS[5]]), 1.0, atol=0.2)
