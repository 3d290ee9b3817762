"""A family of simulated KR 210s whose error structure nobody has described, for tests and benches.

``random_robot(seed)`` draws, deterministically per seed, on the nominal ``kr210``:

- DH errors of seed Table 1's magnitude: each Δa, Δd, Δα, Δθ normal with the RMS of its column
  of Table 1 (kr210-paper's ``errors``);
- 0-4 reducer harmonics per axis, distinct orders 1..``MAX_FAMILY_ORDER``, amplitudes uniform
  in 2e-5..2e-4 rad, phases uniform;
- gravity compliance of A2 and A3 (0.5e-7..2.5e-7 rad/N·m) under lumped masses drawn around an
  upper arm, a forearm, the wrist and a payload (kg and mm in the DH link frames);
- an SMR that sits off the declared TCP by a random vector of length <= 1 mm.

``FamilyRobot.session`` measures poses as a tracker would: nominal IK with the declared tool (the
controller), the true arm's FK, repeatability then tracker noise (sigma per axis, mm).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from accugrid.kinematics.frames import matrix_to_abc, pose_from_xyzabc
from accugrid.kinematics.joint_errors import Harmonic, JointErrors, PointMass
from accugrid.kinematics.robot import Robot, load_robot

__all__ = [
    "DECLARED_TOOL",
    "MAX_FAMILY_ORDER",
    "NOISE_REPEAT_MM",
    "NOISE_TRACKER_MM",
    "FamilyRobot",
    "Session",
    "random_robot",
]

MAX_FAMILY_ORDER = 16
NOISE_TRACKER_MM, NOISE_REPEAT_MM = 0.02, 0.03
DECLARED_TOOL = (0.0, 0.0, 250.0, 0.0, 0.0, 0.0)  # x, y, z mm, a, b, c deg


@dataclass(frozen=True)
class Session:
    """A simulated tracker session: commanded positions (N, 3) mm and orientations a,b,c (N, 3)
    deg, the joints the controller logged (N, 6) deg, the measured positions (N, 3) mm; repeats
    of a pose are consecutive rows."""

    commanded: np.ndarray
    abc_deg: np.ndarray
    joints_deg: np.ndarray
    measured: np.ndarray


@dataclass(frozen=True)
class FamilyRobot:
    """One drawn robot: ``robot`` is the controller's model (nominal kr210 DH with the declared
    tool) carrying the true errors (``errors``, ``joint_errors``); ``tcp_offset_mm`` (3,) where
    the SMR really is, in the flange frame, relative to the declared TCP."""

    seed: int
    robot: Robot
    tcp_offset_mm: np.ndarray

    @property
    def nominal(self) -> Robot:
        """What the user gives ``identify``: the nominal model and the declared tool, no errors."""
        return replace(self.robot, errors=None, joint_errors=None, name="kr210")

    @property
    def harmonics(self) -> tuple[tuple[int, int], ...]:
        """The true reducer harmonics (axis, order), axis by axis."""
        return tuple((h.axis, h.order) for h in self.robot.joint_errors.harmonics)

    def true_robot(self) -> Robot:
        """The real arm (FK only): DH errors, joint errors and the SMR where it really is."""
        tool = self.robot.flange_T_tool.copy()
        tool[:3, 3] += self.tcp_offset_mm
        return self.robot.with_tool(tool).true_robot()

    def session(
        self,
        q: np.ndarray,
        repeats: int = 3,
        seed: int = 0,
        noise_tracker_mm: float = NOISE_TRACKER_MM,
        noise_repeat_mm: float = NOISE_REPEAT_MM,
    ) -> Session:
        """Measure the controller's joints q (N, 6) rad ``repeats`` times each (consecutive rows),
        noise from ``numpy.random.default_rng(seed)``: repeatability, then tracker."""
        q = np.repeat(np.atleast_2d(np.asarray(q, dtype=float)), repeats, axis=0)
        commanded = self.nominal.fk(q)
        measured = self.true_robot().fk(q)[:, :3, 3]
        rng = np.random.default_rng(seed)
        measured = measured + rng.normal(0.0, noise_repeat_mm, measured.shape)
        measured = measured + rng.normal(0.0, noise_tracker_mm, measured.shape)
        return Session(
            commanded[:, :3, 3], matrix_to_abc(commanded[:, :3, :3]), np.degrees(q), measured
        )


def random_robot(seed: int, declared_tool=DECLARED_TOOL) -> FamilyRobot:
    """The family member ``seed`` (int >= 0) with the declared tool (x, y, z mm, a, b, c deg)."""
    rng = np.random.default_rng([21, seed])
    nominal = load_robot("kr210").with_tool(pose_from_xyzabc(declared_tool))
    table1 = load_robot("kr210-paper").errors
    errors = rng.normal(0.0, 1.0, (6, 4)) * np.sqrt(np.mean(table1**2, axis=0))
    harmonics = []
    for axis in range(1, 7):
        count = int(rng.integers(0, 5))
        orders = np.sort(rng.choice(np.arange(1, MAX_FAMILY_ORDER + 1), count, replace=False))
        for order in orders:
            amplitude = float(rng.uniform(2e-5, 2e-4))
            harmonics.append(
                Harmonic(axis, int(order), amplitude, float(rng.uniform(0, 2 * np.pi)))
            )
    masses = (
        PointMass(2, rng.uniform(150, 350), (-rng.uniform(400, 750), *rng.normal(0, 30, 2))),
        PointMass(3, rng.uniform(100, 250), (*rng.normal(0, 50, 2), rng.uniform(150, 500))),
        PointMass(4, rng.uniform(30, 90), tuple(rng.normal(0, 20, 3))),
        PointMass(6, rng.uniform(0, 60), (*rng.normal(0, 30, 2), rng.uniform(50, 250))),
    )
    compliance = np.zeros(6)
    compliance[1:3] = rng.uniform(0.5e-7, 2.5e-7, 2)
    joint_errors = JointErrors(compliance, masses, tuple(harmonics))
    direction = rng.normal(size=3)
    offset = direction / np.linalg.norm(direction) * rng.uniform(0.0, 1.0)
    robot = replace(
        nominal,
        name=f"family-{seed}",
        errors=errors,
        joint_errors=joint_errors,
        description=f"random KR 210 {seed} of kinematics.robot_family",
    )
    return FamilyRobot(seed, robot, offset)
