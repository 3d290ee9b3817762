"""What every robot model offers the rest of accugrid: the DH ``kinematics.robot.Robot`` and the
``kinematics.urdf.UrdfRobot`` both satisfy ``RobotModel``."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from accugrid.kinematics.configuration import IKSolution

__all__ = ["RobotModel", "reach_mm"]


@runtime_checkable
class RobotModel(Protocol):
    """A serial robot with a tool. Joint vectors (N, n) rad, poses (N, 4, 4) mm, robot frame."""

    name: str
    flange_T_tool: np.ndarray  # (4, 4) mm

    @property
    def joint_limits_deg(self) -> np.ndarray:
        """(n, 2) [min, max] deg."""
        ...

    def with_tool(self, flange_T_tool: np.ndarray) -> RobotModel:
        """The same robot with another tool (4, 4) mm."""
        ...

    def true_robot(self) -> RobotModel | None:
        """The robot with its parameter errors applied, or None without errors."""
        ...

    def fk(self, q: np.ndarray) -> np.ndarray:
        """TCP poses robot_T_tcp (N, 4, 4) mm for joint vectors q (N, n) rad."""
        ...

    def ik(self, robot_T_tcp: np.ndarray, status=None, turn=None, reference=None) -> IKSolution:
        """Joint solutions for TCP poses (N, 4, 4) mm; KUKA Status/Turn where the model has
        them (-1 otherwise)."""
        ...


def reach_mm(robot: RobotModel, samples: int = 2048) -> float:
    """How far the TCP gets from the robot's base origin, mm: the farthest of the forward
    kinematics over ``samples`` joint vectors spread within the limits (seeded, so the same
    robot gives the same number; a few percent short of the true reach at most)."""
    lo, hi = np.radians(robot.joint_limits_deg).T
    q = lo + np.random.default_rng(0).random((samples, len(lo))) * (hi - lo)
    return float(np.linalg.norm(robot.fk(q)[:, :3, 3], axis=1).max())
