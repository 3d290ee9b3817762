"""The G-code section of the cell: what only the G-code emitter and rewrite read
(``cell.dialects["gcode"]``).

The YAML keys stay where the cell file has them (``gcode:``, ``program.decimals``,
``program_frame:``); ``KEYS`` declares them for the cell reader, and ``read_section``
builds and validates the record in one place.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from accugrid.codegen.cellfile import FRAME_KEYS, CellReader, SectionKeys

__all__ = ["KEYS", "GcodeSection", "read_section"]

KEYS: SectionKeys = {
    "gcode": frozenset({"spindle_rpm", "canned_cycles"}),
    "program": frozenset({"decimals"}),
    "program_frame": frozenset(FRAME_KEYS),
}


@dataclass(frozen=True)
class GcodeSection:
    """robot_T_program: the program frame (4, 4) in the robot frame, mm (default: the BASE
    frame); decimals of positions (mm) and angles (deg); spindle_rpm: the S word of M3 (1/min);
    canned_cycles: G81/G82/G83 where the drill axis is the program's -Z."""

    robot_T_program: np.ndarray
    decimals: int = 3
    spindle_rpm: float = 6000.0
    canned_cycles: bool = True


def read_section(r: CellReader, robot_T_base: np.ndarray) -> GcodeSection:
    """The G-code record of the cell ``r`` reads (``robot_T_base``: the default program frame);
    InputError naming the key and line."""
    frame = r.top.get("program_frame")
    return GcodeSection(
        robot_T_program=robot_T_base
        if frame is None
        else r.frame(frame, "program_frame", False)[1],
        decimals=r.integer("program", "decimals", 3, 1, 6),
        spindle_rpm=r.number("gcode", "spindle_rpm", 6000.0, 0.0, 10**6, True),
        canned_cycles=r.boolean("gcode", "canned_cycles", True),
    )
