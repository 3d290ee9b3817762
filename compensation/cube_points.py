"""Test points of a cube after GB/T 12642-2001 / ISO 9283:1998 and the seed (Sec. 4.3, Fig. 8-9).

Vertex numbering (seed Fig. 8 is not reproduced in the text; this numbering is the one for which
the seed's four measuring planes C1-C2-C7-C8, C2-C3-C8-C5, C3-C4-C5-C6 and C4-C1-C6-C7 are the
cube's four diagonal planes, each holding one edge and the opposite parallel edge)::

        C8 -------- C7          z
        /|          /|          |  y
      C5 -------- C6 |          | /
       | C4 ------|- C3         |/____ x
       |/         | /
      C1 -------- C2

C1 = (xmin, ymin, zmin), C2 = (xmax, ymin, zmin), C3 = (xmax, ymax, zmin), C4 = (xmin, ymax, zmin)
and C5..C8 straight above C1..C4. The diagonals of every measuring plane are space diagonals of
the cube (C1-C7, C2-C8 in plane C1-C2-C7-C8; C3-C5, C4-C6 in plane C3-C4-C5-C6), of length
L = step * sqrt(3).

Standard positions (ISO 9283:1998 §7.2.1, taken over by GB/T 12642-2001): P1 is the centre of the
cube (the intersection of the diagonals); P2..P5 lie on the diagonals of the measuring plane
C1-C2-C7-C8 at 0.1 * L from the diagonal ends. The seed adds P6..P9 at the same distance on the
other two space diagonals, so that all four diagonals are sampled:

    P2 near C1, P3 near C2, P4 near C7, P5 near C8   (diagonals C1-C7 and C2-C8)
    P6 near C3, P7 near C4, P8 near C5, P9 near C6   (diagonals C3-C5 and C4-C6)

A point at 0.1 * L from corner C along its space diagonal is C + 0.1 * (C_opposite - C), i.e. the
corner pulled 20 % of the way towards the centre.
"""

from __future__ import annotations

import numpy as np

from accugrid.infra.errors import InputError

__all__ = ["DIAGONAL_FRACTION", "TEST_LABELS", "VERTEX_LABELS", "cube_test_points", "cube_vertices"]

#: Fraction of the diagonal length between a diagonal end and its test point (ISO 9283 §7.2.1).
DIAGONAL_FRACTION = 0.1

VERTEX_LABELS = tuple(f"C{i}" for i in range(1, 9))
TEST_LABELS = tuple(f"P{i}" for i in range(1, 10))

# Unit-cube corners in units of the half step, in the order C1..C8.
_CORNER_SIGNS = np.array(
    [
        [-1, -1, -1],
        [1, -1, -1],
        [1, 1, -1],
        [-1, 1, -1],
        [-1, -1, 1],
        [1, -1, 1],
        [1, 1, 1],
        [-1, 1, 1],
    ],
    dtype=float,
)
# The corner (0-based vertex index) each of P2..P9 is close to.
_TEST_CORNERS = np.array([0, 1, 6, 7, 2, 3, 4, 5])


def _check(centres: np.ndarray, steps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    centres = np.asarray(centres, dtype=float)
    steps = np.asarray(steps, dtype=float)
    if centres.ndim != 2 or centres.shape[1] != 3:
        raise InputError(f"cube centres must be (N, 3) mm, got shape {centres.shape}")
    steps = np.broadcast_to(steps, (centres.shape[0],))
    if not np.all(np.isfinite(centres)) or not np.all(np.isfinite(steps)):
        raise InputError("cube centres and steps must be finite numbers")
    if np.any(steps <= 0):
        raise InputError(f"cube step must be > 0 mm, got {steps[steps <= 0][0]:g}")
    return centres, steps


def cube_vertices(centres: np.ndarray, steps: np.ndarray | float) -> np.ndarray:
    """Vertices C1..C8 of axis-aligned cubes: centres (N, 3) mm, steps (N,) or scalar edge
    length in mm -> (N, 8, 3) mm."""
    centres, steps = _check(centres, steps)
    return centres[:, None, :] + 0.5 * steps[:, None, None] * _CORNER_SIGNS[None, :, :]


def cube_test_points(centres: np.ndarray, steps: np.ndarray | float) -> np.ndarray:
    """Test points P1..P9 of axis-aligned cubes: centres (N, 3) mm, steps (N,) or scalar edge
    length in mm -> (N, 9, 3) mm (P1 = centre, P2..P9 as in the module docstring)."""
    centres, steps = _check(centres, steps)
    corners = cube_vertices(centres, steps)[:, _TEST_CORNERS, :]
    # C + f * (C_opposite - C) with C_opposite = 2 * centre - C.
    near = corners + DIAGONAL_FRACTION * 2.0 * (centres[:, None, :] - corners)
    return np.concatenate([centres[:, None, :], near], axis=1)
