"""How far a TCP orientation is from the one a grid was measured at.

The grid's errors hold for the orientation it was measured at (the seed keeps it constant), so a
point commanded at another orientation gets a less trustworthy correction. The distance between
two orientations is the angle of the relative rotation R_a^T R_b (0..180 deg).
"""

from __future__ import annotations

import numpy as np

from accugrid.kinematics.frames import abc_to_matrix


def rotation_angle_deg(abc_deg: np.ndarray, reference_abc_deg: np.ndarray) -> np.ndarray:
    """Angle (N,) deg of the rotation between each KUKA a,b,c (N, 3) deg and one reference (3,)."""
    rot = abc_to_matrix(np.atleast_2d(np.asarray(abc_deg, dtype=float)))
    ref = abc_to_matrix(np.asarray(reference_abc_deg, dtype=float))
    # trace(R_ref^T R) = sum of the element-wise product
    trace = np.einsum("ij,nij->n", ref, rot)
    return np.degrees(np.arccos(np.clip((trace - 1.0) / 2.0, -1.0, 1.0)))
