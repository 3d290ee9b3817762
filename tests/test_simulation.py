"""Error-field simulation: one KUKA Status for the whole grid, noise model, default IK choice."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from accugrid.infra.errors import InputError
from accugrid.kinematics.configuration import ik_codes
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.ik import wrap
from accugrid.kinematics.robot import load_robot
from accugrid.kinematics.simulation import (
    commanded_joints,
    commanded_poses,
    grid_status,
    reached_positions,
    simulate_measurements,
)

ABC = np.array([0.0, 90.0, 0.0])


@lru_cache(maxsize=1)
def robot():
    return load_robot("kr210-paper").with_tool(pose_from_xyzabc([0, 0, 250, 0, 0, 0]))


def demo_grid() -> np.ndarray:
    axes = [np.arange(1200.0, 2201.0, 200.0), np.arange(-600.0, 601.0, 200.0)]
    axes.append(np.arange(1100.0, 2101.0, 200.0))
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def test_the_whole_grid_is_solved_in_the_status_of_its_first_point():
    points = demo_grid()
    first = robot().ik(commanded_poses(points[:1], ABC))
    assert grid_status(robot(), points, ABC) == first.status[0] == 6
    q = commanded_joints(robot(), points, ABC)
    status, _ = ik_codes(robot(), q)
    assert (status == 6).all()
    # the per-point default would have flipped the wrist (Status 2 and 6 mixed) on this grid
    assert set(robot().ik(commanded_poses(points, ABC)).status) == {2, 6}
    expected = robot().true_robot().fk(q)[:, :3, 3]
    np.testing.assert_array_equal(reached_positions(robot(), points, ABC), expected)


def test_error_field_has_no_wrist_flip_kinks_away_from_the_wrist_singularity():
    # Away from the Y = 0 column (where A5 passes through 0 and A4 sweeps 180 deg) the held Status
    # gives a smooth field: second differences below 0.2 mm (the per-point default: ~0.8 mm).
    points = demo_grid()
    error = (points - reached_positions(robot(), points, ABC)).reshape(6, 7, 6, 3)
    off_axis = error[:, [0, 1, 5, 6]]
    for axis in (0, 2):
        assert np.linalg.norm(np.diff(off_axis, 2, axis=axis), axis=-1).max() < 0.2
    for side in (error[:, 0:3], error[:, 4:7]):
        assert np.linalg.norm(np.diff(side, 2, axis=1), axis=-1).max() < 0.2


def test_given_status_is_used_and_unreachable_status_is_an_error():
    points = demo_grid()[:20]
    q = commanded_joints(robot(), points, ABC, status=2)
    assert (ik_codes(robot(), q)[0] == 2).all()
    with pytest.raises(InputError, match=r"20 of 20 points cannot be reached .*first: X 1200"):
        reached_positions(robot(), points, ABC, status=3)


def test_nominal_robot_reaches_the_commanded_points():
    points = demo_grid()[::7]
    nominal = load_robot("kr210").with_tool(pose_from_xyzabc([0, 0, 250, 0, 0, 0]))
    np.testing.assert_allclose(reached_positions(nominal, points, ABC), points, atol=1e-9)


def test_noise_is_seeded_with_consecutive_repeats():
    points = demo_grid()[:30]
    cmd, meas = simulate_measurements(robot(), points, ABC, 4, 0.02, 0.03, seed=5)
    again = simulate_measurements(robot(), points, ABC, 4, 0.02, 0.03, seed=5)[1]
    np.testing.assert_array_equal(meas, again)
    np.testing.assert_array_equal(cmd, np.repeat(points, 4, axis=0))
    spread = meas - np.repeat(reached_positions(robot(), points, ABC), 4, axis=0)
    assert 0.02 < spread.std() < 0.05  # sqrt(0.02^2 + 0.03^2) = 0.036 mm


@lru_cache(maxsize=1)
def kr210():
    return load_robot("kr210")


@settings(max_examples=30)
@given(u=arrays(float, (12, 6), elements=st.floats(0.0, 1.0)))
def test_default_ik_takes_the_candidate_closest_to_the_reference(u):
    r = kr210()
    lo, hi = np.radians(r.joint_limits_deg).T
    q = wrap(lo + u * (hi - lo))
    poses = r.fk(q)
    cand, reach = r.ik_all(poses)
    status = ik_codes(r, np.nan_to_num(cand.reshape(-1, 6)))[0].reshape(-1, 8)
    home = np.radians([0.0, -90.0, 90.0, 0.0, 0.0, 0.0])
    distance = np.where(reach & (status & 3 == 2), (wrap(cand - home) ** 2).sum(axis=2), np.inf)
    has = np.isfinite(distance).any(axis=1)
    best = cand[np.arange(len(q)), np.argmin(distance, axis=1)]
    sol = r.ik(poses)
    np.testing.assert_allclose(sol.q[has], best[has], atol=1e-12)
    # with the pose's own joints as reference, the default gives those joints back (off the wrist
    # singularity, where only A4 + A6 is defined and the closed form puts it all into A6)
    own = ((ik_codes(r, q)[0] & 3) == 2) & (np.abs(q[:, 4]) > 1e-6)
    np.testing.assert_allclose(r.ik(poses[own], reference=q[own]).q, q[own], atol=1e-6)
