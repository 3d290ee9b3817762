"""The grid model against the simulated kr210-paper (seed Table 1 errors, no noise).

The true robot is commanded like a KRL program does: nominal IK with one fixed Status (wrist
A5 < 0), then the true forward kinematics. The region X 1400..1800, Y 300..700, Z 1300..1700 mm at
A 0 B 90 C 0 keeps |A5| > 10 deg (clear of the wrist singularity), which the tests check.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from accugrid.compensation import GridModel
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.robot import load_robot
from accugrid.kinematics.simulation import commanded_poses

ABC = np.array([0.0, 90.0, 0.0])
STATUS = 6  # basic area, A3 >= phi, A5 < 0
LOW, HIGH = np.array([1400.0, 300.0, 1300.0]), np.array([1800.0, 700.0, 1700.0])


@lru_cache(maxsize=1)
def robot():
    return load_robot("kr210-paper").with_tool(pose_from_xyzabc([0, 0, 250, 0, 0, 0]))


def reached(commands: np.ndarray) -> np.ndarray:
    """Where the true robot's TCP goes (N, 3) for commands (N, 3) mm; checks |A5| > 10 deg."""
    solution = robot().ik(commanded_poses(commands, ABC), status=STATUS)
    assert solution.ok.all(), solution.reason[~solution.ok][:3]
    assert (np.abs(np.degrees(solution.q[:, 4])) > 10.0).all()
    return robot().true_robot().fk(solution.q)[:, :3, 3]


@lru_cache(maxsize=4)
def measured_grid(step: float) -> GridModel:
    axes = [np.arange(LOW[a], HIGH[a] + step / 2, step) for a in range(3)]
    vertices = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return GridModel.from_measurements((vertices, reached(vertices)))


@pytest.mark.parametrize(("method", "iterations"), [("idw", 1), ("idw", 3), ("trilinear", 1)])
@settings(max_examples=15)
@given(frac=arrays(float, (25, 3), elements=st.floats(0.0, 1.0)))
def test_corrected_command_lands_closer_than_the_uncorrected_one(method, iterations, frac):
    targets = LOW + frac * (HIGH - LOW)
    model = measured_grid(200.0)
    before = np.linalg.norm(targets - reached(targets), axis=1)
    command = model.correct(targets, iterations=iterations, method=method)
    after = np.linalg.norm(targets - reached(command), axis=1)
    assert (after < before).all()
    assert before.min() > 1.0  # the uncorrected robot is really off (seed: 1-4 mm)


@pytest.mark.parametrize("method", ["idw", "trilinear"])
def test_largest_residual_shrinks_with_the_step(method):
    targets = np.random.default_rng(11).uniform(LOW, HIGH, size=(300, 3))
    worst = []
    for step in (400.0, 200.0, 100.0):
        command = measured_grid(step).correct(targets, method=method, iterations=2)
        worst.append(np.abs(targets - reached(command)).max())
    assert worst[0] > worst[1] > worst[2], worst
