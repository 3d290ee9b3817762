"""Where a calibrated model has support: the prediction leverage of a target among the poses the
model was identified from, and the DH-only fit of the same poses that corrects targets without.

A model with joint-error terms (reducer harmonics, gravity groups) can fit its calibration poses
well and still miss elsewhere in joint space, inside every per-joint range
(``kinematics.validity``): the terms trade off against each other in joint combinations the poses
never showed. The leverage of a target with joints q is

    h(q) = trace(J(q) (Jᵀ J)⁺ J(q)ᵀ),

J(q) (3, p) the model's position Jacobian in its parameters there (``identification_jacobian``:
DH errors, TCP, tracker frame, the chosen joint-error terms), Jᵀ J summed over the distinct
calibration poses and ⁺ its pseudo-inverse in the identifiable directions: the variance of the
model's prediction at q in units of the measurement noise. Its yardstick comes from the poses
themselves: a pose left out of its own fit has the leave-one-out leverage h/(1-h) (block form
trace(H (I - H)⁻¹), H the pose's (3, 3) hat block), which is what a new target drawn like the
calibration poses gets. A target whose leverage exceeds the largest leave-one-out leverage of the
calibration poses (``ratio`` > 1) lies where the model extrapolates: it has no support.

``accugrid identify`` records both in the calibrated YAML (``identification.support``, written by
``support_section``, the only writer):

- ``parameters``: the names of the Jacobian's columns (``identification.parameter_names``);
- ``leverage_map``: (k, p) rows W with h(q) = |W J(q)ᵀ|² (the whitened inverse of Jᵀ J in its k
  identifiable directions), 7 significant digits;
- ``loo_leverage_max``: the largest leave-one-out leverage of the calibration poses; ``poses``;
- ``fallback``: the DH-only fit of the same poses (``errors``: six rows Δa mm, Δd mm, Δα rad,
  Δθ rad; ``tool``: its TCP x, y, z mm, a, b, c deg; with a tracker frame identified, that fit's
  ``tracker_T_robot``), which corrects the targets without support (``Support.fallback``): it
  holds no term that the poses pin only in their own joint combinations.

The correction policy (``compensation.policy``) flags targets without support and corrects them
with the fallback (``--strict``: refuses them).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from accugrid.infra.yamlfile import YamlDoc
from accugrid.kinematics.calibrated import pose_dict
from accugrid.kinematics.candidates import GravityTerm
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.identification import (
    RTOL,
    Identification,
    identification_jacobian,
    parameter_names,
)
from accugrid.kinematics.robot import ERROR_KEYS, Robot

__all__ = ["SECTION", "SUPPORT_SCHEMA", "Structure", "Support", "support_section"]

SECTION = ("identification", "support")
SUPPORT_SCHEMA = {
    "parameters": None,
    "leverage_map": None,
    "loo_leverage_max": None,
    "poses": None,
    "fallback": {
        "errors": [dict.fromkeys(ERROR_KEYS)],
        "tool": dict.fromkeys("xyzabc"),
        "tracker_T_robot": dict.fromkeys("xyzabc"),
    },
}
_DIGITS = 7  # significant digits of the leverage map in the file


@dataclass(frozen=True)
class Structure:
    """The parameters a model was identified with (``identification.identify``'s options)."""

    base_frame: bool = False
    compliance: bool = False
    harmonics: tuple[tuple[int, int], ...] = ()
    gravity: tuple[GravityTerm, ...] = ()

    @property
    def names(self) -> list[str]:
        return parameter_names(self.base_frame, self.compliance, self.harmonics, self.gravity)

    def jacobian(self, robot: Robot, q: np.ndarray) -> np.ndarray:
        """(N, 3, p) mm per parameter unit at joints q (N, 6) rad, at the nominal parameters of
        ``robot`` (its DH table, tool and gravity model)."""
        return identification_jacobian(
            robot,
            q,
            base_frame=self.base_frame,
            compliance=self.compliance,
            harmonics=self.harmonics,
            gravity=self.gravity,
        )


def _whitened(jac: np.ndarray) -> np.ndarray:
    """W (k, p) with |W j|² = j (Jᵀ J)⁺ jᵀ for rows J (M, p), in the directions whose singular
    value (columns scaled to unit RMS) is at least ``RTOL`` times the largest."""
    scale = np.sqrt(np.mean(jac**2, axis=0))
    scale[scale == 0] = 1.0
    _, s, vt = np.linalg.svd(jac / scale, full_matrices=False)
    keep = s > RTOL * s[0]
    return vt[keep] / s[keep, None] / scale


def _hat_blocks(w: np.ndarray, jac: np.ndarray) -> np.ndarray:
    """(N, 3, 3) J(q) (Jᵀ J)⁺ J(q)ᵀ of Jacobians jac (N, 3, p)."""
    z = np.einsum("kp,nap->nak", w, jac)
    return np.einsum("nak,nbk->nab", z, z)


@dataclass(frozen=True)
class Support:
    """A model's support (module docstring): its ``structure`` and nominal ``robot`` (the
    Jacobian's), the leverage map W (k, p), the largest leave-one-out leverage of its poses and
    the DH-only ``fallback`` (a calibrated robot: its ``true_robot()`` the DH-only arm, its tool
    that fit's TCP) and that fit's tracker frame (4, 4) mm (None: not identified)."""

    structure: Structure
    robot: Robot
    leverage_map: np.ndarray
    loo_max: float
    fallback: Robot
    fallback_frame: np.ndarray | None = None

    def leverage(self, q: np.ndarray) -> np.ndarray:
        """h (N,) of targets with joints q (N, 6) rad (noise units; NaN rows give NaN)."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        if not len(q):
            return np.zeros(0)
        blocks = _hat_blocks(self.leverage_map, self.structure.jacobian(self.robot, q))
        return np.einsum("naa->n", blocks)

    def ratio(self, q: np.ndarray) -> np.ndarray:
        """h (N,) over the calibration poses' largest leave-one-out leverage: above 1, no
        support."""
        return self.leverage(q) / self.loo_max

    @classmethod
    def from_doc(cls, doc: YamlDoc, robot: Robot, structure: Structure) -> Support | None:
        """The ``identification.support`` section of a calibrated file (``robot`` loaded from
        it, ``structure`` the terms it was fitted with), None without one; InputError at a bad
        key or value, or when its columns are not those of ``structure``."""
        if not doc.has(*SECTION):
            return None
        key = SECTION
        doc.check_keys(SUPPORT_SCHEMA, *key)
        names = [str(n) for n in doc.sequence(*key, "parameters")]
        if names != structure.names:
            raise doc.error(
                f"{doc.keyname(*key, 'parameters')} are not the parameters of the model's "
                "terms: the file was edited or written by another version",
                *key,
                "parameters",
            )
        rows = doc.sequence(*key, "leverage_map")
        try:
            w = np.array(rows, dtype=float)
        except (TypeError, ValueError):
            w = np.zeros((0, 0))
        if w.ndim != 2 or w.shape[1] != len(names) or not np.isfinite(w).all() or not len(w):
            raise doc.error(
                f"{doc.keyname(*key, 'leverage_map')} must be rows of {len(names)} numbers",
                *key,
                "leverage_map",
            )
        loo = doc.number(*key, "loo_leverage_max")
        if not loo > 0:
            raise doc.error(f"{doc.keyname(*key, 'loo_leverage_max')} must be > 0", *key)
        fb = (*key, "fallback")
        doc.sequence(*fb, "errors", length=6)
        errors = np.array([[doc.number(*fb, "errors", i, k) for k in ERROR_KEYS] for i in range(6)])
        tool = pose_from_xyzabc([doc.number(*fb, "tool", k) for k in "xyzabc"])
        fallback = replace(
            robot, errors=errors, joint_errors=None, fk_joint_errors=None, flange_T_tool=tool
        )
        frame = None
        if doc.has(*fb, "tracker_T_robot"):
            frame = pose_from_xyzabc([doc.number(*fb, "tracker_T_robot", k) for k in "xyzabc"])
        return cls(structure, robot, w, loo, fallback, frame)


def support_section(
    calibrated: Robot, q: np.ndarray, group: np.ndarray, structure: Structure, dh: Identification
) -> dict:
    """The ``identification.support`` mapping (module docstring) of a model ``calibrated``
    (its nominal DH and identified TCP give the Jacobian) identified with ``structure`` from
    joints q (N, 6) rad whose rows belong to distinct poses ``group`` (N,) int, and ``dh``, the
    DH-only identification of the same poses; plain YAML data."""
    _, first = np.unique(group, return_index=True)
    jac = structure.jacobian(calibrated, q[first])  # one row triple per distinct pose
    w = _whitened(jac.reshape(-1, jac.shape[2]))
    hat = _hat_blocks(w, jac)
    loo = np.einsum("nab,nba->n", hat, np.linalg.inv(np.eye(3) - hat))
    rounded = [[float(f"{v:.{_DIGITS}g}") for v in row] for row in w]
    frame = dh.tracker_T_robot
    return {
        "parameters": structure.names,
        "leverage_map": rounded,
        "loo_leverage_max": float(loo.max()),
        "poses": len(first),
        "fallback": {
            "errors": [
                {k: float(v) for k, v in zip(ERROR_KEYS, row, strict=True)}
                for row in dh.robot.errors
            ],
            "tool": pose_dict(dh.robot.flange_T_tool),
            **({} if frame is None else {"tracker_T_robot": pose_dict(frame)}),
        },
    }
