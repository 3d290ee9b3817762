"""The RS274NGC line that sets a work offset: ``G10 L2 P<n> X Y Z R`` (LinuxCNC: the origin of
coordinate system n, G54 for P1, and its rotation R about Z, deg). A frame tilted about X or Y
has no G10 form: the line then says so in a comment. A tool: ``G10 L1 P<n> X Y Z``, the tool
table's offsets of tool n (its orientation has no tool-table form: a comment says so)."""

from __future__ import annotations

import numpy as np

from accugrid.infra.textsafe import fixed
from accugrid.kinematics.frames import xyzabc_from_pose

__all__ = ["base_line", "tool_line"]

ANGLE_DECIMALS = 4  # deg
TILT_DEG = 0.0001  # a B or C below this is no tilt at ANGLE_DECIMALS
OFFSETS = 9  # P1..P9: G54..G59.3


def base_line(number: int, robot_T_base: np.ndarray) -> str:
    """``G10 L2 P<number>`` with the origin (mm) and rotation about Z (deg) of ``robot_T_base``
    (4, 4); a comment when it is tilted or ``number`` is not a work offset."""
    x, y, z, a, b, c = xyzabc_from_pose(robot_T_base)
    words = " ".join(f"{k}{fixed(v, 3)}" for k, v in zip("XYZ", (x, y, z), strict=True))
    line = f"G10 L2 P{number} {words} R{fixed(a, ANGLE_DECIMALS)}"
    if max(abs(b), abs(c)) >= TILT_DEG:
        line += (
            f" (tilted: B {fixed(b, ANGLE_DECIMALS)} C {fixed(c, ANGLE_DECIMALS)} deg have no "
            "G10 form; program in the robot frame or a program_frame)"
        )
    if not 1 <= number <= OFFSETS:
        line += f" (work offsets are P1..P{OFFSETS})"
    return line


def tool_line(number: int, flange_T_tool: np.ndarray) -> str:
    """``G10 L1 P<number>`` with the offsets (mm) of ``flange_T_tool`` (4, 4); a comment when
    the tool is turned against the spindle."""
    x, y, z, a, b, c = xyzabc_from_pose(flange_T_tool)
    words = " ".join(f"{k}{fixed(v, 3)}" for k, v in zip("XYZ", (x, y, z), strict=True))
    line = f"G10 L1 P{number} {words}"
    if max(abs(a), abs(b), abs(c)) >= TILT_DEG:
        angles = " ".join(
            f"{k} {fixed(v, ANGLE_DECIMALS)}" for k, v in zip("ABC", (a, b, c), strict=True)
        )
        line += f" (turned: {angles} deg have no tool-table form)"
    return line
