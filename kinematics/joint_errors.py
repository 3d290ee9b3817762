"""Non-geometric errors of a real arm, as joint-angle perturbations inside its forward kinematics.

The true robot reaches FK(q + δ(q)) when its controller commands the KUKA axis angles q (N, 6) rad.
δ (N, 6) rad is the sum of

- **joint compliance under gravity**: δ_j = c_j · τ_j(q), c_j in rad per N·m and τ_j the static
  gravity torque on axis j (N·m, about the positive KUKA axis direction, so a positive c deflects
  the joint the way gravity pulls it). τ comes from lumped point masses, each fixed in one DH link
  frame (frame i is the pose A_1 ... A_i of seed Eq. 1; mm), with gravity along −Z of the robot
  base (floor mounting): τ_j = sign_j · z_{j−1} · Σ_{masses on links ≥ j} (p_m − o_{j−1}) × m g.
- **reducer transmission errors**: δ_j += Σ_k A_jk sin(k_jk · q_j + φ_jk), amplitudes in rad.

Thermal drift is a change of the link lengths, not of the joint angles: ``JointErrors.thermal``
(a ``Thermal``) scales every DH a and d by 1 + expansion · ΔT in ``Robot.true_robot``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from accugrid.kinematics.dh import DHTable, chain

__all__ = ["GRAVITY_MPS2", "MAX_ORDER", "Harmonic", "JointErrors", "PointMass", "Thermal"]

GRAVITY_MPS2 = 9.80665
MAX_ORDER = 100_000  # highest harmonic order accepted (a motor-side stage is a few hundred)


@dataclass(frozen=True)
class PointMass:
    """A lumped mass ``kg`` at ``at_mm`` (3,) in DH link frame ``link`` (1..6)."""

    link: int
    kg: float
    at_mm: tuple[float, float, float]


@dataclass(frozen=True)
class Harmonic:
    """One transmission-error term amplitude_rad · sin(order · A_axis + phase_rad); axis 1..6."""

    axis: int
    order: int
    amplitude_rad: float
    phase_rad: float = 0.0


@dataclass(frozen=True)
class Thermal:
    """Linear thermal growth: every DH a, d scaled by 1 + expansion_per_k · delta_t_k."""

    delta_t_k: float = 0.0
    expansion_per_k: float = 1.2e-5  # structural steel / cast iron, 1/K

    @property
    def scale(self) -> float:
        return 1.0 + self.expansion_per_k * self.delta_t_k

    def apply(self, dh: DHTable) -> DHTable:
        """The DH table with its lengths a, d (mm) grown by ``scale``."""
        return DHTable(dh.a * self.scale, dh.d * self.scale, dh.alpha, dh.theta_offset, dh.sign)


@dataclass(frozen=True)
class JointErrors:
    """Compliance (``compliance`` (6,) rad/(N·m) and ``masses``), ``harmonics`` and ``thermal``."""

    compliance: np.ndarray = field(default_factory=lambda: np.zeros(6))
    masses: tuple[PointMass, ...] = ()
    harmonics: tuple[Harmonic, ...] = ()
    thermal: Thermal | None = None
    gravity_mps2: float = GRAVITY_MPS2

    @classmethod
    def from_compliance(
        cls, compliance: np.ndarray, masses: tuple[PointMass, ...] | list[PointMass]
    ) -> JointErrors:
        """Compliance only: c (6,) rad per N·m (zeros on axes without compliance) and masses."""
        c = np.array(compliance, dtype=float).reshape(6)
        return cls(compliance=c, masses=tuple(masses))

    def gravity_torques(
        self, dh: DHTable, q: np.ndarray, axes: np.ndarray | None = None
    ) -> np.ndarray:
        """Static gravity torques τ (N, 6) N·m about the positive KUKA axes at joints q (N, 6) rad
        (only on ``axes``, a (6,) bool mask, when given; zero elsewhere).

        This is also ∂δ/∂c: ∂δ_j/∂c_j = τ_j(q), ∂δ_j/∂c_i = 0 for i ≠ j."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        tau = np.zeros((len(q), 6))
        wanted = np.ones(6, bool) if axes is None else np.asarray(axes, bool)
        masses = [m for m in self.masses if m.kg != 0.0]
        if not masses or not wanted.any():
            return tau
        deepest = max(m.link for m in masses)
        frames = [np.broadcast_to(np.eye(4), (len(q), 4, 4))] + chain(dh, q, links=deepest)
        # first moments kg·mm of the masses on each link, base frame
        first = np.zeros((deepest + 1, len(q), 3))
        kg = np.zeros(deepest + 1)
        for m in masses:
            link = frames[m.link]
            first[m.link] += m.kg * (link[:, :3, :3] @ np.asarray(m.at_mm, dtype=float))
            first[m.link] += m.kg * link[:, :3, 3]
            kg[m.link] += m.kg
        for j in np.flatnonzero(wanted[:deepest]):  # joint j + 1 turns about z of frame j
            # moment of the weights beyond joint j about frame j's origin: v × (0, 0, -g), with
            # v = Σ kg (p - o_j) in kg·m
            v = (first[j + 1 :].sum(axis=0) - kg[j + 1 :].sum() * frames[j][:, :3, 3]) * 1e-3
            axis = frames[j][:, :3, 2]
            moment_on_axis = self.gravity_mps2 * (v[:, 0] * axis[:, 1] - v[:, 1] * axis[:, 0])
            tau[:, j] = dh.sign[j] * moment_on_axis
        return tau

    def delta(self, dh: DHTable, q: np.ndarray) -> np.ndarray:
        """Joint-angle perturbation δ (N, 6) rad at commanded KUKA angles q (N, 6) rad."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        out = np.zeros((len(q), 6))
        if np.any(self.compliance):
            out += self.compliance * self.gravity_torques(dh, q, self.compliance != 0)
        for h in self.harmonics:
            out[:, h.axis - 1] += h.amplitude_rad * np.sin(h.order * q[:, h.axis - 1] + h.phase_rad)
        return out
