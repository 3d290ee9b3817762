"""The measured error model: regular grid, inverse-distance weighting (seed Eq. 12–13),
correction (Eq. 14), sampling plans, ISO 9283 / GB/T 12642 test points and the grid-step study."""

from accugrid.compensation.grid import GridModel

__all__ = ["GridModel"]
