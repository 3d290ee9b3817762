"""Kinematic identification: recovery of injected DH errors and TCP offset, the unidentifiable
directions of position data, robust fitting, cross-validation and the refusals of bad data."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from accugrid.infra.errors import InputError
from accugrid.kinematics.calibrated import calibrated_yaml
from accugrid.kinematics.dh import flange_poses
from accugrid.kinematics.frames import matrix_to_abc, pose_from_xyzabc
from accugrid.kinematics.identification import (
    LAST_LINK,
    harmonic_terms,
    identification_jacobian,
    identify,
    parameter_names,
    parameter_units,
    pose_set,
)
from accugrid.kinematics.joint_errors import Harmonic, JointErrors
from accugrid.kinematics.robot import Robot, load_robot

TOOL = pose_from_xyzabc([20.0, -10.0, 250.0, 0.0, 0.0, 0.0])
NOMINAL = load_robot("kr210").with_tool(TOOL)
TABLE1 = load_robot("kr210-paper").errors  # seed Table 1, (6, 4)
# A spread of joint angles a measurement program could visit (deg): A5 away from the wrist
# singularity, A2/A3 in the usual working range.
LOW = np.radians([-60.0, -120.0, 20.0, -150.0, 20.0, -150.0])
HIGH = np.radians([60.0, -40.0, 120.0, 150.0, 110.0, 150.0])


def random_joints(n: int, seed: int) -> np.ndarray:
    return LOW + np.random.default_rng(seed).random((n, 6)) * (HIGH - LOW)


def true_arm(errors: np.ndarray, tcp_offset_mm) -> Robot:
    """The simulated real robot: nominal DH + errors, the tool's position off by tcp_offset."""
    tool = TOOL.copy()
    tool[:3, 3] += tcp_offset_mm
    arm = Robot("true", NOMINAL.dh, NOMINAL.joint_limits_deg, tool, np.asarray(errors))
    return arm.true_robot()


def measured_set(true: Robot, q: np.ndarray, noise_mm: float = 0.0, seed: int = 0):
    """PoseSet of joints q (N, 6) rad: commanded = nominal FK, measured = true FK + noise."""
    nominal = NOMINAL.fk(q)
    measured = true.fk(q)[:, :3, 3]
    measured = measured + np.random.default_rng(seed + 100).normal(0.0, noise_mm, measured.shape)
    return pose_set(
        NOMINAL,
        nominal[:, :3, 3],
        measured,
        abc_deg=matrix_to_abc(nominal[:, :3, :3]),
        joints_deg=np.degrees(q),
    )


# What position-only data cannot tell apart on this robot with this tool, worked out by hand:
# link 6's four errors only move the TCP within the flange (like the TCP offset: identify holds
# them at zero and the TCP takes their share), and the A2 and A3 axes are parallel
# (alpha_2 = 0), so Δd2 and Δd3 shift the arm along the same axis.
REDUNDANT = {"dd2", "dd3", "da6", "dd6", "dalpha6", "dtheta6"}


def tcp_with_last_link(errors: np.ndarray, offset_mm: np.ndarray) -> np.ndarray:
    """The TCP offset (3,) mm identify reports for link 6's ``errors`` (6, 4) and the real TCP
    off by ``offset_mm``: the real TCP seen from the nominal last link, X (t + offset) with X the
    constant nominal-to-real last-link transform, less the nominal tool's translation t."""
    only_last = np.zeros((6, 4))
    only_last[5] = errors[5]
    q = random_joints(3, 77)
    x = np.linalg.inv(flange_poses(NOMINAL.dh, q)) @ flange_poses(
        NOMINAL.dh.with_errors(only_last), q
    )
    np.testing.assert_allclose(x, np.broadcast_to(x[0], x.shape), atol=1e-9)  # constant
    t = TOOL[:3, 3]
    return x[0, :3, :3] @ (t + offset_mm) + x[0, :3, 3] - t


def test_noise_free_errors_in_the_identifiable_subspace_are_recovered_exactly():
    errors = TABLE1.copy()
    errors[1, 1] = errors[2, 1] = 0.0  # Δd2, Δd3
    errors[5] = 0.0  # link 6
    # Every unidentifiable direction lives on REDUNDANT parameters only, so these errors have no
    # component along them, whatever the column scaling.
    data = measured_set(true_arm(errors, np.zeros(3)), random_joints(60, 1))
    result = identify(NOMINAL, data)
    expected = np.concatenate([errors.ravel(), np.zeros(3)])
    mm = np.array([u == "mm" for u in result.units])
    np.testing.assert_allclose(result.x[mm], expected[mm], atol=1e-6)
    np.testing.assert_allclose(result.x[~mm], expected[~mm], atol=1e-9)
    np.testing.assert_allclose(result.robot.errors, errors, atol=1e-6)


def test_noise_free_full_table1_and_tcp_offset_predict_new_poses():
    offset = np.array([0.3, -0.2, 0.1])
    true = true_arm(TABLE1, offset)
    result = identify(NOMINAL, measured_set(true, random_joints(60, 2)))
    assert np.abs(result.residuals).max() < 1e-6
    # parameters that are identifiable alone are the injected ones
    expected = np.concatenate([TABLE1.ravel(), tcp_with_last_link(TABLE1, offset)])
    expected[LAST_LINK] = 0.0
    alone = result.identifiable
    assert np.all(result.x[LAST_LINK] == 0.0) and alone[24:27].all()
    np.testing.assert_allclose(result.x[alone], expected[alone], atol=1e-6)
    # the calibrated model (its true robot) predicts positions at new poses
    q_new = random_joints(200, 3)
    predicted = result.robot.true_robot().fk(q_new)[:, :3, 3]
    np.testing.assert_allclose(predicted, true.fk(q_new)[:, :3, 3], atol=1e-6)


def test_redundant_setup_reports_its_unidentifiable_directions():
    result = identify(NOMINAL, measured_set(true_arm(TABLE1, np.zeros(3)), random_joints(40, 4)))
    names = result.names
    assert result.rank == 27 - 5
    assert {n for n, ok in zip(names, result.identifiable, strict=True) if not ok} == REDUNDANT
    # each reported direction changes no position (first order) at any pose
    jac = identification_jacobian(NOMINAL, random_joints(30, 5)).reshape(-1, 27)
    assert result.null_space.shape == (1, 27)  # dd2 - dd3; link 6 is held at zero
    assert np.abs(jac @ result.null_space.T).max() < 1e-9 * np.abs(jac).max()
    assert result.unidentifiable_text == [
        "+1.000 dd2 -1.000 dd3",
        "da6 dd6 dalpha6 dtheta6 (in the TCP)",
    ]
    # standard deviations: zero noise gives (almost) zero uncertainty
    assert np.all(result.std < 1e-6)


def test_base_frame_adds_d1_and_theta1_to_the_redundant_set_and_fits_the_tracker():
    tracker_T_robot = np.eye(4)
    tracker_T_robot[:3, :3] = Rotation.from_euler("ZYX", [30, 2, -1], degrees=True).as_matrix()
    tracker_T_robot[:3, 3] = [3000.0, -500.0, 200.0]
    q = random_joints(60, 6)
    true = true_arm(TABLE1, np.array([0.3, -0.2, 0.1]))
    nominal = NOMINAL.fk(q)
    in_tracker = true.fk(q)[:, :3, 3] @ tracker_T_robot[:3, :3].T + tracker_T_robot[:3, 3]
    data = pose_set(
        NOMINAL, nominal[:, :3, 3], in_tracker, matrix_to_abc(nominal[:, :3, :3]), np.degrees(q)
    )
    result = identify(NOMINAL, data, base_frame=True)
    tied = {n for n, ok in zip(result.names, result.identifiable, strict=True) if not ok}
    assert tied == REDUNDANT | {"dd1", "base_z", "dtheta1", "base_rz"}
    # the model and the fitted tracker frame reproduce the tracker's positions at new poses
    q_new = random_joints(100, 7)
    cal = result.robot.true_robot().fk(q_new)[:, :3, 3]
    fitted = result.tracker_T_robot
    predicted = cal @ fitted[:3, :3].T + fitted[:3, 3]
    actual = true.fk(q_new)[:, :3, 3] @ tracker_T_robot[:3, :3].T + tracker_T_robot[:3, 3]
    np.testing.assert_allclose(predicted, actual, atol=1e-6)


def test_noisy_fit_cross_validation_predicts_the_held_out_residual():
    true = true_arm(TABLE1, np.array([0.3, -0.2, 0.1]))
    noise = 0.02
    result = identify(NOMINAL, measured_set(true, random_joints(60, 8), noise, seed=8), folds=5)
    cv = result.cross_validation
    assert cv.folds == 5
    # a separate held-out session: 300 new poses measured with the same noise
    q_new = random_joints(300, 9)
    measured = true.fk(q_new)[:, :3, 3]
    measured += np.random.default_rng(9).normal(0.0, noise, measured.shape)
    held_out = measured - result.robot.true_robot().fk(q_new)[:, :3, 3]
    actual_rms = np.sqrt(np.mean(held_out**2, axis=0))
    # 60 rows per axis estimate an RMS to ~10 %; over several seeds the ratio of the overall RMS
    # stayed within 0.89..1.16, per axis within 0.75..1.36
    overall = np.sqrt(np.mean(cv.rms_mm**2)), np.sqrt(np.mean(actual_rms**2))
    assert overall[0] == pytest.approx(overall[1], rel=0.25)
    np.testing.assert_allclose(cv.rms_mm, actual_rms, rtol=0.4)
    # fitted residuals are at the noise level, not below it by much (no over-fitting)
    assert np.all(result.rms_mm > 0.7 * noise) and np.all(result.rms_mm < 1.3 * noise)
    # the standard deviations cover the actual parameter errors of the identifiable ones
    expected = np.concatenate([TABLE1.ravel(), tcp_with_last_link(TABLE1, [0.3, -0.2, 0.1])])
    alone = result.identifiable
    z = np.abs(result.x[alone] - expected[alone]) / result.std[alone]
    assert z.max() < 5.0


def test_gross_outlier_is_reported_by_row_and_does_not_spoil_the_fit():
    true = true_arm(TABLE1, np.zeros(3))
    q = random_joints(60, 10)
    clean = measured_set(true, q, 0.01, seed=10)
    measured = clean.measured.copy()
    measured[17] += [1.5, -1.0, 0.5]
    labels = [f"line {i + 2}" for i in range(60)]
    nominal = NOMINAL.fk(q)
    data = pose_set(
        NOMINAL,
        nominal[:, :3, 3],
        measured,
        matrix_to_abc(nominal[:, :3, :3]),
        np.degrees(q),
        labels=labels,
    )
    result = identify(NOMINAL, data)
    assert "line 19" in result.outliers
    q_new = random_joints(100, 11)
    error = result.robot.true_robot().fk(q_new)[:, :3, 3] - true.fk(q_new)[:, :3, 3]
    assert np.abs(error).max() < 0.1  # a least-squares fit would carry the 1.9 mm outlier


def test_without_logged_joints_the_nominal_ik_gives_the_joints():
    q = random_joints(40, 12)
    nominal = NOMINAL.fk(q)
    abc = matrix_to_abc(nominal[:, :3, :3])
    # the Status of each pose, as a KUKA program would carry it
    status = NOMINAL.ik(nominal).status  # default configuration
    data = pose_set(NOMINAL, nominal[:, :3, 3], nominal[:, :3, 3], abc, status=status)
    reached = NOMINAL.fk(data.q)[:, :3, 3]
    np.testing.assert_allclose(reached, nominal[:, :3, 3], atol=1e-6)


def test_repeats_share_a_group():
    q = np.repeat(random_joints(30, 13), 3, axis=0)
    data = measured_set(true_arm(TABLE1, np.zeros(3)), q, 0.01)
    assert data.poses == 30
    np.testing.assert_array_equal(data.group[0::3], data.group[1::3])


def test_parameter_names_follow_eq2_layout():
    names = parameter_names(base_frame=True)
    assert names[:4] == ["da1", "dd1", "dalpha1", "dtheta1"]
    assert names[20:24] == ["da6", "dd6", "dalpha6", "dtheta6"]
    assert names[24:] == ["tool_x", "tool_y", "tool_z"] + [
        "base_x",
        "base_y",
        "base_z",
        "base_rx",
        "base_ry",
        "base_rz",
    ]


def test_jacobian_matches_finite_differences_of_the_model():
    q = random_joints(5, 14)
    x = np.concatenate([TABLE1.ravel(), [0.3, -0.2, 0.1]])
    jac = identification_jacobian(NOMINAL, q, x)

    def positions(v):
        tool = TOOL.copy()
        tool[:3, 3] += v[24:27]
        arm = Robot("x", NOMINAL.dh, NOMINAL.joint_limits_deg, tool, v[:24].reshape(6, 4))
        return arm.true_robot().fk(q)[:, :3, 3]

    for k in range(27):
        h = 1e-4 if k % 4 in (0, 1) or k >= 24 else 1e-7
        step = np.zeros(27)
        step[k] = h
        numeric = (positions(x + step) - positions(x - step)) / (2 * h)
        np.testing.assert_allclose(
            jac[:, :, k], numeric, atol=1e-5 * max(1.0, np.abs(numeric).max())
        )


# ---- bad data -------------------------------------------------------------------------------


def test_fewer_poses_than_identifiable_parameters():
    data = measured_set(true_arm(TABLE1, np.zeros(3)), random_joints(15, 15))
    with pytest.raises(InputError, match="15 distinct poses for 22 identifiable parameters"):
        identify(NOMINAL, data)


def test_poses_in_one_orientation():
    # 40 positions in a box, all at A 0 B 90 C 0 (as a grid measurement)
    rng = np.random.default_rng(16)
    points = np.column_stack(
        [rng.uniform(1200, 2000, 40), rng.uniform(-500, 500, 40), rng.uniform(900, 1700, 40)]
    )
    abc = np.tile([0.0, 90.0, 0.0], (40, 1))
    data = pose_set(NOMINAL, points, points, abc)
    with pytest.raises(InputError, match="one orientation"):
        identify(NOMINAL, data)


def test_poses_in_one_plane():
    q = random_joints(200, 17)
    nominal = NOMINAL.fk(q)
    z = nominal[:, 2, 3]
    keep = np.argsort(np.abs(z - np.median(z)))[:40]  # 40 poses within a few mm of one height
    poses = nominal[keep]
    poses[:, 2, 3] = np.median(z)
    data = pose_set(NOMINAL, poses[:, :3, 3], poses[:, :3, 3], matrix_to_abc(poses[:, :3, :3]))
    with pytest.raises(InputError, match="one plane"):
        identify(NOMINAL, data)


def logged_pose_set(offset_mm: float):
    """30 rows whose logged joints (4 decimals) reach their commanded position, except rows 4
    and 9, commanded ``offset_mm`` higher than their joints reach."""
    q = random_joints(30, 18)
    nominal = NOMINAL.fk(q)
    commanded = nominal[:, :3, 3].copy()
    commanded[[4, 9]] += [0.0, 0.0, offset_mm]  # two rows commanded elsewhere than their joints
    return pose_set(
        NOMINAL,
        commanded,
        commanded,
        matrix_to_abc(nominal[:, :3, :3]),
        np.round(np.degrees(q), 4),
        joint_decimals=np.full((30, 6), 4),
        position_decimals=np.full((30, 3), 4),
        labels=[f"line {i + 2}" for i in range(30)],
    )


def test_logged_joints_off_by_a_controller_calibration_are_measured():
    """Tenths of a mm between the commanded positions and the nominal FK of the logged joints:
    a controller's own calibration, measured (mean and max over the rows, the rows beyond
    the round-off) and taken as what the robot did."""
    data = logged_pose_set(0.5)
    assert data.controller.rows == 2
    # the joints' 4 printed decimals move the TCP by up to a few microns
    assert data.controller.max_mm == pytest.approx(0.5, abs=0.005)
    assert data.controller.mean_mm == pytest.approx(1.0 / 30, abs=0.005)


def test_logged_joints_far_off_are_refused_naming_the_rows():
    with pytest.raises(
        InputError,
        match=r"2 of 30 rows.*line 6 \((49\.99|50\.00)\d\d mm\), line 11 .*robot or the base wrong",
    ):
        logged_pose_set(50.0)


def test_logged_joints_rounded_to_their_decimals_pass():
    q = np.radians(np.round(np.degrees(random_joints(30, 19)), 3))
    commanded = np.round(NOMINAL.fk(q)[:, :3, 3] + 0.01, 4)  # joints lost ~0.0005 deg
    q_logged = np.round(np.degrees(q), 3)
    data = pose_set(
        NOMINAL,
        commanded,
        commanded,
        joints_deg=q_logged,
        joint_decimals=np.full((30, 6), 3),
        position_decimals=np.full((30, 3), 4),
    )
    assert len(data) == 30 and data.controller.rows == 0


def test_rank_loss_beyond_the_structural_directions_is_named():
    # every pose with A4 = A6 = 0 and A5 fixed: the wrist never turns, so link 5/6 errors and
    # the TCP offset blur into each other beyond the structural set
    q = random_joints(60, 20)
    q[:, 3] = 0.0
    q[:, 4] = np.radians(60.0)
    q[:, 5] = 0.0
    data = measured_set(true_arm(TABLE1, np.zeros(3)), q)
    with pytest.raises(InputError, match="more parameter combinations unidentifiable"):
        identify(NOMINAL, data)


# ---- compliance -----------------------------------------------------------------------------

REALISTIC = load_robot("kr210-realistic")


def test_compliance_of_a2_a3_is_recovered_with_the_geometric_errors():
    nominal = REALISTIC.with_tool(TOOL)  # its masses are the gravity model
    errors = TABLE1.copy()
    errors[1, 1] = errors[2, 1] = 0.0
    errors[5] = 0.0
    c = np.array([0.0, 1.0e-7, 2.0e-7, 0.0, 0.0, 0.0])
    moves = JointErrors.from_compliance(c, REALISTIC.joint_errors.masses)
    true = Robot("t", nominal.dh, nominal.joint_limits_deg, TOOL, errors, "", moves).true_robot()
    q = random_joints(60, 21)
    commanded = nominal.fk(q)
    data = pose_set(
        nominal,
        commanded[:, :3, 3],
        true.fk(q)[:, :3, 3],
        matrix_to_abc(commanded[:, :3, :3]),
        np.degrees(q),
    )
    result = identify(nominal, data, compliance=True)
    assert result.names[-2:] == ["compliance_a2", "compliance_a3"]
    assert result.units[-2:] == ["rad/Nm", "rad/Nm"]
    np.testing.assert_allclose(result.x[-2:], c[1:3], rtol=1e-6)
    np.testing.assert_allclose(result.robot.errors, errors, atol=1e-6)
    # the calibrated robot's true arm applies the identified compliance
    np.testing.assert_allclose(result.robot.joint_errors.compliance, c, rtol=1e-6, atol=1e-15)
    q_new = random_joints(100, 22)
    np.testing.assert_allclose(
        result.robot.true_robot().fk(q_new)[:, :3, 3], true.fk(q_new)[:, :3, 3], atol=1e-6
    )
    # a geometric model alone cannot follow the sag
    geometric = identify(nominal, data)
    assert np.abs(geometric.residuals).max() > 0.01


def test_compliance_needs_a_gravity_model():
    data = measured_set(true_arm(TABLE1, np.zeros(3)), random_joints(40, 23))
    with pytest.raises(InputError, match="no gravity model"):
        identify(NOMINAL, data, compliance=True)


# ---- pose selection -------------------------------------------------------------------------


def _log_det(q: np.ndarray) -> float:
    """log det of JᵀJ of the column-scaled Jacobian, identifiable part (test's own SVD)."""
    jac = identification_jacobian(NOMINAL, q).reshape(-1, 27)
    reference = identification_jacobian(NOMINAL, random_joints(200, 99)).reshape(-1, 27)
    scale = np.sqrt(np.mean(reference**2, axis=0))
    vt = np.linalg.svd(reference / scale)[2][:22]  # the 22 identifiable directions
    return float(np.linalg.slogdet(((jac / scale) @ vt.T).T @ ((jac / scale) @ vt.T))[1])


def test_greedy_selection_beats_random_subsets_of_the_same_size():
    from accugrid.kinematics.identification import select_poses

    candidates = random_joints(400, 30)
    chosen, o1 = select_poses(NOMINAL, candidates, 30)
    assert len(set(chosen.tolist())) == 30
    best = _log_det(candidates[chosen])
    rng = np.random.default_rng(31)
    randoms = [_log_det(candidates[rng.choice(400, 30, replace=False)]) for _ in range(20)]
    assert best > max(randoms)
    # and identification from the chosen poses has a better O1 than from a random 30
    true = true_arm(TABLE1, np.zeros(3))
    picked = identify(NOMINAL, measured_set(true, candidates[chosen]))
    random_fit = identify(
        NOMINAL, measured_set(true, candidates[rng.choice(400, 30, replace=False)])
    )
    # identify scales the columns by the data, select_poses by the reference set: with the
    # same scale the two O1 agree to rounding; as they are, within a few 1e-3
    assert picked.o1 == pytest.approx(o1, rel=5e-3)
    assert picked.o1 > random_fit.o1


def test_selection_refuses_impossible_counts():
    from accugrid.kinematics.identification import select_poses

    with pytest.raises(InputError, match="cannot choose 50 poses from 40"):
        select_poses(NOMINAL, random_joints(40, 32), 50)
    with pytest.raises(InputError, match="choose at least 8"):
        select_poses(NOMINAL, random_joints(40, 32), 5)


# ---- property: any injected errors off the unidentifiable directions come back ----------------

from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from hypothesis.extra.numpy import arrays  # noqa: E402

_ALONE = [i for i, n in enumerate(parameter_names()) if n not in REDUNDANT]


@settings(max_examples=15)
@given(
    seed=st.integers(0, 2**16),
    size_mm=st.floats(0.01, 10.0),
    size_rad=st.floats(1e-5, 1e-2),
)
def test_injected_errors_are_recovered(seed, size_mm, size_rad):
    rng = np.random.default_rng(seed)
    x = np.zeros(27)
    units = np.array([u == "mm" for u in parameter_units()])
    x[_ALONE] = rng.uniform(-1, 1, len(_ALONE)) * np.where(units[_ALONE], size_mm, size_rad)
    data = measured_set(true_arm(x[:24].reshape(6, 4), x[24:]), random_joints(50, seed))
    result = identify(NOMINAL, data)
    np.testing.assert_allclose(result.x, x, atol=1e-6)


# ---- reducer harmonics ----------------------------------------------------------------------

# Orders as a reducer data sheet would give them: eccentricity (1) and an output stage (7, 40).
HARMONIC_TERMS = ((1, 1), (1, 40), (2, 1), (2, 7), (3, 7), (5, 2))


def harmonic_arm(amplitudes: np.ndarray, phases: np.ndarray) -> tuple[Robot, np.ndarray]:
    """The true arm (identifiable DH errors, compliance, HARMONIC_TERMS with these amplitudes
    (rad) and phases (rad)) and the sine/cosine coefficients (12,) identify should find."""
    errors = TABLE1.copy()
    errors[1, 1] = errors[2, 1] = 0.0
    errors[5] = 0.0
    terms = tuple(
        Harmonic(axis, order, float(a), float(p))
        for (axis, order), a, p in zip(HARMONIC_TERMS, amplitudes, phases, strict=True)
    )
    c = np.array([0.0, 1.0e-7, 2.0e-7, 0.0, 0.0, 0.0])
    moves = JointErrors(compliance=c, masses=REALISTIC.joint_errors.masses, harmonics=terms)
    nominal = REALISTIC.with_tool(TOOL)
    true = Robot("t", nominal.dh, nominal.joint_limits_deg, TOOL, errors, "", moves)
    # a·sin(kA + φ) = a·cos φ · sin kA + a·sin φ · cos kA
    coefficients = np.column_stack([amplitudes * np.cos(phases), amplitudes * np.sin(phases)])
    return true.true_robot(), coefficients.ravel()


@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    amplitudes=arrays(float, 6, elements=st.floats(2e-5, 2e-4)),
    phases=arrays(float, 6, elements=st.floats(-np.pi, np.pi)),
)
def test_noise_free_harmonics_of_known_orders_are_recovered(amplitudes, phases):
    true, coefficients = harmonic_arm(amplitudes, phases)
    nominal = REALISTIC.with_tool(TOOL)
    data = measured_set(true, random_joints(90, 31))  # kr210-realistic's DH is kr210's
    result = identify(nominal, data, compliance=True, harmonics=HARMONIC_TERMS)
    assert result.names[-2:] == ["harmonic_a5_k2_sin", "harmonic_a5_k2_cos"]
    assert result.units[-12:] == ["rad"] * 12
    # the harmonics' coefficients are not tied to any other parameter on this robot
    assert result.identifiable[-12:].all()
    np.testing.assert_allclose(result.x[-12:], coefficients, atol=1e-9)
    # the calibrated arm lands where the true arm does
    q_new = random_joints(100, 32)
    np.testing.assert_allclose(
        result.robot.true_robot().fk(q_new)[:, :3, 3], true.fk(q_new)[:, :3, 3], atol=1e-6
    )
    # without the harmonic terms the same data leave a residual far above the 1e-6 mm fit
    assert np.abs(identify(nominal, data, compliance=True).residuals).max() > 0.005


def test_identified_harmonics_survive_the_calibrated_yaml(tmp_path):
    true, _ = harmonic_arm(np.full(6, 1e-4), np.linspace(-3.0, 3.0, 6))
    nominal = REALISTIC.with_tool(TOOL)
    data = measured_set(true, random_joints(90, 33))
    result = identify(nominal, data, compliance=True, harmonics=HARMONIC_TERMS)
    path = tmp_path / "cal.yaml"
    path.write_text(calibrated_yaml(result.robot))
    reloaded = load_robot(path)
    kept = [(h.axis, h.order) for h in reloaded.joint_errors.harmonics]
    assert kept == list(HARMONIC_TERMS)
    q_new = random_joints(100, 34)
    np.testing.assert_allclose(
        reloaded.true_robot().fk(q_new)[:, :3, 3], true.fk(q_new)[:, :3, 3], atol=1e-6
    )


def test_harmonic_terms_are_checked():
    assert harmonic_terms([(2, 7), (2, 7), (3, 1)]) == ((2, 7), (3, 1))
    with pytest.raises(InputError, match="axis 1..6"):
        harmonic_terms([(7, 1)])
    with pytest.raises(InputError, match="order 1..100000"):
        harmonic_terms([(2, 0)])
    with pytest.raises(InputError, match="order 1..100000"):
        harmonic_terms([(2, 100_001)])
    with pytest.raises(InputError, match="more than 60 harmonic terms"):
        harmonic_terms((2, k) for k in range(1, 1_000_000))  # refused at the 61st


@settings(max_examples=25)
@given(st.permutations(range(4)), st.lists(st.sampled_from([-1.0, 1.0]), min_size=4, max_size=4))
def test_unidentifiable_directions_come_in_one_order_whatever_the_svd_gives(order, signs):
    """The SVD orders directions whose singular values are all ~0 by rounding noise, which differs
    between CPUs and BLAS kernels: their readable basis comes out in the order of its pivots'
    parameters whatever order and signs the null-space basis arrives in."""
    from accugrid.kinematics.identification import _readable_null

    null = np.zeros((8, 4))
    null[[0, 1], 0] = [1.0, -1.0]  # da1 - dd1
    null[[2, 5], 1] = [0.6, 0.8]
    null[4, 2] = 1.0
    null[[3, 6, 7], 3] = [0.2, 0.9, -0.3]
    null /= np.linalg.norm(null, axis=0)
    expected = _readable_null(null)
    shuffled = _readable_null(null[:, list(order)] * np.array(signs))
    assert [int(np.argmax(np.abs(c) > 0.05)) for c in expected.T] == [0, 2, 3, 4]
    assert np.allclose(shuffled, expected, atol=1e-12)


def test_an_unidentifiable_pair_reads_the_same_whichever_of_its_equal_components_leads():
    """da6 - tool_x: which of the two equal components is the larger is rounding noise."""
    from accugrid.kinematics.identification import _direction_text, _readable_null

    names = ["da6", "tool_x"]
    texts = {
        _direction_text(_readable_null(np.array([[a], [b]]) / np.hypot(a, b))[:, 0], names)
        for a, b in ((1.0, -1.0 + 1e-15), (1.0 - 1e-15, -1.0), (-1.0, 1.0 - 1e-15))
    }
    assert texts == {"+1.000 da6 -1.000 tool_x"}
