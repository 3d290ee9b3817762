"""The KRL line that sets a base frame: ``BASE_DATA[n]={X ..,Y ..,Z ..,A ..,B ..,C ..}`` as
``$config.dat`` holds it."""

from __future__ import annotations

import numpy as np

from accugrid.infra.textsafe import fixed
from accugrid.kinematics.frames import xyzabc_from_pose

__all__ = ["base_line"]

ANGLE_DECIMALS = 4  # deg: 0.0001 deg moves a point 1 m away by 2 um


def base_line(number: int, robot_T_base: np.ndarray) -> str:
    """``BASE_DATA[number]`` set to ``robot_T_base`` (4, 4) mm (x, y, z mm; KUKA A, B, C deg)."""
    x, y, z, a, b, c = xyzabc_from_pose(robot_T_base)
    lengths = ",".join(f"{k} {fixed(v, 3)}" for k, v in zip("XYZ", (x, y, z), strict=True))
    angles = ",".join(
        f"{k} {fixed(v, ANGLE_DECIMALS)}" for k, v in zip("ABC", (a, b, c), strict=True)
    )
    return f"BASE_DATA[{number}]={{{lengths},{angles}}}"
