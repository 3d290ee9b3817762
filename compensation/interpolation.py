"""Interpolation kernels over the 8 vertices of a regular-grid cell.

Corner c (0..7) of a cell is vertex (i + bx, j + by, k + bz) with c = 4 bx + 2 by + bz.
Cell rule: a point belongs to cell floor((p - origin) / step) clipped to [0, n - 2] per axis, so a
point on a face shared by two cells goes to the upper cell, and the upper boundary of the grid to
the last cell. ``frac`` is the local coordinate in the cell, 0..1 per axis inside the grid.

- IDW (seed Eq. 12-13): q_i = s_i^-p / sum_j s_j^-p, s_i the distance (mm) to corner i. At a
  vertex (s_i = 0) the weight is exactly 1 there and 0 elsewhere. Not continuous across faces.
- Trilinear: q_i = prod over axes of (f or 1 - f); continuous across faces.
"""

from __future__ import annotations

import numpy as np

# corner bits (8, 3): bx, by, bz of corner c = 4 bx + 2 by + bz
CORNERS = np.array([[c >> 2 & 1, c >> 1 & 1, c & 1] for c in range(8)])
_HIT = 1e-12  # a distance below this fraction of the smallest step counts as "at the vertex"


def locate(
    points: np.ndarray, origin: np.ndarray, step: np.ndarray, counts: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Enclosing cell (N, 3) int64 and local coordinates frac (N, 3) of points (N, 3) mm."""
    t = (points - origin) / step
    cell = np.floor(t)
    np.clip(cell, 0, counts - 2, out=cell)
    return cell.astype(np.int64), t - cell


def idw_weights(frac: np.ndarray, step: np.ndarray, power: float = 1.0) -> np.ndarray:
    """Inverse-distance weights (N, 8) of the cell corners for local coordinates frac (N, 3)."""
    near = np.square(frac * step)  # squared distance to the lower corner, per axis
    far = np.square((1.0 - frac) * step)
    pair = np.stack((near, far), axis=1)  # (N, 2, 3): index 1 = upper corner (b = 1)
    d2 = (
        pair[:, :, None, None, 0] + pair[:, None, :, None, 1] + pair[:, None, None, :, 2]
    ).reshape(-1, 8)
    hit = d2 <= (_HIT * float(np.min(step))) ** 2
    with np.errstate(divide="ignore"):
        inv = 1.0 / np.sqrt(d2) if power == 1.0 else d2 ** (-0.5 * power)
    at_vertex = hit.any(axis=1)
    if at_vertex.any():
        inv[at_vertex] = hit[at_vertex]
    inv /= inv.sum(axis=1, keepdims=True)
    return inv


def trilinear_weights(frac: np.ndarray) -> np.ndarray:
    """Trilinear weights (N, 8) of the cell corners for local coordinates frac (N, 3)."""
    pair = np.stack((1.0 - frac, frac), axis=1)  # (N, 2, 3)
    return (
        pair[:, :, None, None, 0] * pair[:, None, :, None, 1] * pair[:, None, None, :, 2]
    ).reshape(-1, 8)


def corner_indices(cell: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Flat vertex indices (N, 8) of the corners of cells (N, 3); vertices in C order."""
    ny, nz = int(counts[1]), int(counts[2])
    base = (cell[:, 0] * ny + cell[:, 1]) * nz + cell[:, 2]
    offsets = (CORNERS[:, 0] * ny + CORNERS[:, 1]) * nz + CORNERS[:, 2]
    return base[:, None] + offsets


def blend(values: np.ndarray, corners: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Sum of weights (N, 8) times per-vertex values (3, M) at corners (N, 8) -> (N, 3)."""
    out = np.empty((len(corners), 3))
    for axis in range(3):
        out[:, axis] = np.einsum("nc,nc->n", weights, values[axis][corners])
    return out
