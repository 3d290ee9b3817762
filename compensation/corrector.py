"""The one place that decides how targets are corrected: by the grid alone, or by a calibrated
model plus the grid as its residual (issue 10, issue 13 item 5).

``Corrector.build`` takes the job's inputs once. Without a calibrated model the grid is the
measured error grid and P' = P + e(P) (``GridModel.check``). With a model the grid, if any,
becomes ``residual_grid`` (what the model leaves) and P' comes from ``model_correct``.

KUKA Status rule (``model_status``): the Status given (``--status``, the cell's
``configuration.status``); else, with a grid, the Status its measurement run kept
(``grid_status`` at the grid origin and its a,b,c), because the residual is only the model's
residual in the Status the grid was measured in, and a wrist flip between measurement and
program would put the other wrist's errors into it; else the IK default Status at the first
target. The controller solving these is the nominal model with ``controller_tool``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from accugrid.compensation.grid import GridCheck, GridModel
from accugrid.compensation.model_correction import ModelCorrection, model_correct, residual_grid
from accugrid.compensation.settings import CorrectionSettings

if TYPE_CHECKING:  # a grid-only correction never loads the robot modules
    from accugrid.kinematics.robot import Robot

__all__ = ["Corrector", "model_status"]

GridSource = str | os.PathLike[str] | GridModel | None


def model_status(
    controller: Robot,
    status: int | None,
    grid: GridModel | None,
    points: np.ndarray | None = None,
    abc_deg: np.ndarray | None = None,
    turn: int | None = None,
) -> int | None:
    """The KUKA Status a model correction runs in (module docstring): ``status``; else the
    ``grid``'s measurement Status (at its origin and a,b,c; None if it has no a,b,c, which
    ``residual_grid`` then refuses); else the IK default (with ``turn``) at the first of
    ``points`` (N, 3) mm at ``abc_deg`` (N, 3) deg, robot frame (None if unreachable or none)."""
    from accugrid.kinematics.simulation import commanded_poses, grid_status  # model jobs only

    if status is not None:
        return int(status)
    if grid is not None:
        if grid.orientation_abc is None:
            return None
        return grid_status(controller, grid.origin, grid.orientation_abc)
    if points is None or not len(points):
        return None
    abc = np.asarray(abc_deg, dtype=float).reshape(-1, 3)
    first = controller.ik(commanded_poses(np.asarray(points)[:1], abc[0]), turn=turn)
    return int(first.status[0]) if first.ok[0] else None


@dataclass(frozen=True)
class Corrector:
    """How targets are corrected. ``grid``: the error grid (no model) or the residual grid after
    ``calibrated`` (None: model only); ``status``: the KUKA Status of the model correction;
    ``controller_tool``: the controller's flange_T_tool (4, 4) mm (None: the calibrated TCP)."""

    settings: CorrectionSettings
    grid: GridModel | None
    calibrated: Robot | None = None
    status: int | None = None
    controller_tool: np.ndarray | None = None

    @classmethod
    def build(
        cls,
        settings: CorrectionSettings,
        grid: GridSource,
        calibrated: Robot | None = None,
        status: int | None = None,
        controller_tool: np.ndarray | None = None,
        repeat_tol_mm: float | None = None,
        points: np.ndarray | None = None,
        abc_deg: np.ndarray | None = None,
        turn: int | None = None,
    ) -> Corrector:
        """The corrector for one job: ``grid`` a measurement CSV path, a measured GridModel or
        None; ``points``/``abc_deg``/``turn`` only serve the Status rule without a grid
        (``model_status``). InputError for a bad grid or vertices the controller cannot reach."""
        measured = grid
        if grid is not None and not isinstance(grid, GridModel):
            kwargs = {} if repeat_tol_mm is None else {"repeat_tol_mm": repeat_tol_mm}
            measured = GridModel.from_measurements(grid, **kwargs)
        if calibrated is None:
            return cls(settings, measured)
        controller = (
            calibrated if controller_tool is None else calibrated.with_tool(controller_tool)
        )
        status = model_status(controller, status, measured, points, abc_deg, turn)
        if measured is not None:
            measured = residual_grid(calibrated, measured, status, controller_tool=controller_tool)
        return cls(settings, measured, calibrated, status, controller_tool)

    def check(self, points: np.ndarray, rotations: np.ndarray | None = None) -> GridCheck | None:
        """``GridModel.check`` of the grid (error or residual) at targets (N, 3) mm with their
        rotations (N, 3, 3), robot frame: outside points, orientation angles; None without one."""
        if self.grid is None:
            return None
        return self.grid.check(points, self.settings, rotations=rotations)

    def correct(self, points: np.ndarray, abc_deg: np.ndarray) -> ModelCorrection:
        """Commands for targets (N, 3) mm at KUKA A, B, C (N, 3) deg, robot frame: ``command``
        (N, 3) mm, ``ok`` (N,) and ``reason`` (N,), plus the model's miss and passes. Without a
        model: the grid's P + e(P) (outside points clamped as ``GridModel.check``; the safety
        limit is the caller's), all ok."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        if self.calibrated is None:
            n = len(points)
            command = points.copy() if self.grid is None else self.check(points).command
            return ModelCorrection(
                command, np.ones(n, bool), np.full(n, "", dtype=object), np.zeros(n), 0
            )
        return model_correct(
            self.calibrated,
            points,
            abc_deg,
            self.status,
            self.grid,
            self.settings,
            controller_tool=self.controller_tool,
        )

    def too_long(self, points: np.ndarray, command: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Correction lengths |P' - P| (N,) mm (0 where the command is NaN) and the mask (N,)
        of those above the safety limit ``settings.max_correction_mm`` (None: no limit)."""
        length = np.linalg.norm(np.nan_to_num(np.asarray(command) - points), axis=1)
        limit = self.settings.max_correction_mm
        return length, (np.zeros(len(length), bool) if limit is None else length > limit)
