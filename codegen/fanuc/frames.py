"""The FANUC entry of a user frame and of a tool frame: X, Y, Z mm and W, P, R deg (fixed
angles about X, Y, Z), as the frame setup's direct entry takes them; a user frame in the world
frame (a FANUC robot file's robot frame), a tool frame in the faceplate frame."""

from __future__ import annotations

import numpy as np

from accugrid.infra.textsafe import fixed
from accugrid.kinematics.frames import matrix_to_abc

__all__ = ["base_line", "tool_line"]


def _entry(pose: np.ndarray) -> str:
    w, p, r = matrix_to_abc(pose[:3, :3])[::-1]
    x, y, z = pose[:3, 3]
    return (
        f"X = {fixed(x, 3)} mm, Y = {fixed(y, 3)} mm, Z = {fixed(z, 3)} mm, "
        f"W = {fixed(w, 3)} deg, P = {fixed(p, 3)} deg, R = {fixed(r, 3)} deg"
    )


def base_line(number: int, robot_T_base: np.ndarray) -> str:
    """``UFRAME[<number>]: X = .. mm, .. R = .. deg`` for ``robot_T_base`` (4, 4) mm."""
    return f"UFRAME[{number}]: {_entry(robot_T_base)}"


def tool_line(number: int, flange_T_tool: np.ndarray) -> str:
    """``UTOOL[<number>]: X = .. mm, .. R = .. deg`` for ``flange_T_tool`` (4, 4) mm."""
    return f"UTOOL[{number}]: {_entry(flange_T_tool)}"
