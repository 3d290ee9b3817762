"""The candidate joint-error terms ``identify`` may add to the DH + TCP model, in groups.

- **Reducer harmonic** (axis 1..6, order k): δ_axis += s · sin(k · A_axis) + c · cos(k · A_axis),
  one group of two linear parameters s, c (rad).
- **Gravity compliance without masses** (an axis gravity loads, part): on every axis not
  parallel to gravity (``gravity_axes``: a UR's A2, A3 and A4 all carry load, a KUKA's A4-A6 the
  wrist and tool), the static gravity torque of unknown lumped masses fixed in the link frames is
  linear in their first moments (m and m · r per link, ``joint_errors.gravity_basis``), so
  compliance × first moment products are linear parameters whose Jacobian columns come from the
  nominal geometry only. The functions of the joint angles they span are split into parts by what
  carries the mass: the **upper arm** (link 2), the **forearm** (link 3 and a mass at the wrist
  point) and the **wrist** (first moments of links 4-6: a tool or payload off the wrist point).
  Each part's parameters are the
  coordinates of an orthonormal basis of the torque functions it adds beyond the parts before it
  (SVD over a fixed spread-out set of reference joints), so no two parameters are the same
  function. ``GravityTerm.moments`` maps them back to the first-moment products the calibrated
  YAML stores (``joint_errors.gravity_moments``, minimum-norm), which ``true_robot`` reproduces.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from accugrid.kinematics.joint_errors import GRAVITY_MPS2, gravity_basis
from accugrid.kinematics.robot import Robot

__all__ = [
    "gravity_axes",
    "GRAVITY_PARTS",
    "GravityTerm",
    "gravity_terms",
    "harmonic_name",
    "reference_joints",
]

# part name -> (link 1..6, u) first-moment quantities (u = 0 mass at the origin, 1..3 x, y, z)
GRAVITY_PARTS = {
    "upper arm": tuple((2, u) for u in range(4)),
    "forearm": tuple((3, u) for u in range(4)) + ((4, 0),),
    "wrist": tuple((4, u) for u in (1, 2, 3))
    + tuple((link, u) for link in (5, 6) for u in range(4)),
}
_REFERENCE_POSES = 400
_RTOL = 1e-9  # a unit quantity whose torque is this small against the largest carries none
_NEW = 1e-3  # a part's function with less than this share of its RMS beyond those before: none


@dataclass(frozen=True)
class GravityTerm:
    """One gravity group: ``axis`` 1..6, ``part`` (a GRAVITY_PARTS key) and ``basis`` (24, r):
    the axis's gravity-moment vector (6 links × 4 u, flattened, units of ``joint_errors``) of each
    of the group's r parameters (rad per unit of its normalised torque function)."""

    axis: int
    part: str
    basis: np.ndarray

    @property
    def name(self) -> str:
        return f"gravity A{self.axis} {self.part}"

    @property
    def size(self) -> int:
        return self.basis.shape[1]

    def moments(self, w: np.ndarray) -> np.ndarray:
        """The (6, 6, 4) gravity moments of the group's parameters w (r,)."""
        out = np.zeros((6, 6, 4))
        out[self.axis - 1] = (self.basis @ np.asarray(w, dtype=float)).reshape(6, 4)
        return out

    def functions(self, unit: np.ndarray) -> np.ndarray:
        """∂δ_axis/∂w (N, r) rad from the unit torques (N, 6, 6, 4) of ``gravity_basis``."""
        return unit[:, self.axis - 1].reshape(len(unit), 24) @ self.basis


def harmonic_name(axis: int, order: int) -> str:
    """The group name of a reducer harmonic, e.g. 'A2 k7'."""
    return f"A{axis} k{order}"


def reference_joints(robot: Robot, count: int, seed: int = 0) -> np.ndarray:
    """A fixed spread-out set of ``count`` joint vectors (rad) inside the limits, A5 away from 0."""
    rng = np.random.default_rng(seed)
    lo, hi = np.radians(robot.joint_limits_deg).T
    lo, hi = np.maximum(lo, -np.pi), np.minimum(hi, np.pi)
    q = lo + rng.random((count, 6)) * (hi - lo)
    q[:, 4] = np.where(np.abs(q[:, 4]) < 0.3, 0.3, q[:, 4])
    return q


def gravity_axes(unit: np.ndarray) -> tuple[int, ...]:
    """The axes 1..6 that gravity loads at the joints of the unit torques ``unit`` (P, 6, 6, 4)
    (``gravity_basis``): every axis whose direction is not parallel to gravity at those poses
    (an axis along gravity, e.g. a floor-mounted arm's A1, carries no gravity torque)."""
    scale = np.sqrt(np.mean(unit**2, axis=(0, 2, 3)))  # (6,)
    return tuple(int(a) + 1 for a in np.flatnonzero(scale > _RTOL * scale.max()))


def gravity_terms(robot: Robot) -> tuple[GravityTerm, ...]:
    """The gravity groups of ``robot``'s nominal geometry, axis by axis, part by part (parts
    that add no new torque function, e.g. the upper arm on A3, are left out)."""
    q = reference_joints(robot, _REFERENCE_POSES)
    unit = gravity_basis(robot.dh, q, GRAVITY_MPS2)  # (P, 6, 6, 4)
    terms = []
    for axis in gravity_axes(unit):
        table = unit[:, axis - 1].reshape(len(q), 24)
        scale = np.sqrt(np.mean(table**2, axis=0))
        top = scale.max()
        spanned = np.zeros((len(q), 0))  # orthonormal torque functions of the parts before
        for part, quantities in GRAVITY_PARTS.items():
            cols = np.array([4 * (link - 1) + u for link, u in quantities])
            cols = cols[scale[cols] > _RTOL * top]
            if cols.size == 0:
                continue
            scaled = table[:, cols] / scale[cols]
            rest = scaled - spanned @ (spanned.T @ scaled)
            u_, sing, vt = np.linalg.svd(rest, full_matrices=False)
            rank = int(np.sum(sing > _NEW * np.sqrt(len(q))))
            if rank == 0:
                continue
            basis = np.zeros((24, rank))
            # the rest's orthonormal functions u_ = rest @ vt.T / sing; in the part's columns
            # they are the moments vt.T / sing / scale, minus what the parts before already give
            # (their span is added back by those parts' own parameters in the fit)
            basis[cols] = vt[:rank].T / sing[:rank] / scale[cols, None] * np.sqrt(len(q))
            terms.append(GravityTerm(axis, part, basis))
            spanned = np.column_stack([spanned, u_[:, :rank]])
    return tuple(terms)
