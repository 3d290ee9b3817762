"""Joint errors of the true robot: compliance under gravity, transmission harmonics, thermal."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.joint_errors import GRAVITY_MPS2, Harmonic, JointErrors, PointMass
from accugrid.kinematics.robot import load_robot

ROBOTS = Path(__file__).resolve().parents[1] / "kinematics" / "robots"
HOME = np.radians([[0.0, -90.0, 90.0, 0.0, 0.0, 0.0]])
NOMINAL = load_robot("kr210")


def joints(n: int):
    lo, hi = np.radians(NOMINAL.joint_limits_deg).T
    lo, hi = lo + 0.1, hi - 0.1
    return arrays(float, (n, 6), elements=st.floats(0.0, 1.0)).map(lambda u: lo + u * (hi - lo))


def test_compliance_at_home_is_the_hand_computed_torque():
    # At home the link arm stands upright (A2 axis at X 350, Z 675; A3 axis 1150 mm above it) and
    # the arm is horizontal: the wrist point is 1200 mm in front of both axes (X 1550, Z 1784).
    # 100 kg at the wrist point: 100 * g * 1.2 m on A2 and on A3, pulling the arm down, i.e. in
    # the positive KUKA sense (A2 = -5 deg is the arm lowered forward). 50 kg halfway up the
    # upright link arm has no lever about A2.
    masses = [PointMass(3, 100.0, (0.0, 0.0, 1200.0)), PointMass(2, 50.0, (-575.0, 0.0, 0.0))]
    c = np.array([0.0, 2e-7, 3e-7, 0.0, 0.0, 0.0])
    errors = JointErrors.from_compliance(c, masses)
    tau = 100.0 * GRAVITY_MPS2 * 1.2
    np.testing.assert_allclose(
        errors.gravity_torques(NOMINAL.dh, HOME), [[0, tau, tau, 0, 0, 0]], atol=1e-9
    )
    np.testing.assert_allclose(errors.delta(NOMINAL.dh, HOME), [c * [0, tau, tau, 0, 0, 0]])


@given(joints(4))
def test_gravity_torque_is_minus_the_gradient_of_the_potential_energy(q):
    # Independent of the torque code: V = m g z(q) from the robot's own FK with the mass as a tool.
    at = (120.0, -40.0, 300.0)
    errors = JointErrors.from_compliance(np.zeros(6), [PointMass(6, 30.0, at)])
    probe = NOMINAL.with_tool(pose_from_xyzabc([*at, 0.0, 0.0, 0.0]))
    h = 1e-6
    expected = np.empty((len(q), 6))
    for j in range(6):
        step = np.zeros(6)
        step[j] = h
        dz_mm = probe.fk(q + step)[:, 2, 3] - probe.fk(q - step)[:, 2, 3]
        expected[:, j] = -30.0 * GRAVITY_MPS2 * dz_mm * 1e-3 / (2 * h)
    np.testing.assert_allclose(errors.gravity_torques(NOMINAL.dh, q), expected, atol=1e-4)


@given(joints(3), arrays(float, 6, elements=st.floats(0.0, 1e-6)))
def test_compliance_delta_is_linear_in_c_with_derivative_the_torque(q, c):
    masses = [PointMass(3, 200.0, (0.0, 0.0, 400.0)), PointMass(4, 60.0, (0.0, 0.0, 0.0))]
    tau = JointErrors.from_compliance(np.zeros(6), masses).gravity_torques(NOMINAL.dh, q)
    np.testing.assert_allclose(
        JointErrors.from_compliance(c, masses).delta(NOMINAL.dh, q), c * tau, rtol=1e-12, atol=0
    )


def test_harmonics_add_their_sines_to_their_axis():
    errors = JointErrors(harmonics=(Harmonic(2, 3, 1e-4, 0.5), Harmonic(2, 1, 2e-4)))
    q = np.radians([[10.0, -60.0, 80.0, 5.0, 30.0, 0.0]])
    want = 1e-4 * np.sin(3 * q[0, 1] + 0.5) + 2e-4 * np.sin(q[0, 1])
    np.testing.assert_allclose(errors.delta(NOMINAL.dh, q), [[0, want, 0, 0, 0, 0]], atol=1e-18)


@given(joints(5))
def test_realistic_true_fk_is_the_paper_true_fk_at_the_perturbed_joints(q):
    realistic, paper = load_robot("kr210-realistic"), load_robot("kr210-paper")
    np.testing.assert_array_equal(realistic.dh.a, paper.dh.a)
    np.testing.assert_array_equal(realistic.errors, paper.errors)
    paper_true = paper.true_robot()
    delta = realistic.joint_errors.delta(paper_true.dh, q)
    assert np.abs(delta).max() > 1e-5  # the joint-error term is really there
    np.testing.assert_allclose(
        realistic.true_robot().fk(q), paper_true.fk(q + delta), atol=1e-9, rtol=0
    )


def test_paper_robot_has_no_joint_errors():
    paper = load_robot("kr210-paper")
    assert paper.joint_errors is None and paper.true_robot().fk_joint_errors is None


def _robot_file(tmp_path: Path, extra: str) -> Path:
    path = tmp_path / "robot.yaml"
    path.write_text((ROBOTS / "kr210.yaml").read_text() + extra)
    return path


def test_thermal_growth_scales_lengths_only(tmp_path):
    extra = "joint_errors:\n  thermal: {delta_t_k: 10.0, expansion_per_k: 1.0e-5}\n"
    robot = load_robot(_robot_file(tmp_path, extra))
    true = robot.true_robot()
    np.testing.assert_allclose(true.dh.a, NOMINAL.dh.a * 1.0001)
    np.testing.assert_allclose(true.dh.d, NOMINAL.dh.d * 1.0001)
    np.testing.assert_array_equal(true.dh.alpha, NOMINAL.dh.alpha)
    # Every length grows by 1e-4, so the flange of the home pose moves away from the base by 1e-4.
    np.testing.assert_allclose(true.fk(HOME)[0, :3, 3], NOMINAL.fk(HOME)[0, :3, 3] * 1.0001)


@pytest.mark.parametrize(
    ("section", "message"),
    [
        (
            "  compliance_rad_per_nm: [0, 1.0e-7, 0, 0, 0, 0]\n",
            r"robot\.yaml:\d+:3: 'joint_errors\.compliance_rad_per_nm' needs 'masses'",
        ),
        (
            "  harmonics:\n    - {axis: 7, order: 1, amplitude_rad: 1.0e-4}\n",
            r"'joint_errors\.harmonics\[0\]\.axis' must be a whole number 1\.\.6",
        ),
        (
            "  masses:\n    - {link: 2, kg: -1, at_mm: [0, 0, 0]}\n",
            r"'joint_errors\.masses\[0\]\.kg' must not be negative",
        ),
        (
            "  masses:\n    - {link: 2, kg: 1, at_mm: [0, 0]}\n",
            r"'joint_errors\.masses\[0\]\.at_mm' must have 3 entries",
        ),
    ],
)
def test_bad_joint_errors_section_is_a_located_error(tmp_path, section, message):
    path = _robot_file(tmp_path, "joint_errors:\n" + section)
    with pytest.raises(InputError, match=message):
        load_robot(path)


def test_realistic_robot_makes_the_seed_study_choose_the_seeds_step(tmp_path, capsys):
    # Seed Sec. 5 chose 200 mm on the real KR210 (thresholds 200-250 mm in X and Z); the
    # geometric-only kr210-paper chooses 440 mm. Default study settings = the seed's design.
    from accugrid.app.cli import main

    assert main(["study", "--robot", "kr210-realistic", "-o", str(tmp_path / "s")]) == 0
    out = capsys.readouterr().out
    assert "step 200 mm chosen" in out
    threshold_z = float(out.split("threshold step Z: ")[1].split(" mm")[0])
    assert 200.0 <= threshold_z <= 250.0
