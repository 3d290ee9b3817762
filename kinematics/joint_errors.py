"""Non-geometric errors of a real arm, as joint-angle perturbations inside its forward kinematics.

The true robot reaches FK(q + δ(q)) when its controller commands the KUKA axis angles q (N, 6) rad.
δ (N, 6) rad is the sum of

- **joint compliance under gravity**: δ_j = c_j · τ_j(q), c_j in rad per N·m and τ_j the static
  gravity torque on axis j (N·m, about the positive KUKA axis direction, so a positive c deflects
  the joint the way gravity pulls it). τ comes from lumped point masses, each fixed in one DH link
  frame (frame i is the pose A_1 ... A_i of seed Eq. 1; mm), with gravity along −Z of the robot
  base (floor mounting): τ_j = sign_j · z_{j−1} · Σ_{masses on links ≥ j} (p_m − o_{j−1}) × m g.
- **gravity moments** (compliance without masses): δ_j += Σ_L Σ_u G_jLu · τ_j^(L,u)(q), where
  τ_j^(L,u) is the gravity torque on axis j of a unit mass (u = 0, 1 kg at the origin of link frame
  L) or a unit first moment (u = 1..3, 1 kg·mm along x, y, z of frame L), so G_jLu = c_j · m_L
  (rad/(N·m)·kg) and c_j · m_L · r_L (rad/(N·m)·kg·mm): the compliance × first-moment products of
  unknown lumped masses, linear in the data (``moments`` (6, 6, 4): axis, link 1..6, u).
- **reducer transmission errors**: δ_j += Σ_k A_jk sin(k_jk · q_j + φ_jk), amplitudes in rad.

Thermal drift is a change of the link lengths, not of the joint angles: ``JointErrors.thermal``
(a ``Thermal``) scales every DH a and d by 1 + expansion · ΔT in ``Robot.true_robot``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from accugrid.kinematics.dh import DHTable, chain

__all__ = [
    "GRAVITY_MPS2",
    "MAX_ORDER",
    "Harmonic",
    "JointErrors",
    "PointMass",
    "Thermal",
    "gravity_basis",
]

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
    moments: np.ndarray | None = None  # (6, 6, 4) gravity moments G (module docstring)

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
        wanted = np.ones(6, bool) if axes is None else np.asarray(axes, bool)
        masses = [m for m in self.masses if m.kg != 0.0]
        if not masses or not wanted.any():
            return np.zeros((len(q), 6))
        first = np.zeros((6, 4))  # per link: kg, then kg·mm first moment in the link frame
        for m in masses:
            first[m.link - 1] += m.kg * np.array([1.0, *m.at_mm])
        deepest = max(m.link for m in masses)
        unit = gravity_basis(dh, q, self.gravity_mps2, deepest)  # (N, 6, deepest, 4)
        return np.einsum("njlu,lu->nj", unit, first[:deepest]) * wanted

    def moment_deltas(self, dh: DHTable, q: np.ndarray) -> np.ndarray:
        """δ (N, 6) rad of the gravity moments alone (zero without ``moments``)."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        if self.moments is None or not np.any(self.moments):
            return np.zeros((len(q), 6))
        used = np.flatnonzero(np.abs(self.moments).sum(axis=(0, 2)))
        deepest = int(used.max()) + 1
        unit = gravity_basis(dh, q, self.gravity_mps2, deepest)
        return np.einsum("njlu,jlu->nj", unit, self.moments[:, :deepest])

    def delta(self, dh: DHTable, q: np.ndarray) -> np.ndarray:
        """Joint-angle perturbation δ (N, 6) rad at commanded KUKA angles q (N, 6) rad."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        out = np.zeros((len(q), 6))
        if np.any(self.compliance):
            out += self.compliance * self.gravity_torques(dh, q, self.compliance != 0)
        if self.moments is not None:
            out += self.moment_deltas(dh, q)
        for h in self.harmonics:
            out[:, h.axis - 1] += h.amplitude_rad * np.sin(h.order * q[:, h.axis - 1] + h.phase_rad)
        return out


def gravity_basis(dh: DHTable, q: np.ndarray, gravity_mps2: float, links: int = 6) -> np.ndarray:
    """Gravity torques (N, 6, links, 4) N·m on each KUKA axis at joints q (N, 6) rad of a unit
    quantity fixed in link frame L = 1..links: u = 0 one kg at the frame's origin, u = 1..3 one
    kg·mm of first moment along its x, y, z (gravity along −Z of the base; zero on axes at or
    beyond L, which do not carry it). Torques are linear in the masses: a lumped mass m at r (mm)
    in frame L gives τ = unit[..., L, :] @ (m, m·r)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    frames = [np.broadcast_to(np.eye(4), (len(q), 4, 4))] + chain(dh, q, links=links)
    out = np.zeros((len(q), 6, links, 4))
    for j in range(min(links, 6)):  # joint j + 1 turns about z of frame j
        axis = frames[j][:, :3, 2]
        origin = frames[j][:, :3, 3]
        for link in range(j + 1, links + 1):
            # lever v (kg·m) of each unit quantity about frame j's origin, base frame
            levers = [frames[link][:, :3, 3] - origin] + [frames[link][:, :3, k] for k in range(3)]
            for u, v in enumerate(levers):
                # moment of v × (0, 0, -g) about the axis
                moment = gravity_mps2 * 1e-3 * (v[:, 0] * axis[:, 1] - v[:, 1] * axis[:, 0])
                out[:, j, link - 1, u] = dh.sign[j] * moment
    return out
