"""Where a calibrated model has support (``kinematics.support``): the flag, the DH-only fallback
in the correction policy and ``--strict``, on a simulated arm and on the real UR10 data
(``../shared/realdata/ipa-ur10``).

The simulated arm (kr210-paper with second-order reducer harmonics on A4 and A5) is calibrated
on two clusters of poses: A4 near 0 deg with A5 near 30 deg, and A4 near 90 deg with A5 near
95 deg. The crossed combinations (A4 near 90 deg with A5 near 30 deg, and the reverse) lie
inside every per-joint range of the calibration poses, yet no calibration pose is near them.
"""

from __future__ import annotations

import csv
from dataclasses import replace

import numpy as np
import pytest
import yaml

from accugrid.app.cli import main
from accugrid.app.jobs.correct_model import read_model
from accugrid.compensation.budget import ModelBudget, coverage, coverage_range
from accugrid.compensation.model_correction import model_correct
from accugrid.infra.bounds import length_bound_95
from accugrid.infra.csvtable import TableFormat, read_table
from accugrid.infra.yamlfile import YamlDoc
from accugrid.kinematics.configuration import ik_codes
from accugrid.kinematics.frames import pose_from_xyzabc, xyzabc_from_pose
from accugrid.kinematics.identification import identify, pose_set
from accugrid.kinematics.joint_errors import Harmonic, JointErrors
from accugrid.kinematics.robot import load_robot
from accugrid.kinematics.support import Structure, Support, support_section

TOOL = ["20", "-10", "250", "0", "0", "0"]
PAPER = load_robot("kr210-paper").with_tool(pose_from_xyzabc([20.0, -10.0, 250.0, 0, 0, 0]))
HARMONICS = ((4, 2), (5, 2))
TRUE = replace(
    PAPER,
    joint_errors=JointErrors(harmonics=tuple(Harmonic(a, k, 2e-4, 0.3) for a, k in HARMONICS)),
).true_robot()
LOW = np.array([-60.0, -120.0, 20.0, 0.0, 0.0, -150.0])
HIGH = np.array([60.0, -40.0, 120.0, 0.0, 0.0, 150.0])
NEAR_0, NEAR_90 = (-15.0, 15.0), (75.0, 105.0)  # A4 ranges, deg
LOW_A5, HIGH_A5 = (20.0, 45.0), (80.0, 110.0)  # A5 ranges, deg


def cluster(a4, a5, n: int, seed: int) -> np.ndarray:
    """Random joints (n, 6) rad with A4, A5 in the given ranges (deg), 4 decimals in deg."""
    lo, hi = LOW.copy(), HIGH.copy()
    (lo[3], hi[3]), (lo[4], hi[4]) = a4, a5
    deg = lo + np.random.default_rng(seed).random((n, 6)) * (hi - lo)
    return np.radians(np.round(deg, 4))


CALIBRATION = np.r_[cluster(NEAR_0, LOW_A5, 40, 1), cluster(NEAR_90, HIGH_A5, 40, 2)]
# kept inside the calibration poses' ranges of every axis
CROSSED = np.clip(
    np.r_[cluster(NEAR_90, LOW_A5, 20, 3), cluster(NEAR_0, HIGH_A5, 20, 4)],
    CALIBRATION.min(axis=0),
    CALIBRATION.max(axis=0),
)


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory) -> str:
    """The arm identified from the two clusters with the harmonics pinned (``--structure dh``
    keeps them): a model with joint-error terms, so the file records its support."""
    folder = tmp_path_factory.mktemp("support")
    commanded = xyzabc_from_pose(PAPER.fk(CALIBRATION))
    measured = TRUE.fk(CALIBRATION)[:, :3, 3]
    measured += np.random.default_rng(5).normal(0.0, 0.02, measured.shape)
    lines = ["id,x,y,z,a,b,c,x_meas,y_meas,z_meas,a1,a2,a3,a4,a5,a6"]
    for i, q in enumerate(CALIBRATION):
        cells = [f"{v:.4f}" for v in (*commanded[i], *measured[i], *np.degrees(q))]
        lines.append(",".join([f"P{i}", *cells]))
    meas = folder / "meas.csv"
    meas.write_text("\n".join(lines) + "\n")
    out = folder / "cal.yaml"
    harmonics = [f"A{a}:{k}" for a, k in HARMONICS]
    argv = ["identify", str(meas), "--robot", "kr210", "--tool", *TOOL, "-o", str(out)]
    assert main([*argv, "--structure", "dh", "--harmonics", *harmonics]) == 0
    return str(out)


def write_points(path, q: np.ndarray):
    """Targets at the nominal poses of joints q (N, 6) rad, each with its own Status."""
    xyzabc = xyzabc_from_pose(PAPER.fk(q))
    status = ik_codes(PAPER, q)[0]
    lines = ["id,x,y,z,a,b,c,s"]
    for i in range(len(q)):
        lines.append(",".join([f"T{i}", *(f"{v:.4f}" for v in xyzabc[i]), str(status[i])]))
    path.write_text("\n".join(lines) + "\n")
    return xyzabc, status


def test_the_file_records_the_poses_and_the_dh_only_fit(calibrated):
    support = yaml.safe_load(open(calibrated))["identification"]["support"]
    assert len(support["joints_deg"]) == 80 and len(support["lever_mm_per_rad"]) == 6
    assert support["parameters"][-4:] == [
        "harmonic_a4_k2_sin",
        "harmonic_a4_k2_cos",
        "harmonic_a5_k2_sin",
        "harmonic_a5_k2_cos",
    ]
    assert "leverage_map" not in support and support["loo_leverage_max"] > 0
    assert support["loo_distance_max_mm"] > 0
    read = read_model(calibrated).validity.support
    fallback = read.fallback
    assert fallback.joint_errors is None and fallback.errors.shape == (6, 4)
    # the leverage map is computed from the recorded poses when the file is read: every
    # calibration pose has support (its leverage below its leave-one-out one, the largest of
    # which identify recorded), and the largest comes within a few percent of that bound
    ratio = read.leverage(read.joints) / support["loo_leverage_max"]
    assert ratio.max() <= 1.0 and ratio.max() > 0.5


def test_crossed_poses_inside_every_joint_range_have_no_support(calibrated):
    validity = read_model(calibrated).validity
    inside = validity.excess(PAPER.fk(CROSSED)[:, :3, 3], None, CROSSED)[2]
    assert not inside.any()  # every joint inside the calibration poses' ranges
    assert (validity.support.ratio(CROSSED) > 1.0).all()


def test_targets_near_the_calibration_poses_have_support(calibrated):
    support = read_model(calibrated).validity.support
    near = CALIBRATION + np.radians(np.random.default_rng(6).uniform(-1.0, 1.0, CALIBRATION.shape))
    assert (support.ratio(near) < 1.0).all()
    # new poses drawn like the calibration poses: flagged about as often as the largest of 80
    # leave-one-out leverages is exceeded (1 in 81 in expectation)
    fresh = np.r_[cluster(NEAR_0, LOW_A5, 200, 7), cluster(NEAR_90, HIGH_A5, 200, 8)]
    assert (support.ratio(fresh) > 1.0).mean() < 0.05


def test_targets_without_support_are_flagged_and_corrected_by_the_dh_only_fit(
    calibrated, tmp_path, capsys
):
    near = CALIBRATION[:10] + np.radians(0.5)
    targets = np.r_[CROSSED[:10], near]
    xyzabc, status = write_points(tmp_path / "points.csv", targets)
    out = tmp_path / "out.csv"
    argv = ["correct", str(tmp_path / "points.csv"), "--model", calibrated, "--tool", *TOOL]
    assert main([*argv, "-o", str(out)]) == 0
    rows = list(csv.DictReader(line for line in open(out) if not line.startswith("#")))
    notes = [next(reversed(r.values())) for r in rows]
    flagged = ["corrected by the DH-only fit" in n for n in notes]
    assert flagged == [True] * 10 + [False] * 10
    command = np.array([[float(r[k]) for k in ("x_cmd", "y_cmd", "z_cmd")] for r in rows])
    model = read_model(calibrated)
    tool = pose_from_xyzabc(np.array(TOOL, dtype=float))
    for robot, rows_ in (
        (model.validity.support.fallback, slice(0, 10)),
        (model.robot, slice(10, 20)),
    ):
        expected = model_correct(
            robot,
            xyzabc[rows_, :3],
            xyzabc[rows_, 3:],
            status[rows_],
            controller_tool=tool,
            arm_tool=tool,
        )
        assert expected.ok.all()
        np.testing.assert_allclose(command[rows_], expected.command, atol=2e-3)  # 3 decimals
    # the DH-only fit and the full model differ there: the fallback is really used
    full = model_correct(
        model.robot,
        xyzabc[:10, :3],
        xyzabc[:10, 3:],
        status[:10],
        None,
        None,
        controller_tool=tool,
        arm_tool=tool,
    )
    assert np.abs(full.command - command[:10]).max() > 0.005


def test_a_position_the_fallback_corrects_carries_the_fallback_fits_own_bound(calibrated, tmp_path):
    """The error budget of a position the DH-only fallback corrects is that fit's own, sigma²
    (I + H_fb) at the joints it commands (sigma its held-out RMS per axis, recorded beside it),
    not the full model's there; the DH-only fit leaves the harmonics, so it is the wider one."""
    near = CALIBRATION[:10] + np.radians(0.5)
    xyzabc, status = write_points(tmp_path / "points.csv", np.r_[CROSSED[:10], near])
    out = tmp_path / "out.csv"
    argv = ["correct", str(tmp_path / "points.csv"), "--model", calibrated, "--tool", *TOOL]
    assert main([*argv, "-o", str(out)]) == 0
    rows = list(csv.DictReader(line for line in open(out) if not line.startswith("#")))
    u95 = np.array([float(r["u95_mm"]) for r in rows])
    model = read_model(calibrated)
    support = model.validity.support
    own = yaml.safe_load(open(calibrated))["identification"]["support"]["fallback"]["sigma_mm"]
    np.testing.assert_allclose(support.fallback_sigma_mm, [own[k] for k in "xyz"])
    tool = pose_from_xyzabc(np.array(TOOL, dtype=float))
    joints = [
        model_correct(
            robot,
            xyzabc[:10, :3],
            xyzabc[:10, 3:],
            status[:10],
            controller_tool=tool,
            arm_tool=tool,
        ).q
        for robot in (support.fallback, model.robot)
    ]
    fallback, full = (
        length_bound_95(budget.covariance(q))
        for budget, q in zip((ModelBudget.of_fallback(support), model.budget), joints, strict=True)
    )
    np.testing.assert_allclose(u95[:10], fallback, atol=6e-4)  # the CSV's 3 decimals
    assert np.abs(fallback - full).min() > 0.002  # the model's bound there: 0.004-0.007 apart
    assert (u95[10:] < fallback.min()).all()  # the model's own near its poses: 0.059-0.061


def test_strict_refuses_targets_without_support(calibrated, tmp_path, capsys):
    xyz = PAPER.fk(CALIBRATION)[:, :3, 3]
    inner = (xyz - xyz.min(axis=0) > 1.0) & (xyz.max(axis=0) - xyz > 1.0)  # inside the box
    own = CALIBRATION[inner.all(axis=1)][:3]  # calibration poses: supported, in every range
    write_points(tmp_path / "points.csv", np.r_[own, CROSSED[:2]])
    out = tmp_path / "out.csv"
    argv = ["correct", str(tmp_path / "points.csv"), "--model", calibrated, "--tool", *TOOL]
    assert main([*argv, "-o", str(out), "--strict"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and not out.exists()
    assert "points.csv:5:" in err[0]  # the first crossed target: header line + 3 rows + 1
    assert "2 without the model's support" in err[0]
    assert "without support in the poses the model was identified from" in err[0]


def _series(path) -> tuple[np.ndarray, np.ndarray]:
    """Joints (N, 6) rad and measured positions (N, 3) mm (tracker frame) of a UR10 series file
    as it comes (semicolon, decimal comma)."""
    table = read_table(path, TableFormat(delimiter=";", decimal=","))
    joints = ["shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3"]
    q = table.floats([f"{name}_joint" for name in joints])
    return q, table.floats(["measurement_x", "measurement_y", "measurement_z"])


def test_real_ur10_poses_of_another_series_have_no_support(realdata):
    """Calibrated on 300 random poses of Series C (the UR10's random poses), the model has no
    support at Series A's grid poses (other shoulder angles and configurations) and has it at
    the rest of C; its fallback is the DH-only fit of the same poses, and that fit's own 95 %
    bound (the budget of the positions it corrects) holds for about 95 % of its errors at the
    rest of C."""
    folder = realdata / "ipa-ur10"
    q_c, m_c = _series(folder / "Series_C" / "measurements_random_poses.csv")
    q_a, _ = _series(folder / "Series_A" / "measurements_grid.csv")
    robot = load_robot("ur10").with_tool(pose_from_xyzabc([0, 0, 109.0, 0, 0, 0]))
    pick = np.random.default_rng(0).permutation(len(q_c))[:300]
    commanded = robot.fk(q_c[pick])[:, :3, 3]  # the controller's own model is not the nominal
    data = pose_set(robot, commanded, m_c[pick], joints_deg=np.degrees(q_c[pick]))
    structure = Structure(base_frame=True, harmonics=((2, 2), (3, 2), (2, 3), (3, 3)))
    full = identify(robot, data, base_frame=True, harmonics=structure.harmonics)
    dh = identify(robot, data, base_frame=True, folds=5)
    section = support_section(full.robot, data.q, data.group, structure, dh)
    doc = YamlDoc.parse(yaml.safe_dump({"identification": {"support": section}}), "cal.yaml")
    support = Support.from_doc(doc, full.robot, structure)
    assert (support.ratio(q_a) > 1.0).all()
    rest = np.setdiff1d(np.arange(len(q_c)), pick)
    assert (support.ratio(q_c[rest]) > 1.0).mean() < 0.02  # measured: 0.4 %
    fallback = support.fallback.true_robot().fk(q_a)[:, :3, 3]
    np.testing.assert_allclose(fallback, dh.robot.true_robot().fk(q_a)[:, :3, 3], atol=1e-9)
    frame = support.fallback_frame
    predicted = support.fallback.true_robot().fk(q_c[rest])[:, :3, 3]
    errors = (m_c[rest] - frame[:3, 3]) @ frame[:3, :3] - predicted  # robot frame
    u95 = length_bound_95(ModelBudget.of_fallback(support).covariance(q_c[rest]))
    share, _ = coverage(errors, u95)
    low, high = coverage_range(len(rest))
    assert low <= share <= high, share  # measured: 92.6 %


def test_a_damaged_support_record_is_a_located_error(calibrated, tmp_path, capsys):
    text = open(calibrated).read()
    at = text.index("  joints_deg: [", text.index("support:"))
    damaged = tmp_path / "cal.yaml"
    damaged.write_text(text[:at] + text[at:].replace("joints_deg: [", "joints_deg: [oops ", 1))
    write_points(tmp_path / "points.csv", CALIBRATION[:1])
    argv = ["correct", str(tmp_path / "points.csv"), "--model", str(damaged), "--tool", *TOOL]
    assert main([*argv, "-o", str(tmp_path / "out.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "support.joints_deg' must be rows of 6 numbers" in err[0]
    line = text[:at].count("\n") + 1
    assert f"cal.yaml:{line}:" in err[0]


def test_a_target_the_fallback_cannot_reach_is_refused_as_not_reachable(
    calibrated, tmp_path, monkeypatch, capsys
):
    """Where the DH-only fallback finds no joints for a target, the target is refused for the
    fallback's own reason (not reachable), as the full model's failures are, and its command is
    the target itself."""
    from dataclasses import replace

    from accugrid.compensation import policy

    fallback = read_model(calibrated).validity.support.fallback
    real = policy.model_correct

    def fallback_unreachable(robot, *args, **kwargs):
        result = real(robot, *args, **kwargs)
        if robot.errors is None or not np.allclose(robot.errors, fallback.errors):
            return result
        failed = np.zeros(len(result.ok), bool)
        failed[:3] = True
        reason = result.reason.copy()
        reason[failed] = "A1 beyond its limit"
        return replace(result, ok=result.ok & ~failed, reason=reason)

    monkeypatch.setattr(policy, "model_correct", fallback_unreachable)
    xyzabc, _ = write_points(tmp_path / "points.csv", CROSSED[:10])
    out = tmp_path / "out.csv"
    argv = ["correct", str(tmp_path / "points.csv"), "--model", calibrated, "--tool", *TOOL]
    assert main([*argv, "--allow-partial", "-o", str(out)]) == 0
    rows = list(csv.DictReader(line for line in open(out) if not line.startswith("#")))
    notes = [next(reversed(r.values())) for r in rows]
    assert all(n.startswith("not corrected: not reachable") and "A1 beyond" in n for n in notes[:3])
    assert all("corrected by the DH-only fit" in n for n in notes[3:])
    command = np.array([[float(r[k]) for k in ("x_cmd", "y_cmd", "z_cmd")] for r in rows[:3]])
    np.testing.assert_allclose(command, xyzabc[:3, :3], atol=1e-3)
