"""The KRL lines that set a base frame and a tool: ``BASE_DATA[n]={X ..,Y ..,Z ..,A ..,B ..,C ..}``
and ``TOOL_DATA[n]={...}`` as ``$config.dat`` holds them."""

from __future__ import annotations

import numpy as np

from accugrid.infra.textsafe import fixed
from accugrid.kinematics.frames import xyzabc_from_pose

__all__ = ["base_line", "tool_line"]

ANGLE_DECIMALS = 4  # deg: 0.0001 deg moves a point 1 m away by 2 um


def base_line(number: int, robot_T_base: np.ndarray) -> str:
    """``BASE_DATA[number]`` set to ``robot_T_base`` (4, 4) mm (x, y, z mm; KUKA A, B, C deg)."""
    return f"BASE_DATA[{number}]={_frame(robot_T_base)}"


def tool_line(number: int, flange_T_tool: np.ndarray) -> str:
    """``TOOL_DATA[number]`` set to ``flange_T_tool`` (4, 4) mm (x, y, z mm; A, B, C deg)."""
    return f"TOOL_DATA[{number}]={_frame(flange_T_tool)}"


def _frame(pose: np.ndarray) -> str:
    """A KRL FRAME aggregate ``{X ..,Y ..,Z ..,A ..,B ..,C ..}`` of a pose (4, 4) mm."""
    x, y, z, a, b, c = xyzabc_from_pose(pose)
    lengths = ",".join(f"{k} {fixed(v, 3)}" for k, v in zip("XYZ", (x, y, z), strict=True))
    angles = ",".join(
        f"{k} {fixed(v, ANGLE_DECIMALS)}" for k, v in zip("ABC", (a, b, c), strict=True)
    )
    return f"{{{lengths},{angles}}}"
