"""The RAPID declaration of a base frame: a ``wobjdata`` whose user frame is the part (the
object frame left at the user frame's origin)."""

from __future__ import annotations

import numpy as np

from accugrid.codegen.rapid.emit import QUATERNION_DECIMALS, quaternions
from accugrid.infra.textsafe import fixed

__all__ = ["base_line"]


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
