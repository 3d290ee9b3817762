"""Interpolation kernels over the 8 vertices of a regular-grid cell.

Corner c (0..7) of a cell is vertex (i + bx, j + by, k + bz) with c = 4 bx + 2 by + bz.
Cell rule: a point belongs to cell floor((p - origin) / step) clipped to [0, n - 2] per axis, so a
point on a face shared by two cells goes to the upper cell, and the upper boundary of the grid to
the last cell. ``frac`` is the local coordinate in the cell, 0..1 per axis inside the grid.

- IDW (seed Eq. 12-13): q_i = s_i^-p / sum_j s_j^-p, s_i the distance (mm) to corner i. At a
  vertex (s_i < 1e-9 of the smallest step) the weight is exactly 1 there and 0 elsewhere.
  Not continuous across faces. Power 0 < p <= 16.
- Trilinear: q_i = prod over axes of (f or 1 - f); continuous across faces.

Arrays are axis-major for speed: points and frac (3, N), weights and corner indices (8, N).

A method is a strategy in the registry ``METHODS`` (name -> ``Method``); ``method_named`` is the one
place a name is checked. ``CellInterpolator`` is fitted from a grid's vertex values and predicts
at points, like scipy's ``RegularGridInterpolator(method=...)``. A new method (a model-based one,
say) is a weights function and one registry entry.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from accugrid.infra.errors import InputError

__all__ = [
    "CORNERS",
    "MAX_POWER",
    "METHODS",
    "CellInterpolator",
    "Method",
    "blend",
    "corner_indices",
    "idw_weights",
    "locate",
    "method_named",
    "trilinear_weights",
]

# corner bits (8, 3): bx, by, bz of corner c = 4 bx + 2 by + bz
CORNERS = np.array([[c >> 2 & 1, c >> 1 & 1, c & 1] for c in range(8)])
VERTEX_SNAP = 1e-9  # IDW: closer to a vertex than this fraction of the smallest step = at it
MAX_POWER = 16.0  # IDW powers above this overflow s^-p for points near a vertex


def locate(
    points_t: np.ndarray, origin: np.ndarray, step: np.ndarray, counts: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Enclosing cell (3, N) int64 and local coordinates frac (3, N) of points (3, N) mm."""
    t = (points_t - origin[:, None]) / step[:, None]
    cell = np.floor(t)
    np.clip(cell, 0, (counts - 2)[:, None], out=cell)
    t -= cell
    return cell.astype(np.int64), t


def idw_weights(frac: np.ndarray, step: np.ndarray, power: float = 1.0) -> np.ndarray:
    """Inverse-distance weights (8, N) of the cell corners for local coordinates frac (3, N)."""
    # squared distance per axis to the lower (b = 0) and upper (b = 1) corner
    side = [(np.square(frac[a] * step[a]), np.square((1.0 - frac[a]) * step[a])) for a in range(3)]
    inv = np.empty((8, frac.shape[1]))
    for c, (bx, by, bz) in enumerate(CORNERS):
        np.add(side[0][bx], side[1][by], out=inv[c])
        inv[c] += side[2][bz]
    # at a vertex (distance below 1e-9 of the smallest step, which absorbs the rounding of
    # (p - origin) / step) that vertex alone: exact there, no division by zero
    hit = inv <= (VERTEX_SNAP * float(np.min(step))) ** 2
    at_vertex = hit.any(axis=0)
    with np.errstate(divide="ignore", over="ignore"):  # only where hit: replaced below
        if power == 1.0:
            np.sqrt(inv, out=inv)
            np.reciprocal(inv, out=inv)
        else:
            np.power(inv, -0.5 * power, out=inv)
    if at_vertex.any():
        inv[:, at_vertex] = hit[:, at_vertex]
    total = inv.sum(axis=0)
    inv *= 1.0 / total
    return inv


def trilinear_weights(frac: np.ndarray, step: np.ndarray | None = None, power: float = 1.0):
    """Trilinear weights (8, N) of the cell corners for local coordinates frac (3, N); step and
    power are not used (the signature of every method's weights)."""
    side = [(1.0 - frac[a], frac[a]) for a in range(3)]
    out = np.empty((8, frac.shape[1]))
    for c, (bx, by, bz) in enumerate(CORNERS):
        np.multiply(side[0][bx], side[1][by], out=out[c])
        out[c] *= side[2][bz]
    return out


def corner_indices(cell: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Flat vertex indices (8, N) of the corners of cells (3, N); vertices in C order."""
    ny, nz = int(counts[1]), int(counts[2])
    base = (cell[0] * ny + cell[1]) * nz + cell[2]
    offsets = (CORNERS[:, 0] * ny + CORNERS[:, 1]) * nz + CORNERS[:, 2]
    return base + offsets[:, None]


def blend(values: np.ndarray, corners: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Weighted sum (3, N) of per-vertex values (3, M) at corners (8, N) with weights (8, N)."""
    out = np.zeros((3, corners.shape[1]))
    for axis in range(3):
        for c in range(8):
            out[axis] += weights[c] * values[axis].take(corners[c])
    return out


@dataclass(frozen=True)
class Method:
    """An interpolation strategy: weights(frac (3, N), step (3,) mm, power) -> (8, N)."""

    name: str
    weights: Callable[[np.ndarray, np.ndarray, float], np.ndarray]
    uses_power: bool


METHODS = {
    "idw": Method("idw", idw_weights, uses_power=True),
    "trilinear": Method("trilinear", trilinear_weights, uses_power=False),
}


def method_named(name: str) -> Method:
    """The registered method ``name``; InputError naming the choices otherwise."""
    try:
        return METHODS[name]
    except (KeyError, TypeError):
        raise InputError(f"unknown method '{name}' (choose {' or '.join(METHODS)})") from None


class CellInterpolator:
    """Vertex values (3, nx*ny*nz) of a regular grid (origin, step (3,) mm, counts (3,)) fitted
    once; ``predict`` blends the 8 corners of each point's cell with ``method``'s weights."""

    def __init__(
        self,
        origin: np.ndarray,
        step: np.ndarray,
        counts: np.ndarray,
        values: np.ndarray,
        method: str = "idw",
        power: float = 1.0,
    ) -> None:
        self.origin, self.step, self.counts = origin, step, counts
        self.values = values
        self.method = method_named(method)
        self.power = power

    def predict(self, points_t: np.ndarray) -> np.ndarray:
        """Interpolated values (3, n) at points (3, n) mm inside the grid box."""
        cell, frac = locate(points_t, self.origin, self.step, self.counts)
        weights = self.method.weights(frac, self.step, self.power)
        return blend(self.values, corner_indices(cell, self.counts), weights)
