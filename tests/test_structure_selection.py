"""The structure `identify` chooses from the data: mass-free gravity groups, the robot family,
selection by cross-validation (dominant terms found, noise chooses nothing, pinned terms kept,
deterministic) and its refusals."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import yaml
from hypothesis import Phase, assume, given, settings
from hypothesis import strategies as st

from accugrid.app.cli import main
from accugrid.infra.errors import InputError
from accugrid.kinematics.calibrated import calibrated_yaml
from accugrid.kinematics.candidates import gravity_terms, reference_joints
from accugrid.kinematics.frames import matrix_to_abc, pose_from_xyzabc
from accugrid.kinematics.identification import identify, pose_set
from accugrid.kinematics.joint_errors import Harmonic, JointErrors, PointMass, gravity_basis
from accugrid.kinematics.robot import STRUCTURE_SCHEMA, Robot, load_robot
from accugrid.kinematics.robot_family import MAX_FAMILY_ORDER, random_robot
from accugrid.kinematics.structure import SCREEN_KEEP, identify_structure, screen_keep

TOOL = pose_from_xyzabc([20.0, -10.0, 250.0, 0.0, 0.0, 0.0])
NOMINAL = load_robot("kr210").with_tool(TOOL)
TABLE1 = load_robot("kr210-paper").errors
LOW = np.radians([-60.0, -120.0, 20.0, -150.0, 20.0, -150.0])
HIGH = np.radians([60.0, -40.0, 120.0, 150.0, 110.0, 150.0])
NOISE_MM = 0.02


def joints(n: int, seed: int) -> np.ndarray:
    return LOW + np.random.default_rng(seed).random((n, 6)) * (HIGH - LOW)


def session(true: Robot, q: np.ndarray, repeats: int = 2, seed: int = 0, noise_mm=NOISE_MM):
    """PoseSet: commanded = nominal FK of q (N, 6), measured = true FK + noise, each pose
    ``repeats`` times."""
    q = np.repeat(q, repeats, axis=0)
    commanded = NOMINAL.fk(q)
    measured = true.fk(q)[:, :3, 3]
    measured = measured + np.random.default_rng(seed).normal(0.0, noise_mm, measured.shape)
    abc = matrix_to_abc(commanded[:, :3, :3])
    return pose_set(NOMINAL, commanded[:, :3, 3], measured, abc, np.degrees(q))


def arm(harmonics=(), joint_errors: JointErrors | None = None) -> Robot:
    """The real arm: Table 1 DH errors, these harmonics (or joint errors), the TCP 0.3 mm off."""
    tool = TOOL.copy()
    tool[:3, 3] += [0.3, -0.2, 0.1]
    moves = joint_errors or (JointErrors(harmonics=tuple(harmonics)) if harmonics else None)
    robot = Robot("true", NOMINAL.dh, NOMINAL.joint_limits_deg, tool, TABLE1, joint_errors=moves)
    return robot.true_robot()


def random_masses(rng) -> tuple[PointMass, ...]:
    return tuple(
        PointMass(link, float(rng.uniform(10, 300)), tuple(rng.normal(0, 300, 3)))
        for link in (2, 3, 4, 6)
    )


# -- gravity without masses ---------------------------------------------------------------------


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 10_000))
def test_gravity_moments_reproduce_compliance_under_masses(seed):
    """c · τ(masses) is the same δ as the moments c·m, c·m·r per link (linear in them)."""
    rng = np.random.default_rng(seed)
    masses = random_masses(rng)
    compliance = np.zeros(6)
    compliance[1:3] = rng.uniform(1e-8, 3e-7, 2)
    moments = np.zeros((6, 6, 4))
    for axis in (1, 2):
        for m in masses:
            if m.link > axis:
                moments[axis, m.link - 1] += compliance[axis] * m.kg * np.array([1.0, *m.at_mm])
    q = reference_joints(NOMINAL, 50, seed)
    with_masses = JointErrors(compliance, masses).delta(NOMINAL.dh, q)
    without = JointErrors(moments=moments).delta(NOMINAL.dh, q)
    np.testing.assert_allclose(without, with_masses, rtol=1e-9, atol=1e-15)


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 10_000))
def test_gravity_groups_span_any_lumped_masses(seed):
    """The A2/A3 deflection of any masses on links 2-6 is a combination of the groups' functions."""
    rng = np.random.default_rng(seed)
    compliance = np.array([0.0, 1e-7, 2e-7, 0.0, 0.0, 0.0])
    truth = JointErrors(compliance, random_masses(rng))
    q = reference_joints(NOMINAL, 300, seed + 1)
    delta = truth.delta(NOMINAL.dh, q)
    unit = gravity_basis(NOMINAL.dh, q, truth.gravity_mps2)
    for axis in (2, 3):
        functions = np.column_stack(
            [t.functions(unit) for t in gravity_terms(NOMINAL) if t.axis == axis]
        )
        w = np.linalg.lstsq(functions, delta[:, axis - 1], rcond=None)[0]
        left = delta[:, axis - 1] - functions @ w
        assert np.abs(left).max() <= 1e-6 * np.abs(delta[:, axis - 1]).max()


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from(["kr210", "ur10"]))
def test_every_axis_gravity_loads_has_gravity_groups(seed, name):
    """Compliance on every axis under any masses: the deflection of each axis gravity loads is a
    combination of that axis's groups (a UR's A4 carries the wrist like A2, A3 carry the arm);
    A1, along gravity on a floor-mounted arm, carries no torque and has none."""
    robot = load_robot(name)
    rng = np.random.default_rng(seed)
    truth = JointErrors(np.full(6, 1e-7), random_masses(rng))
    q = reference_joints(robot, 300, seed + 1)
    delta = truth.delta(robot.dh, q)
    unit = gravity_basis(robot.dh, q, truth.gravity_mps2)
    terms = gravity_terms(robot)
    assert {t.axis for t in terms} == {2, 3, 4, 5, 6}
    assert np.abs(delta[:, 0]).max() <= 1e-12
    for axis in range(2, 7):
        functions = np.column_stack([t.functions(unit) for t in terms if t.axis == axis])
        w = np.linalg.lstsq(functions, delta[:, axis - 1], rcond=None)[0]
        left = delta[:, axis - 1] - functions @ w
        assert np.abs(left).max() <= 1e-6 * np.abs(delta[:, axis - 1]).max()


def test_gravity_moments_round_trip_through_the_calibrated_yaml(tmp_path):
    rng = np.random.default_rng(3)
    moments = np.zeros((6, 6, 4))
    moments[1, 1:] = rng.normal(0, 1e-5, (5, 4))
    moments[2, 2:] = rng.normal(0, 1e-5, (4, 4))
    errors = JointErrors(moments=moments, harmonics=(Harmonic(2, 7, 1e-4, 0.3),))
    robot = replace(NOMINAL, errors=TABLE1, joint_errors=errors)
    path = tmp_path / "cal.yaml"
    path.write_text(calibrated_yaml(robot))
    loaded = load_robot(path)
    np.testing.assert_array_equal(loaded.joint_errors.moments, moments)
    q = joints(30, 4)
    np.testing.assert_allclose(
        loaded.true_robot().fk(q), robot.true_robot().fk(q), rtol=0, atol=1e-9
    )
    assert (
        np.abs(
            robot.true_robot().fk(q) - replace(robot, joint_errors=None).true_robot().fk(q)
        ).max()
        > 0.01
    )


def test_a_gravity_moment_on_a_link_the_axis_does_not_carry_is_refused(tmp_path):
    text = calibrated_yaml(NOMINAL).replace(
        "tool:",
        "joint_errors:\n  gravity_moments:\n  - {axis: 3, link: 2, c_kg: 1.0e-5, "
        "c_kg_mm: [0, 0, 0]}\ntool:",
    )
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(InputError, match="must be a link the axis carries") as error:
        load_robot(path)
    assert error.value.path is not None


# -- the family of simulated robots -------------------------------------------------------------


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 100_000))
def test_family_robots_are_drawn_within_their_stated_ranges_and_repeat_per_seed(seed):
    robot = random_robot(seed)
    again = random_robot(seed)
    np.testing.assert_array_equal(robot.robot.errors, again.robot.errors)
    assert robot.harmonics == again.harmonics
    np.testing.assert_array_equal(robot.tcp_offset_mm, again.tcp_offset_mm)
    assert np.linalg.norm(robot.tcp_offset_mm) <= 1.0
    per_axis = np.bincount([a for a, _ in robot.harmonics], minlength=7)[1:]
    assert per_axis.max() <= 4
    for h in robot.robot.joint_errors.harmonics:
        assert 1 <= h.order <= MAX_FAMILY_ORDER and 2e-5 <= h.amplitude_rad <= 2e-4
    assert robot.nominal.errors is None and robot.nominal.joint_errors is None
    q = joints(5, seed)
    # the true arm differs from the nominal model, and the session measures the true arm
    s = robot.session(q, repeats=1, noise_tracker_mm=0.0, noise_repeat_mm=0.0)
    np.testing.assert_allclose(s.measured, robot.true_robot().fk(q)[:, :3, 3], atol=1e-9)
    assert np.abs(s.measured - s.commanded).max() > 0.05


# -- selection ----------------------------------------------------------------------------------


@pytest.mark.slow
@settings(max_examples=4, deadline=None, derandomize=True, phases=(Phase.generate,))
@given(
    st.lists(
        st.tuples(st.integers(1, 3), st.integers(2, 10), st.floats(0.0, 2 * np.pi)),
        min_size=1,
        max_size=3,
        unique_by=lambda t: (t[0], t[1]),
    )
)
def test_dominant_harmonics_are_found(terms):
    """Harmonics of 2e-4 rad on A1-A3 whose effect beyond what the DH errors and TCP can absorb
    is at least 4x the noise floor (the DH + TCP fit to the term alone, noise-free, leaves an
    RMS of >= 4 x 0.02 mm) are all chosen."""
    harmonics = [Harmonic(a, k, 2e-4, phase) for a, k, phase in terms]
    q = joints(50, 11)
    for h in harmonics:
        moves = JointErrors(harmonics=(h,))  # the nominal arm with this term alone
        alone = replace(NOMINAL, fk_joint_errors=moves)
        clean = session(alone, q, repeats=1, noise_mm=0.0)
        left = identify(NOMINAL, clean).rms_mm
        assume(np.sqrt(np.mean(left**2)) >= 4 * NOISE_MM)
    data = session(arm(harmonics), q, seed=12)
    result, selection = identify_structure(NOMINAL, data, nested=False)
    for a, k, _ in terms:
        assert f"A{a} k{k}" in selection.chosen
    assert len(selection.chosen) <= len(terms) + 2
    assert result.robot.joint_errors is not None


@pytest.mark.slow
@settings(max_examples=4, deadline=None, derandomize=True, phases=(Phase.generate,))
@given(
    st.integers(1, 6),
    st.integers(30, 120),
    st.floats(1e-4, 3e-4),
    st.floats(0.0, 2 * np.pi),
)
def test_a_dominant_high_order_harmonic_beyond_the_library_is_found(axis, order, amplitude, phase):
    """One reducer harmonic of order 30..120 (beyond the orders the median-gap rule searches) on
    any axis, whose effect beyond the DH errors and TCP is at least 4x the noise floor, is found
    at its order by the periodogram screen and kept by the cross-validated selection; the
    calibrated model then matches the arm at other poses within a few noise floors."""
    h = Harmonic(axis, order, amplitude, phase)
    q = joints(50, 11)
    alone = replace(NOMINAL, fk_joint_errors=JointErrors(harmonics=(h,)))
    left = identify(NOMINAL, session(alone, q, repeats=1, noise_mm=0.0)).rms_mm
    assume(np.sqrt(np.mean(left**2)) >= 4 * NOISE_MM)
    data = session(arm([h]), q, seed=13)
    result, selection = identify_structure(NOMINAL, data, nested=False)
    assert f"A{axis} k{order}" in selection.chosen
    assert len(selection.chosen) <= 3
    # inside the poses' joint ranges the model predicts the arm (extrapolating a high order
    # beyond them is not claimed)
    other = joints(400, 14)
    other = other[np.all((other >= q.min(axis=0)) & (other <= q.max(axis=0)), axis=1)]
    error = result.robot.true_robot().fk(other)[:, :3, 3] - arm([h]).fk(other)[:, :3, 3]
    assert np.sqrt(np.mean(error**2)) <= 3 * NOISE_MM


def test_with_more_poses_the_screen_offers_more_high_orders_per_axis():
    """Five reducer harmonics of orders 40..110 on A1 (beyond the library): 200 poses give the
    screen one offered order per 32 poses and axis (6), so all five are found and chosen; three
    per axis, whatever the poses, left two of them out."""
    orders = (40, 55, 70, 90, 110)
    harmonics = [Harmonic(1, k, 2e-4, 0.7 * i) for i, k in enumerate(orders)]
    assert screen_keep(200) >= len(orders) > SCREEN_KEEP
    data = session(arm(harmonics), joints(200, 31), seed=32)
    _, selection = identify_structure(NOMINAL, data, nested=False)
    for k in orders:
        assert f"A1 k{k}" in selection.chosen


@pytest.mark.slow
@settings(max_examples=3, deadline=None, derandomize=True, phases=(Phase.generate,))
@given(st.integers(0, 1000))
def test_noise_only_data_choose_nothing(seed):
    """A robot with DH errors and a TCP offset only: the search adds no joint-error term."""
    data = session(arm(), joints(50, seed), seed=seed + 1)
    result, selection = identify_structure(NOMINAL, data, nested=False)
    assert selection.chosen == ()
    assert result.robot.joint_errors is None
    assert selection.kept == 0 and len(selection.curve) >= 1


def test_pinned_terms_are_kept_and_the_same_input_gives_the_same_model():
    data = session(arm([Harmonic(2, 3, 1.5e-4, 1.0)]), joints(40, 21), seed=22)
    first, selection = identify_structure(NOMINAL, data, harmonics=((5, 2),), max_order=4)
    again, same = identify_structure(NOMINAL, data, harmonics=((5, 2),), max_order=4)
    assert "A5 k2" in selection.pinned and (5, 2) in selection.harmonics
    assert "harmonic_a5_k2_sin" in first.names
    assert "A5 k2" not in selection.chosen
    assert "A2 k3" in selection.chosen
    np.testing.assert_array_equal(first.x, again.x)
    assert selection.chosen == same.chosen
    nested = selection.nested
    assert nested is not None and nested.folds == 5 and len(nested.chosen) == 5
    # the nested estimate is held out: never below the noise the measured positions carry
    assert np.all(nested.rms_mm > 0.5 * NOISE_MM)


def test_a_max_order_beyond_what_the_poses_resolve_is_refused_naming_the_limit():
    data = session(arm(), joints(30, 31), repeats=1)
    with pytest.raises(
        InputError, match=r"--max-order 5000: these 30 poses resolve harmonic orders 1\.\.\d+"
    ):
        identify_structure(NOMINAL, data, max_order=5000)


# -- the command --------------------------------------------------------------------------------


def write_csv(path, true: Robot, q: np.ndarray, repeats: int = 2):
    data = session(true, q, repeats)
    commanded = NOMINAL.fk(np.repeat(q, repeats, axis=0))
    lines = ["x,y,z,a,b,c,x_meas,y_meas,z_meas,a1,a2,a3,a4,a5,a6"]
    abc = matrix_to_abc(commanded[:, :3, :3])
    for i in range(len(data.q)):
        cells = [*commanded[i, :3, 3], *abc[i], *data.measured[i], *np.degrees(data.q[i])]
        lines.append(",".join(f"{v:.6f}" for v in cells))
    path.write_text("\n".join(lines) + "\n")
    return path


def run(tmp_path, csv, *extra):
    out = tmp_path / "cal.yaml"
    tool = ["20", "-10", "250", "0", "0", "0"]
    return main(["identify", str(csv), "--robot", "kr210", "--tool", *tool, "-o", str(out), *extra])


def test_plain_identify_records_the_chosen_structure_in_the_yaml(tmp_path, capsys):
    csv = write_csv(tmp_path / "meas.csv", arm([Harmonic(2, 5, 2e-4, 0.5)]), joints(40, 41))
    assert run(tmp_path, csv, "--max-order", "6") == 0
    printed = capsys.readouterr().out
    assert "structure chosen by sparse Bayesian learning" in printed
    assert "expected accuracy (nested 5-fold" in printed
    doc = yaml.safe_load((tmp_path / "cal.yaml").read_text())
    structure = doc["identification"]["structure"]
    assert set(structure) <= set(STRUCTURE_SCHEMA)
    assert structure["mode"] == "auto" and "A2 k5" in structure["chosen"]
    assert structure["cv_curve"][0]["added"] == "start"
    assert len(structure["cv_curve"]) >= structure["kept_steps"] + 1
    assert any(h["order"] == 5 for h in doc["joint_errors"]["harmonics"])
    # the model's claim is the nested estimate's held-out max
    loaded = load_robot(tmp_path / "cal.yaml")
    nested = structure["nested"]["held_out_max_mm"]
    np.testing.assert_allclose(loaded.validated_max_mm, [nested[k] for k in "xyz"])


def test_structure_search_is_the_forward_selection_and_finds_the_dominant_harmonic(
    tmp_path, capsys
):
    csv = write_csv(tmp_path / "meas.csv", arm([Harmonic(2, 5, 2e-4, 0.5)]), joints(40, 41))
    assert run(tmp_path, csv, "--max-order", "6", "--structure", "search") == 0
    assert "structure chosen by forward selection by 5-fold" in capsys.readouterr().out
    structure = yaml.safe_load((tmp_path / "cal.yaml").read_text())["identification"]["structure"]
    assert structure["mode"] == "search"
    assert "A2 k5" in structure["chosen"]


def test_structure_dh_is_the_geometric_fit(tmp_path, capsys):
    csv = write_csv(tmp_path / "meas.csv", arm([Harmonic(2, 5, 2e-4, 0.5)]), joints(40, 41))
    assert run(tmp_path, csv, "--structure", "dh") == 0
    assert "22 of 27 parameters identifiable" in capsys.readouterr().out
    doc = yaml.safe_load((tmp_path / "cal.yaml").read_text())
    assert doc["identification"]["structure"] == {"mode": "dh"}
    assert "joint_errors" not in doc


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (("--structure", "magic"), "--structure 'magic': one of auto, search, dh"),
        (("--folds", "0"), "--folds 0: choosing the structure needs folds"),
        (("--max-order", "4", "--structure", "dh"), "--max-order chooses the harmonics"),
        (("--max-order", "9999"), "--max-order 9999: these 40 poses resolve harmonic orders"),
    ],
)
def test_bad_structure_options_are_refused_with_one_line(tmp_path, capsys, extra, message):
    csv = write_csv(tmp_path / "meas.csv", arm(), joints(40, 51))
    assert run(tmp_path, csv, *extra) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
    assert not (tmp_path / "cal.yaml").exists()


def test_too_few_poses_are_refused(tmp_path, capsys):
    csv = write_csv(tmp_path / "meas.csv", arm(), joints(12, 61))
    assert run(tmp_path, csv) == 2
    err = capsys.readouterr().err
    assert "12 distinct poses for 22 identifiable parameters" in err and err.count("\n") == 1
    assert not (tmp_path / "cal.yaml").exists()


def test_plan_identify_reports_the_candidates_its_poses_cannot_separate(tmp_path, capsys):
    """With the tool on A6's axis an A6 harmonic cannot move the TCP: the plan says so before
    anyone measures; an offset tool lets the poses see A6's orders."""
    plan = ["plan", "identify", "--count", "40", "--tilt", "25", "-o", str(tmp_path), "--force"]
    assert main([*plan, "--tool", "0", "0", "250", "0", "0", "0"]) == 0
    on_axis = [line for line in capsys.readouterr().out.splitlines() if "not separable" in line]
    assert len(on_axis) == 1 and "A6 orders 1,2,3" in on_axis[0]
    assert main([*plan, "--tool", "20", "-10", "250", "0", "0", "0"]) == 0
    offset = [line for line in capsys.readouterr().out.splitlines() if "not separable" in line]
    assert len(offset) == 1 and "A6 orders 1,2,3" not in offset[0]


def test_plan_identify_augment_plans_for_the_structure_a_calibrated_file_chose(tmp_path, capsys):
    csv = write_csv(tmp_path / "meas.csv", arm([Harmonic(2, 5, 2e-4, 0.5)]), joints(40, 41))
    assert run(tmp_path, csv, "--max-order", "6") == 0
    cal = tmp_path / "cal.yaml"
    capsys.readouterr()
    plan = ["plan", "identify", "--count", "40", "--tilt", "25", "--tool", "20", "-10", "250"]
    plan += ["0", "0", "0", "--augment", str(cal), "-o", str(tmp_path / "plan")]
    assert main(plan) == 0
    printed = capsys.readouterr().out
    chosen = yaml.safe_load(cal.read_text())["identification"]["structure"]["chosen"]
    harmonics = sum(1 for name in chosen if not name.startswith("gravity"))
    assert f"identification plan (DH errors, TCP, {harmonics} harmonics" in printed
    other = ["plan", "identify", "--count", "10", "--robot", "kr210-realistic"]
    other += ["--augment", str(tmp_path / "meas.csv"), "-o", str(tmp_path / "p2")]
    assert main(other) == 2  # not a robot file
    assert capsys.readouterr().err.count("\n") == 1
