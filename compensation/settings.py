"""How a grid correction is made: one ``CorrectionSettings`` value, built once from the cell file
(``correction:``) or the command line and passed through ``correct``, ``krl``, ``gcode`` and
``rewrite`` to ``GridModel``."""

from __future__ import annotations

from dataclasses import dataclass, replace

from accugrid.compensation.interpolation import MAX_POWER, method_named
from accugrid.infra.errors import InputError

__all__ = [
    "DEFAULT_TOLERANCE_MM",
    "MAX_CORRECTION_MM",
    "OUTSIDE",
    "TOOL_DISTANCE_MM",
    "CorrectionSettings",
]

OUTSIDE = ("error", "clamp")  # points outside the grid box: refuse, or use the nearest cell
MAX_CORRECTION_MM = 5.0  # default safety limit on the length of any one correction
DEFAULT_TOLERANCE_MM = 0.3  # the hole-position accuracy aircraft drilling asks (seed: +-0.3 mm)
# A grid holds the position error of the TCP it was measured with. At another TCP of the same
# flange pose the error differs by the arm's orientation error times their distance, which a
# grid does not measure (0.05 deg, common for an uncalibrated arm, makes 0.09 mm at 100 mm):
# a grid corrects another tool only when its TCP is this close (0.001 mm per mrad).
TOOL_DISTANCE_MM = 1.0


@dataclass(frozen=True)
class CorrectionSettings:
    """method: interpolation over a cell's 8 vertices (``interpolation.METHODS``); power: the
    inverse-distance power p (0 < p <= 16); iterations: K of P'_k = P + e(P'_(k-1)) (>= 1);
    outside: "error" or "clamp"; max_correction_mm: refuse the job when any |P' - P| is longer
    (mm, None: no limit); tool_distance_mm: how close (mm) another tool's TCP must be to the
    one a grid was measured with for the grid to correct it (``TOOL_DISTANCE_MM``). InputError
    on any invalid value."""

    method: str = "idw"
    power: float = 1.0
    iterations: int = 1
    outside: str = "error"
    max_correction_mm: float | None = MAX_CORRECTION_MM
    tool_distance_mm: float = TOOL_DISTANCE_MM

    def __post_init__(self) -> None:
        method_named(self.method)
        if self.outside not in OUTSIDE:
            raise InputError(
                f"unknown outside rule '{self.outside}' (choose {' or '.join(OUTSIDE)})"
            )
        if not (0 < self.power <= MAX_POWER):
            raise InputError(
                f"the inverse-distance power must be > 0 and <= {MAX_POWER:g}, got {self.power}"
            )
        if int(self.iterations) != self.iterations or self.iterations < 1:
            raise InputError(f"iterations must be a whole number >= 1, got {self.iterations}")
        if self.max_correction_mm is not None and not self.max_correction_mm > 0:
            raise InputError(f"the safety limit must be > 0 mm, got {self.max_correction_mm}")
        if not self.tool_distance_mm >= 0:
            raise InputError(f"the tool distance must be >= 0 mm, got {self.tool_distance_mm}")

    def but(self, **changes) -> CorrectionSettings:
        """A copy with some fields changed (validated again)."""
        return replace(self, **changes) if changes else self
