"""Poses for the candidate library (`plan identify --design library`, the default): the greedy
Bayesian D-optimal choice, and plans that stay reachable and tell the candidates apart better
than the D-optimal DH + TCP design."""

from __future__ import annotations

import numpy as np
from hypothesis import Phase, assume, given, settings
from hypothesis import strategies as st

from accugrid.compensation.plans import identification_plan
from accugrid.kinematics.frames import abc_to_matrix, pose_from_xyzabc, rotation_angle_deg
from accugrid.kinematics.pose_design import bayesian_d_greedy, library_share
from accugrid.kinematics.robot import load_robot

ROBOT = load_robot("kr210").with_tool(pose_from_xyzabc([20.0, -10.0, 250.0, 0, 0, 0]))
DRILL = (0.0, 90.0, 0.0)


@given(
    st.integers(0, 2**32 - 1),
    st.integers(4, 14),
    st.integers(1, 3),
    st.integers(2, 9),
    st.integers(1, 4),
)
def test_greedy_takes_the_pose_that_raises_the_posterior_determinant_most(seed, m, k, p, count):
    # brute force: every step recomputes log det(diag(precision) + Σ JᵢᵀJᵢ) for every free
    # candidate; the Woodbury updates of the greedy must make the same choices
    rng = np.random.default_rng(seed)
    rows = rng.normal(size=(m, k, p)) * rng.uniform(0.1, 3.0, size=p)
    precision = rng.uniform(0.01, 10.0, size=p)
    count = min(count, m)
    info = np.diag(precision)
    expected = []
    for _ in range(count):
        gains = np.full(m, -np.inf)
        for i in set(range(m)) - set(expected):
            gains[i] = np.linalg.slogdet(info + rows[i].T @ rows[i])[1]
        top = np.sort(gains)[::-1]
        assume(len(top) < 2 or not np.isfinite(top[1]) or top[0] - top[1] > 1e-9)
        best = int(np.argmax(gains))
        expected.append(best)
        info = info + rows[best].T @ rows[best]
    assert bayesian_d_greedy(rows, precision, count).tolist() == expected


@settings(max_examples=4, deadline=None, derandomize=True, phases=(Phase.generate,))
@given(
    st.floats(1400.0, 1900.0),
    st.floats(-400.0, 400.0),
    st.floats(1300.0, 1800.0),
    st.floats(120.0, 450.0),
    st.floats(8.0, 35.0),
    st.integers(25, 45),
)
def test_library_plan_is_reachable_and_tells_the_candidates_apart_better(x, y, z, half, tilt, n):
    lo, hi = np.array([x, y, z]) - half, np.array([x, y, z]) + half
    args = (ROBOT, lo, hi, n, tilt, DRILL, 6)
    plan = identification_plan(*args, candidates=500)[0]
    # in the region, within the tilt, reachable in the one Status, A5 away from the singularity
    assert np.all(plan.points >= lo - 1e-9) and np.all(plan.points <= hi + 1e-9)
    angle = rotation_angle_deg(abc_to_matrix(plan.abc_rows()), abc_to_matrix(DRILL))
    assert angle.max() <= tilt + 1e-6
    sol = ROBOT.ik(pose_from_xyzabc(np.column_stack([plan.points, plan.abc_rows()])), status=6)
    assert sol.ok.all() and np.all(np.abs(np.degrees(sol.q[:, 4])) >= 10.0 - 1e-6)
    assert len(np.unique(plan.points, axis=0)) == n
    # the same input gives the same plan
    again = identification_plan(*args, candidates=500)[0]
    assert np.array_equal(again.points, plan.points) and plan.ids == again.ids
    # from the same candidates, the D-optimal DH + TCP design removes less of the candidate
    # terms' prior variance (the A-criterion, which neither design maximises itself)
    dh = identification_plan(*args, candidates=500, design="dh")[0]
    q_dh = ROBOT.ik(pose_from_xyzabc(np.column_stack([dh.points, dh.abc_rows()])), status=6).q
    assert library_share(ROBOT, sol.q, 16) > library_share(ROBOT, q_dh, 16)
