"""The cell as the jobs and the dialect plug-ins receive it: ``Cell`` and its neutral records
(``DrillingSection``, ``ConfigurationSection``), read from the cell file by ``codegen.cell``."""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from accugrid.infra.errors import InputError

if TYPE_CHECKING:
    import numpy as np

    from accugrid.compensation.settings import CorrectionSettings
    from accugrid.infra.csvtable import TableFormat

__all__ = ["Cell", "ConfigurationSection", "DrillingSection"]


@dataclass(frozen=True)
class DrillingSection:
    """The drilling process every dialect follows. Distances from the hole along the drill axis
    (mm): approach point, clearance (where the feed starts, < approach), retract point, depth
    (when the points have none); dwell at the bottom (s); peck depth (mm, 0 = none); speeds
    (mm/s): travel between holes, approach and retract, feed (when the points have none)."""

    approach_mm: float = 30.0
    clearance_mm: float = 2.0
    retract_mm: float = 30.0
    depth_mm: float = 10.0
    dwell_s: float = 0.5
    peck_mm: float = 0.0
    travel_mm_s: float = 500.0
    approach_mm_s: float = 50.0
    feed_mm_s: float = 5.0


@dataclass(frozen=True)
class ConfigurationSection:
    """How the robot reaches the holes: KUKA Status (0..7) and Turn (0..63) to require (None:
    the first hole's IK solution), whether a hole may take another Status/Turn, |A5| (deg)
    below which a hole is reported near the wrist singularity, and the reference tool
    orientation (robot frame, KUKA A, B, C deg) that holes given as i,j,k are tilted from."""

    status: int | None = None
    turn: int | None = None
    allow_change: bool = False
    singular_a5_deg: float = 5.0
    reference_abc: tuple[float, float, float] = (0.0, 90.0, 0.0)


@dataclass(frozen=True)
class Cell:
    """A validated cell file. Poses are (4, 4) homogeneous transforms in mm: ``flange_T_tool``
    (the TCP, TOOL_DATA ``tool_number``), ``robot_T_base`` (the points' frame, BASE_DATA
    ``base_number``) and ``base_data`` (BASE_DATA number -> robot_T_frame, the base included).
    ``tool_data`` (tool number -> flange_T_tool, the cell's tool and 0, the flange, included)
    is None when the file has no ``tool_data:`` (a program is then corrected with the cell's
    tool alone)."""

    path: Path
    robot_name: str
    grid_path: Path | None
    model_path: Path | None  # correction.model: a calibrated robot YAML (accugrid identify)
    tool_number: int
    flange_T_tool: np.ndarray
    base_number: int
    robot_T_base: np.ndarray
    base_data: dict[int, np.ndarray]
    drilling: DrillingSection
    configuration: ConfigurationSection
    correction: CorrectionSettings
    dialects: Mapping[str, object]  # dialect name -> its section record
    sha256: str = ""
    tracker: TableFormat | None = None  # how the grid file is written (tracker:), None: found
    tool_data: dict[int, np.ndarray] | None = None

    def grid_file(self, override: str | os.PathLike[str] | None = None, hint: str = "") -> Path:
        """The measurement to correct with: ``override`` (--grid), else the cell's ``grid``;
        InputError when there is neither (``hint`` completes the message)."""
        if override is not None:
            return Path(override)
        if self.grid_path is None:
            raise InputError(
                f"no grid: name one in the cell file (grid:), give --grid{hint}", self.path
            )
        return self.grid_path
