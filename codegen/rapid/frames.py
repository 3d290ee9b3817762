"""The RAPID declaration of a base frame: a ``wobjdata`` whose user frame is the part (the
object frame left at the user frame's origin); and the statement that sets a tool's frame
(``tframe``), which leaves its load as it is."""

from __future__ import annotations

import numpy as np

from accugrid.codegen.rapid.emit import QUATERNION_DECIMALS, quaternions
from accugrid.infra.textsafe import fixed

__all__ = ["base_line", "tool_line"]


def base_line(number: int, robot_T_base: np.ndarray) -> str:
    """``PERS wobjdata wobj<number>`` with the user frame ``robot_T_base`` (4, 4) mm: robot
    held, fixed user frame."""
    q = quaternions(robot_T_base[None, :3, :3])[0]
    origin = ",".join(fixed(v, 3) for v in robot_T_base[:3, 3])
    quaternion = ",".join(fixed(v, QUATERNION_DECIMALS) for v in q)
    return (
        f'PERS wobjdata wobj{number}:=[FALSE,TRUE,"",[[{origin}],[{quaternion}]],'
        "[[0,0,0],[1,0,0,0]]];"
    )


def tool_line(number: int, flange_T_tool: np.ndarray) -> str:
    """``tool<number>.tframe:=[[x,y,z],[q1,q2,q3,q4]];`` for ``flange_T_tool`` (4, 4) mm: the
    tool's frame only (its ``tload`` stays what the controller has)."""
    q = quaternions(flange_T_tool[None, :3, :3])[0]
    origin = ",".join(fixed(v, 3) for v in flange_T_tool[:3, 3])
    quaternion = ",".join(fixed(v, QUATERNION_DECIMALS) for v in q)
    return f"tool{number}.tframe:=[[{origin}],[{quaternion}]];"
