"""The error-similarity grid model (seed Sec. 2.3): measured vertex errors in, predicted errors and
corrected commands out.

The error is e = P - M (commanded minus measured, docs/formats.md). Inside the grid the error at a
point is interpolated from the 8 vertices of its cell (``compensation.interpolation``):
inverse-distance weighting (seed Eq. 12-13, the default, power 1) or trilinear. The corrected
command is P' = P + e(P) (Eq. 14); with K iterations P'_k = P + e(P'_(k-1)), which removes the
second-order term e(P) - e(P + e).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from accugrid.compensation.interpolation import METHODS, CellInterpolator
from accugrid.compensation.measurements import (
    COORD_TOL_MM,
    REPEAT_TOL_MM,
    Measurements,
    build_grid,
    measurements_from_arrays,
    read_measurements,
)
from accugrid.compensation.settings import MAX_CORRECTION_MM, OUTSIDE, CorrectionSettings
from accugrid.infra.csvtable import TableFormat
from accugrid.infra.errors import InputError
from accugrid.infra.units import mm_text
from accugrid.kinematics.frames import abc_to_matrix, axis_angle_deg, rotation_angle_deg

__all__ = [
    "BOX_TOL_MM",
    "MAX_CORRECTION_MM",
    "METHODS",
    "OUTSIDE",
    "CorrectionSettings",
    "GridCheck",
    "GridModel",
]

BOX_TOL_MM = 1e-6  # a point this close outside the grid box still counts as inside
_CHUNK = 65536  # points per block: keeps the (block, 8) temporaries in cache


class GridModel:
    """Measured TCP errors at the vertices of an axis-aligned regular grid (robot frame).

    origin, step (3,) mm; counts (3,) int (vertices per axis, >= 2); errors (nx, ny, nz, 3) mm,
    e = P - M at the vertices; orientation_abc (3,) deg or None: the TCP orientation of the
    measurement; status: the KUKA Status it was measured in (column s; None: not recorded);
    source_sha256: SHA-256 of the measurement file (None for arrays); noise_mm: a measured row's
    scatter about its vertex mean, 1 sigma per axis mm (None: no repeats).
    """

    def __init__(
        self,
        origin: np.ndarray,
        step: np.ndarray,
        errors: np.ndarray,
        orientation_abc: np.ndarray | None = None,
        source_sha256: str | None = None,
        source_path: str | None = None,
        repeats: np.ndarray | None = None,
        spread_mm: float = 0.0,
        status: int | None = None,
        noise_mm: float | None = None,
    ) -> None:
        self.errors = np.array(errors, dtype=float)
        if self.errors.ndim != 4 or self.errors.shape[3] != 3 or min(self.errors.shape[:3]) < 2:
            raise ValueError(f"errors must be (nx, ny, nz, 3) with n >= 2, got {self.errors.shape}")
        self.origin = np.array(origin, dtype=float).reshape(3)
        self.step = np.array(step, dtype=float).reshape(3)
        if not (self.step > 0).all() or not np.isfinite(self.errors).all():
            raise ValueError("grid steps must be positive and errors finite")
        self.counts = np.array(self.errors.shape[:3], dtype=np.int64)
        self.orientation_abc = None if orientation_abc is None else np.array(orientation_abc, float)
        self.source_sha256 = source_sha256
        self.source_path = source_path
        self.repeats = repeats
        self.spread_mm = float(spread_mm)
        self.noise_mm = noise_mm
        self.status = None if status is None else int(status)
        self.errors.flags.writeable = False  # predict works from the copy below
        # per-axis vertex values (3, nx*ny*nz), contiguous for the gathers in predict
        self._values = np.ascontiguousarray(self.errors.reshape(-1, 3).T)

    @classmethod
    def from_measurements(
        cls,
        source: str | os.PathLike[str] | tuple | Measurements | np.ndarray,
        measured: np.ndarray | None = None,
        abc: np.ndarray | None = None,
        *,
        coord_tol_mm: float = COORD_TOL_MM,
        repeat_tol_mm: float = REPEAT_TOL_MM,
        fmt: TableFormat | None = None,
    ) -> GridModel:
        """Build from measurements: a CSV path (read as ``fmt`` says, default: found), a
        ``Measurements``, the arrays commanded (N, 3) and ``measured`` (N, 3) mm (robot frame;
        ``abc`` (N, 3) KUKA deg optional) or a tuple of them.

        Repeats of a commanded point are averaged; InputError (file, line) when the points are
        not a complete regular grid or repeats disagree by more than ``repeat_tol_mm``.
        """
        if measured is not None:
            source = (source, measured, abc)
        if isinstance(source, Measurements):
            meas = source
        elif isinstance(source, tuple):
            meas = measurements_from_arrays(*source)
        elif isinstance(source, np.ndarray):
            raise TypeError("give the measured points too: from_measurements(commanded, measured)")
        else:
            meas = read_measurements(source, fmt)
        grid = build_grid(meas, coord_tol_mm=coord_tol_mm, repeat_tol_mm=repeat_tol_mm)
        return cls(
            grid.origin,
            grid.step,
            grid.errors,
            orientation_abc=grid.abc,
            source_sha256=meas.sha256,
            source_path=meas.path,
            repeats=grid.repeats,
            spread_mm=grid.spread_mm,
            status=grid.status,
            noise_mm=grid.noise_mm,
        )

    def __repr__(self) -> str:
        source = f", from {os.path.basename(self.source_path)}" if self.source_path else ""
        return (
            f"GridModel({'x'.join(map(str, self.counts))} vertices, origin "
            f"{mm_text(self.origin, 3)} mm, step {mm_text(self.step, 3)} mm{source})"
        )

    @property
    def upper(self) -> np.ndarray:
        """The grid's far corner (3,) mm."""
        return self.origin + (self.counts - 1) * self.step

    def vertices(self) -> np.ndarray:
        """Vertex positions (nx, ny, nz, 3) mm."""
        axes = [self.origin[a] + np.arange(self.counts[a]) * self.step[a] for a in range(3)]
        return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)

    def contains(self, points: np.ndarray) -> np.ndarray:
        """(N,) bool: inside the grid box, boundary included (within 1e-6 mm)."""
        points = _as_points(points)
        lo, hi = self.origin - BOX_TOL_MM, self.upper + BOX_TOL_MM
        if len(points) and all(
            points[:, a].min() >= lo[a] and points[:, a].max() <= hi[a] for a in range(3)
        ):  # the common case, column by column: no (N, 3) temporaries
            return np.ones(len(points), bool)
        return ((points >= lo) & (points <= hi)).all(axis=1)

    def predict(
        self,
        points: np.ndarray,
        method: str = "idw",
        power: float = 1.0,
        outside: str = "error",
    ) -> np.ndarray:
        """Predicted error e (N, 3) mm at points (N, 3) mm.

        outside="error": InputError naming the points outside the grid box; "clamp": such a
        point gets the error of the nearest point of the box (in the nearest cell).
        """
        settings = CorrectionSettings(method=method, power=power, outside=outside)
        return self._predict(_as_points(points), settings, settings.outside)

    def check(
        self,
        points: np.ndarray,
        settings: CorrectionSettings | None = None,
        rotations: np.ndarray | None = None,
        axes: np.ndarray | None = None,
    ) -> GridCheck:
        """Correct targets P (N, 3) mm and report, without raising, what a job must look at:
        the points outside the grid box (evaluated at the nearest box point), the corrections
        longer than ``settings.max_correction_mm``, and, when the grid has an orientation, the
        angle (N,) deg of each point's orientation from it: rotations (N, 3, 3) or drill axes
        (N, 3, unit, compared with the grid tool's Z), robot frame."""
        settings = settings or CorrectionSettings()
        points = _as_points(points)
        command = points + self._predict(points, settings, "clamp")
        for _ in range(int(settings.iterations) - 1):
            command = points + self._predict(command, settings, "clamp")
        change = command - points
        length = np.sqrt(np.einsum("ij,ij->i", change, change))
        limit = settings.max_correction_mm
        too_long = np.zeros(0, np.int64) if limit is None else np.flatnonzero(length > limit)
        angle = None
        if self.orientation_abc is not None and len(points):
            reference = abc_to_matrix(self.orientation_abc)
            if rotations is not None:
                angle = rotation_angle_deg(rotations, reference)
            elif axes is not None:
                angle = axis_angle_deg(axes, reference[:, 2])
        return GridCheck(
            points, command, length, np.flatnonzero(~self.contains(points)), too_long, angle
        )

    def correct(
        self, points: np.ndarray, settings: CorrectionSettings | None = None, **changes
    ) -> np.ndarray:
        """Corrected commands P' (N, 3) mm for targets P (N, 3) mm: P'_k = P + e(P'_(k-1)).

        ``settings`` (default ``CorrectionSettings()``) with ``changes`` to its fields. The
        outside rule applies to P; iterates that step out of the box (by at most one
        correction) are evaluated at the nearest box point. InputError for the whole job when
        any correction |P' - P| exceeds ``max_correction_mm`` (None: no limit).
        """
        settings = (settings or CorrectionSettings()).but(**changes)
        points = _as_points(points)
        if settings.outside == "error":
            self._refuse_outside(points)
        found = self.check(points, settings)
        if found.too_long.size:
            worst = int(np.argmax(found.length))
            raise InputError(
                f"correction of {found.length[worst]:.3f} mm at point {worst} "
                f"{mm_text(points[worst])} exceeds the safety limit of "
                f"{settings.max_correction_mm:g} mm; "
                "refusing the whole job (check the grid, or raise the limit)"
            )
        return found.command

    def describe(self) -> str:
        """Multi-line summary: source, origin, step, counts, repeats, error range per axis."""
        e = self.errors.reshape(-1, 3)
        lines = [
            f"grid       {self.source_path or '(arrays)'}",
            f"origin     {mm_text(self.origin)} mm, far corner {mm_text(self.upper)} mm",
            f"step       {mm_text(self.step)} mm, vertices "
            + "x".join(str(int(c)) for c in self.counts)
            + f" = {int(np.prod(self.counts))}",
        ]
        if self.repeats is not None:
            lines.append(
                f"repeats    {int(self.repeats.min())}..{int(self.repeats.max())} per vertex, "
                f"largest spread {self.spread_mm:.4f} mm"
            )
        for axis, name in enumerate("xyz"):
            lines.append(f"error e{name}   {e[:, axis].min():+.4f} .. {e[:, axis].max():+.4f} mm")
        if self.orientation_abc is not None:
            lines.append(f"orientation a,b,c {mm_text(self.orientation_abc)} deg")
        if self.status is not None:
            lines.append(f"status     KUKA Status {self.status} (column s)")
        return "\n".join(lines)

    def _refuse_outside(self, points: np.ndarray) -> None:
        """InputError naming the points (N, 3) outside the grid box, if any."""
        bad = np.flatnonzero(~self.contains(points))
        if bad.size:
            listed = "; ".join(f"point {i} {mm_text(points[i])}" for i in bad[:5])
            raise InputError(
                f"{bad.size} point(s) outside the grid box {mm_text(self.origin)}.."
                f"{mm_text(self.upper)} mm: {listed} (use outside='clamp' to use the nearest cell)"
            )

    def _predict(
        self, points: np.ndarray, settings: CorrectionSettings, outside: str
    ) -> np.ndarray:
        """Predicted error (N, 3) at points (N, 3), in cache-sized blocks."""
        strategy = CellInterpolator(
            self.origin, self.step, self.counts, self._values, settings.method, settings.power
        )
        lo, hi = self.origin[:, None], self.upper[:, None]
        out = np.empty_like(points)
        for start in range(0, len(points), _CHUNK):
            # (3, n), always a copy: for one point the transpose is contiguous already and
            # the clip below would move the caller's point into the box
            block = np.array(points[start : start + _CHUNK].T, order="C")
            if not (
                (block.min(axis=1) >= self.origin).all() and (block.max(axis=1) <= self.upper).all()
            ):
                if outside == "error":
                    self._refuse_outside(points)
                np.clip(block, lo, hi, out=block)
            out[start : start + _CHUNK] = strategy.predict(block).T
        return out


@dataclass(frozen=True)
class GridCheck:
    """What ``GridModel.check`` found for targets P (N, 3) mm: commands P' (N, 3) mm, correction
    lengths |P' - P| (N,) mm, index arrays of the points outside the grid box and of the
    corrections above the safety limit, and the orientation angle (N,) deg from the grid's (None
    when the grid or the points have no orientation)."""

    points: np.ndarray
    command: np.ndarray
    length: np.ndarray
    outside: np.ndarray
    too_long: np.ndarray
    angle: np.ndarray | None

    @property
    def correction(self) -> np.ndarray:
        """P' - P (N, 3) mm."""
        return self.command - self.points


def _as_points(points: np.ndarray) -> np.ndarray:
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise InputError(f"points must be an (N, 3) array in mm, got shape {points.shape}")
    if not np.isfinite(points).all():
        row = int(np.flatnonzero(~np.isfinite(points).all(axis=1))[0])
        raise InputError(f"point {row} is not finite: {points[row].tolist()}")
    return points
