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
calibration poses lies where the model extrapolates.

Leverage trusts the model's own form: a harmonic term is periodic, so the linearised model sees
no risk at an angle its poses never reached if other angles pinned its coefficients, while a
fitted high order extrapolates whatever it was fitted to. The second measure asks only the
poses: the distance of a target's joints to the nearest calibration pose, in TCP millimetres,

    d(q, q') = sqrt(sum_i (lever_i · 2 sin((q_i - q'_i) / 2))²),

lever_i (mm/rad) the RMS over the calibration poses of |∂p/∂A_i| (each joint's effect on the TCP;
the chord keeps angles periodic). Its yardstick is the largest distance of a calibration pose to
its nearest other one. A target beyond either yardstick (``ratio`` > 1) has no support.

``accugrid identify`` records both in the calibrated YAML (``identification.support``, written by
``support_section``, the only writer):

- ``parameters``: the names of the Jacobian's columns (``identification.parameter_names``);
- ``loo_leverage_max``: the largest leave-one-out leverage of the calibration poses;
- ``joints_deg``: (n, 6) the distinct calibration poses' joints, the robot's deg, 3 decimals,
  each row one text of numbers separated by blanks (a file of 3,000 poses stays quick to read);
  the leverage map W (k, p), h(q) = |W J(q)ᵀ|² (the whitened inverse of Jᵀ J in its k
  identifiable directions), is computed from them when the file is read: any O W with O
  orthogonal serves, so its numbers (the SVD's basis) would differ between CPUs in a file;
  ``lever_mm_per_rad``: (6,) the levers; ``loo_distance_max_mm``: the largest nearest-pose
  distance among them, mm;
- ``fallback``: the DH-only fit of the same poses (``errors``: six rows Δa mm, Δd mm, Δα rad,
  Δθ rad; ``tool``: its TCP x, y, z mm, a, b, c deg; with a tracker frame identified, that fit's
  ``tracker_T_robot``), which corrects the targets without support (``Support.fallback``): it
  holds no term that the poses pin only in their own joint combinations; with that fit's k-fold
  held-out RMS per axis, ``sigma_mm``: the error budget of the positions it corrects is
  sigma² (I + H_fb(q)), H_fb that fit's prediction leverage among the same poses
  (``fallback_map``; ``compensation.budget``; a file without the key leaves their bound
  unknown).

The correction policy (``compensation.policy``) flags targets without support and corrects them
with the fallback (``--strict``: refuses them).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
from scipy.spatial import cKDTree

from accugrid.infra.yamlfile import YamlDoc
from accugrid.kinematics.calibrated import axes_dict, pose_dict
from accugrid.kinematics.candidates import GravityTerm
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.identification import (
    RTOL,
    Identification,
    identification_jacobian,
    parameter_names,
)
from accugrid.kinematics.robot import ERROR_KEYS, Robot

__all__ = [
    "SECTION",
    "SUPPORT_SCHEMA",
    "Structure",
    "Support",
    "hat_blocks",
    "number_rows",
    "row_texts",
    "support_section",
    "whitened",
]

SECTION = ("identification", "support")
SUPPORT_SCHEMA = {
    "parameters": None,
    "loo_leverage_max": None,
    "joints_deg": None,
    "lever_mm_per_rad": None,
    "loo_distance_max_mm": None,
    "fallback": {
        "errors": [dict.fromkeys(ERROR_KEYS)],
        "tool": dict.fromkeys("xyzabc"),
        "tracker_T_robot": dict.fromkeys("xyzabc"),
        "sigma_mm": dict.fromkeys("xyz"),
    },
}
_BLOCK = 4096  # targets per Jacobian block


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


def whitened(jac: np.ndarray) -> np.ndarray:
    """W (k, p) with |W j|² = j (Jᵀ J)⁺ jᵀ for rows J (M, p), in the directions whose singular
    value (columns scaled to unit RMS) is at least ``RTOL`` times the largest."""
    scale = np.sqrt(np.mean(jac**2, axis=0))
    scale[scale == 0] = 1.0
    _, s, vt = np.linalg.svd(jac / scale, full_matrices=False)
    keep = s > RTOL * s[0]
    return vt[keep] / s[keep, None] / scale


def _embedded(q: np.ndarray, lever: np.ndarray) -> np.ndarray:
    """(N, 12) points whose Euclidean distances are d(q, q') (module docstring), mm, of joints
    q (N, 6) rad and levers (6,) mm/rad."""
    return np.concatenate([lever * np.cos(q), lever * np.sin(q)], axis=1)


def hat_blocks(w: np.ndarray, jac: np.ndarray) -> np.ndarray:
    """(N, 3, 3) J(q) (Jᵀ J)⁺ J(q)ᵀ of Jacobians jac (N, 3, p)."""
    z = np.einsum("kp,nap->nak", w, jac)
    return np.einsum("nak,nbk->nab", z, z)


@dataclass(frozen=True)
class Support:
    """A model's support (module docstring): its ``structure`` and nominal ``robot`` (the
    Jacobian's), the leverage map W (k, p), the largest leave-one-out leverage of its poses,
    their joints (n, 6) rad, the levers (6,) mm/rad, their largest nearest-pose distance mm, the
    DH-only ``fallback`` (a calibrated robot: its ``true_robot()`` the DH-only arm, its tool that
    fit's TCP), that fit's tracker frame (4, 4) mm (None: not identified) and its held-out RMS
    (3,) mm per axis (None: not recorded)."""

    structure: Structure
    robot: Robot
    leverage_map: np.ndarray
    loo_max: float
    joints: np.ndarray
    lever: np.ndarray
    loo_distance_mm: float
    fallback: Robot
    fallback_frame: np.ndarray | None = None
    fallback_sigma_mm: np.ndarray | None = None

    @cached_property
    def fallback_structure(self) -> Structure:
        """The DH-only fallback's parameters: DH errors, TCP (and the tracker frame)."""
        return Structure(base_frame=self.structure.base_frame)

    @cached_property
    def fallback_map(self) -> np.ndarray:
        """The DH-only fit's leverage map (k, p) among the calibration poses, as
        ``leverage_map`` is the model's."""
        jac = self.fallback_structure.jacobian(self.robot, self.joints)
        return whitened(jac.reshape(-1, jac.shape[2]))

    @cached_property
    def _tree(self) -> cKDTree:
        return cKDTree(_embedded(self.joints, self.lever))

    def distance(self, q: np.ndarray) -> np.ndarray:
        """d (N,) mm from targets with joints q (N, 6) rad to the nearest calibration pose."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        return self._tree.query(_embedded(q, self.lever))[0] if len(q) else np.zeros(0)

    def leverage(self, q: np.ndarray) -> np.ndarray:
        """h (N,) of targets with joints q (N, 6) rad (noise units; NaN rows give NaN), in
        blocks of ``_BLOCK`` targets (the Jacobian is (block, 3, p))."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        out = np.empty(len(q))
        for lo in range(0, len(q), _BLOCK):
            jac = self.structure.jacobian(self.robot, q[lo : lo + _BLOCK])
            out[lo : lo + _BLOCK] = np.einsum("naa->n", hat_blocks(self.leverage_map, jac))
        return out

    def ratio(self, q: np.ndarray) -> np.ndarray:
        """(N,) the larger of h over the calibration poses' largest leave-one-out leverage and
        d over their largest nearest-pose distance: above 1, no support."""
        return np.maximum(self.leverage(q) / self.loo_max, self.distance(q) / self.loo_distance_mm)

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
        loo, far = (doc.number(*key, k) for k in ("loo_leverage_max", "loo_distance_max_mm"))
        if not (loo > 0 and far > 0):
            raise doc.error("loo_leverage_max and loo_distance_max_mm must be > 0", *key)
        joints = number_rows(doc, (*key, "joints_deg"), 6)
        jac = structure.jacobian(robot, np.radians(joints))
        w = whitened(jac.reshape(-1, jac.shape[2]))
        doc.sequence(*key, "lever_mm_per_rad", length=6)
        lever = np.array([doc.number(*key, "lever_mm_per_rad", i) for i in range(6)])
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
        sigma = None
        if doc.has(*fb, "sigma_mm"):
            sigma = np.array([doc.number(*fb, "sigma_mm", k) for k in "xyz"])
            if not (sigma >= 0).all():
                raise doc.error("sigma_mm must be >= 0", *fb, "sigma_mm")
        joints = np.radians(joints)
        return cls(structure, robot, w, loo, joints, lever, far, fallback, frame, sigma)


def number_rows(doc: YamlDoc, key: tuple, width: int) -> np.ndarray:
    """The numbers (n, width) at ``key``: a list of rows, each a text of ``width`` numbers
    separated by blanks; InputError naming the key unless so and finite."""
    value = doc.get(*key)
    try:
        rows = np.array([np.array(str(r).split(), dtype=float) for r in value])
    except (TypeError, ValueError):
        rows = np.zeros((0, 0))
    if rows.ndim != 2 or rows.shape[1] != width or not len(rows) or not np.isfinite(rows).all():
        raise doc.error(f"{doc.keyname(*key)} must be rows of {width} numbers", *key)
    return rows


def row_texts(rows: np.ndarray, form: str) -> list[str]:
    """Rows (n, m) as texts of m numbers in ``form`` (a format spec) separated by blanks."""
    return [" ".join(format(float(v), form) for v in row) for row in rows]


def support_section(
    calibrated: Robot, q: np.ndarray, group: np.ndarray, structure: Structure, dh: Identification
) -> dict:
    """The ``identification.support`` mapping (module docstring) of a model ``calibrated``
    (its nominal DH and identified TCP give the Jacobian) identified with ``structure`` from
    joints q (N, 6) rad whose rows belong to distinct poses ``group`` (N,) int, and ``dh``, the
    DH-only identification of the same poses (run with folds: its held-out RMS is the budget of
    the positions it corrects); plain YAML data."""
    _, first = np.unique(group, return_index=True)
    joints = np.round(np.degrees(q[first]), 3)  # as the file holds them, the map computed from
    jac = structure.jacobian(calibrated, np.radians(joints))  # one row triple per distinct pose
    w = whitened(jac.reshape(-1, jac.shape[2]))
    hat = hat_blocks(w, jac)
    loo = np.einsum("nab,nba->n", hat, np.linalg.inv(np.eye(3) - hat))
    theta = [4 * i + 3 for i in range(6)]  # the Δθ columns: ∂p/∂A_i up to the axis' sign
    lever = np.sqrt(np.mean(np.sum(jac[:, :, theta] ** 2, axis=1), axis=0))
    points = _embedded(np.radians(joints), lever)
    nearest = cKDTree(points).query(points, k=2)[0][:, 1]  # the nearest other pose
    frame, held = dh.tracker_T_robot, dh.cross_validation
    return {
        "parameters": structure.names,
        "loo_leverage_max": float(loo.max()),
        "joints_deg": row_texts(joints, ".3f"),
        "lever_mm_per_rad": [float(v) for v in lever],
        "loo_distance_max_mm": float(nearest.max()),
        "fallback": {
            "errors": [
                {k: float(v) for k, v in zip(ERROR_KEYS, row, strict=True)}
                for row in dh.robot.errors
            ],
            "tool": pose_dict(dh.robot.flange_T_tool),
            **({} if frame is None else {"tracker_T_robot": pose_dict(frame)}),
            **({} if held is None else {"sigma_mm": axes_dict(held.rms_mm)}),
        },
    }
