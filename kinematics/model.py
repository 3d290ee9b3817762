"""What every robot model offers the rest of accugrid: the DH ``kinematics.robot.Robot`` and the
``kinematics.urdf.UrdfRobot`` both satisfy ``RobotModel``; ``IKSolution`` is what their IK
returns."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["IKSolution", "RobotModel", "reach_mm"]


@dataclass(frozen=True)
class IKSolution:
    """Result of ``Robot.ik`` for N poses (see the field comments for shapes)."""

    q: np.ndarray  # (N, 6) rad, NaN rows where there is no solution
    ok: np.ndarray  # (N,) bool
    reason: np.ndarray  # (N,) object: "" when ok, else why not
    # (N,) int configuration code of q: shoulder + 2 elbow + 4 wrist, the same number on any
    # DH arm (-1 where there is no solution)
    status: np.ndarray
    turn: np.ndarray  # (N,) int sign code of q (-1 where there is no solution)


@runtime_checkable
class RobotModel(Protocol):
    """A serial robot with a tool. Joint vectors (N, n) rad, poses (N, 4, 4) mm, robot frame."""

    name: str
    flange_T_tool: np.ndarray  # (4, 4) mm
    controller: str  # the maker of its controller, lower case ("kuka", "abb"; "": not said)

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
        """Joint solutions for TCP poses (N, 4, 4) mm; the configuration and sign codes
        (``kinematics.configuration``) where the model has them (-1 otherwise)."""
        ...


def reach_mm(robot: RobotModel, samples: int = 2048) -> float:
    """How far the TCP gets from the robot's base origin, mm: the farthest of the forward
    kinematics over ``samples`` joint vectors spread within the limits (seeded, so the same
    robot gives the same number; a few percent short of the true reach at most)."""
    lo, hi = np.radians(robot.joint_limits_deg).T
    q = lo + np.random.default_rng(0).random((samples, len(lo))) * (hi - lo)
    return float(np.linalg.norm(robot.fk(q)[:, :3, 3], axis=1).max())
