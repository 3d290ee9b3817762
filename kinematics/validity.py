"""Where a calibrated model holds: the region, tool tilt and joint ranges of the poses it was
identified from, and the error its identification validated.

``accugrid identify`` records them in the calibrated YAML (``identification.validity``, written
by ``validity_section``, the only writer); the correction policy (``compensation.policy``) reads
them back (``Validity.from_doc``) and measures how far each target lies outside
(``Validity.excess``). Keys, all in the robot frame:

- ``box_min_mm``, ``box_max_mm``: [x, y, z] the bounding box of the identification's commanded
  TCP positions, mm;
- ``tool_axis``: [i, j, k] the mean tool Z direction of its poses (unit), ``tilt_deg``: the
  largest angle of a pose's tool Z from it, deg;
- ``joints_deg``: six [min, max] ranges of the axes A1..A6 over its poses, KUKA deg;
- ``validated_max_mm``: {x, y, z} the largest error the identification validated per axis, mm
  (cross-validated held-out max, else the fit's residual max).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from accugrid.infra.yamlfile import YamlDoc
from accugrid.kinematics.robot import VALIDITY_KEYS

if TYPE_CHECKING:
    from accugrid.kinematics.support import Support

__all__ = ["SECTION", "Validity", "validity_section"]

SECTION = ("identification", "validity")
_EPS = 1e-6  # mm / deg: this close to a bound still counts as inside


@dataclass(frozen=True)
class Validity:
    """The poses' region: box lower, upper (3,) mm; tool_axis (3,) unit; tilt_deg; joints_deg
    (6, 2) KUKA deg; validated_max_mm (3,) mm or None; ``support``: the model's leverage among
    its poses and its DH-only fallback (``kinematics.support``; None: no record)."""

    lower: np.ndarray
    upper: np.ndarray
    tool_axis: np.ndarray
    tilt_deg: float
    joints_deg: np.ndarray
    validated_max_mm: np.ndarray | None = None
    support: Support | None = None

    @classmethod
    def of_poses(
        cls,
        commanded: np.ndarray,
        rotations: np.ndarray,
        q: np.ndarray,
        validated_max_mm: np.ndarray | None = None,
    ) -> Validity:
        """From the identification's commanded positions (N, 3) mm, orientations (N, 3, 3) and
        joints q (N, 6) rad, robot frame."""
        z = np.asarray(rotations, dtype=float)[:, :, 2]
        mean = z.mean(axis=0)
        axis = mean / np.linalg.norm(mean) if np.linalg.norm(mean) > 1e-9 else np.array([0, 0, 1.0])
        tilt = np.degrees(np.arccos(np.clip(z @ axis, -1.0, 1.0)))
        deg = np.degrees(np.asarray(q, dtype=float))
        return cls(
            np.min(commanded, axis=0),
            np.max(commanded, axis=0),
            axis,
            float(tilt.max(initial=0.0)),
            np.column_stack([deg.min(axis=0), deg.max(axis=0)]),
            None if validated_max_mm is None else np.asarray(validated_max_mm, dtype=float),
        )

    @classmethod
    def from_doc(cls, doc: YamlDoc) -> Validity | None:
        """The ``identification.validity`` section of a calibrated file, None without one;
        InputError at an unknown key (a misspelt one would silently drop a bound)."""
        if not doc.has(*SECTION):
            return None
        key = SECTION
        doc.check_keys(dict.fromkeys(VALIDITY_KEYS), *key)
        lower = np.array([doc.number(*key, "box_min_mm", i) for i in range(3)])
        upper = np.array([doc.number(*key, "box_max_mm", i) for i in range(3)])
        axis = np.array([doc.number(*key, "tool_axis", i) for i in range(3)])
        if abs(np.linalg.norm(axis) - 1.0) > 1e-6:
            raise doc.error(f"{doc.keyname(*key, 'tool_axis')} must be a unit vector", *key)
        if (lower > upper).any():
            raise doc.error(f"{doc.keyname(*key, 'box_min_mm')} must not exceed box_max_mm", *key)
        doc.sequence(*key, "joints_deg", length=6)
        joints = np.array(
            [[doc.number(*key, "joints_deg", i, j) for j in range(2)] for i in range(6)]
        )
        error = None
        if doc.has(*key, "validated_max_mm"):
            error = np.array([doc.number(*key, "validated_max_mm", a) for a in "xyz"])
        return cls(lower, upper, axis, doc.number(*key, "tilt_deg"), joints, error)

    def excess(
        self, points: np.ndarray, rotations: np.ndarray | None, q: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """How far targets lie outside: distance (N,) mm of points (N, 3) mm from the box;
        tilt (N,) deg of their tool Z (rotations (N, 3, 3), robot frame) beyond ``tilt_deg``;
        the largest joint excess (N,) deg of q (N, 6) rad beyond the ranges and its axis (N,)
        1..6 (0: none). Zero where inside (and where rotations or q are None or NaN)."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        n = len(points)
        gap = np.maximum(self.lower - points, 0.0) + np.maximum(points - self.upper, 0.0)
        box = np.sqrt(np.einsum("ij,ij->i", gap, gap))
        tilt = np.zeros(n)
        if rotations is not None:
            cos = np.clip(np.asarray(rotations)[:, :, 2] @ self.tool_axis, -1.0, 1.0)
            tilt = np.nan_to_num(np.degrees(np.arccos(cos)) - self.tilt_deg).clip(min=0.0)
        joint, axis = np.zeros(n), np.zeros(n, np.int64)
        if q is not None:
            deg = np.degrees(np.asarray(q, dtype=float))
            over = np.maximum(self.joints_deg[:, 0] - deg, 0.0) + np.maximum(
                deg - self.joints_deg[:, 1], 0.0
            )
            over = np.nan_to_num(over)
            joint = over.max(axis=1)
            axis = np.where(joint > _EPS, over.argmax(axis=1) + 1, 0)
        box[box <= _EPS], tilt[tilt <= _EPS], joint[joint <= _EPS] = 0.0, 0.0, 0.0
        return box, tilt, joint, axis


def validity_section(
    commanded: np.ndarray,
    rotations: np.ndarray,
    q: np.ndarray,
    validated_max_mm: np.ndarray | None,
) -> dict:
    """The ``identification.validity`` mapping (module docstring) of an identification's poses:
    commanded (N, 3) mm, rotations (N, 3, 3), q (N, 6) rad, robot frame; plain YAML data."""
    v = Validity.of_poses(commanded, rotations, q, validated_max_mm)
    out = {
        "box_min_mm": [float(x) for x in v.lower],
        "box_max_mm": [float(x) for x in v.upper],
        "tool_axis": [float(x) for x in v.tool_axis],
        "tilt_deg": float(v.tilt_deg),
        "joints_deg": [[float(lo), float(hi)] for lo, hi in v.joints_deg],
    }
    if v.validated_max_mm is not None:
        out["validated_max_mm"] = {
            a: float(x) for a, x in zip("xyz", v.validated_max_mm, strict=True)
        }
    return out
