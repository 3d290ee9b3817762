"""Correction with a calibrated model (compensation.model_correction, `correct --model`)."""

from __future__ import annotations

import csv
import dataclasses
import io
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from accugrid.app.cli import main
from accugrid.compensation.grid import GridModel
from accugrid.compensation.model_correction import model_correct, residual_grid
from accugrid.compensation.policy import F_SINGULAR, TOO_LONG, UNREACHABLE, Policy
from accugrid.compensation.settings import CorrectionSettings
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix, matrix_to_abc, pose_from_xyzabc
from accugrid.kinematics.robot import load_robot

CALIBRATED = load_robot("kr210-realistic")  # its true robot stands for the calibrated arm
PAPER = load_robot("kr210-paper")
# the same model claiming what a calibrated file's identification validated: 0.5 mm per axis,
# so a residual grid may be offset by up to 1 mm (SETUP_FACTOR x) on average
CLAIMING = dataclasses.replace(PAPER, validated_max_mm=np.full(3, 0.5))
STATUS = 6  # the seed region's Status at A 0 B 90 C 0 (kinematics.simulation.grid_status)
LO, HI = np.array([1300.0, -500.0, 1200.0]), np.array([2100.0, 500.0, 2000.0])


def drive(robot, commands: np.ndarray, abc: np.ndarray, status: int) -> np.ndarray:
    """Where the arm goes: the controller's nominal IK in ``status``, then the true FK (mm)."""
    poses = np.tile(np.eye(4), (len(commands), 1, 1))
    poses[:, :3, :3] = abc_to_matrix(abc)
    poses[:, :3, 3] = commands
    sol = robot.ik(poses, status=status)
    assert sol.ok.all()
    return robot.true_robot().fk(sol.q)[:, :3, 3]


def tilted(seed_abc: np.ndarray, tilt: np.ndarray) -> np.ndarray:
    """A B C (N, 3) deg: the seed orientation 0 90 0 turned by small rotations ``tilt`` (N, 3)
    deg about the base X, Y, Z axes (up to ~25 deg in all)."""
    rx, ry, rz = np.radians(tilt).T
    c, s = np.cos, np.sin
    one, zero = np.ones_like(rx), np.zeros_like(rx)
    mx = np.stack([one, zero, zero, zero, c(rx), -s(rx), zero, s(rx), c(rx)], -1).reshape(-1, 3, 3)
    my = np.stack([c(ry), zero, s(ry), zero, one, zero, -s(ry), zero, c(ry)], -1).reshape(-1, 3, 3)
    mz = np.stack([c(rz), -s(rz), zero, s(rz), c(rz), zero, zero, zero, one], -1).reshape(-1, 3, 3)
    return matrix_to_abc(mz @ my @ mx @ abc_to_matrix(seed_abc))


@given(
    arrays(float, (6, 3), elements=st.floats(0.0, 1.0)),
    arrays(float, (6, 3), elements=st.floats(-14.0, 14.0)),
)
def test_the_calibrated_arm_driven_by_the_command_lands_on_the_target(u, tilt):
    targets = LO + u * (HI - LO)
    abc = tilted(np.array([0.0, 90.0, 0.0]), tilt)
    result = model_correct(CALIBRATED, targets, abc, STATUS, tol_mm=1e-7)
    assert result.ok.all()
    reached = drive(CALIBRATED, result.command, abc, STATUS)
    np.testing.assert_allclose(reached, targets, atol=1e-6, rtol=0)
    # and the command really differs from the target by the arm's error (millimetres)
    assert np.linalg.norm(result.command - targets, axis=1).min() > 0.5


def test_without_errors_the_command_is_the_target():
    nominal = load_robot("kr210")
    targets = np.array([[1500.0, 100.0, 1400.0], [1800.0, -200.0, 1700.0]])
    result = model_correct(nominal, targets, np.array([0.0, 90.0, 0.0]), STATUS)
    assert result.ok.all() and result.iterations == 1
    np.testing.assert_allclose(result.command, targets, atol=1e-9, rtol=0)


def test_unreachable_targets_are_reported_by_index():
    targets = np.array([[1500.0, 0.0, 1500.0], [5000.0, 0.0, 1500.0], [1600.0, 100.0, 1500.0]])
    result = model_correct(CALIBRATED, targets, np.array([0.0, 90.0, 0.0]), STATUS)
    assert result.failed.tolist() == [1]
    assert result.reason[1] == "unreachable"
    np.testing.assert_array_equal(result.command[1], targets[1])
    np.testing.assert_allclose(
        drive(CALIBRATED, result.command[[0, 2]], np.array([0.0, 90.0, 0.0]), STATUS),
        targets[[0, 2]],
        atol=1e-3,
    )


def test_blocks_on_threads_give_the_one_block_result(monkeypatch):
    # targets iterate in blocks on threads: every target's command, miss and reason as when all
    # iterate together (some unreachable, some needing more passes than others)
    import accugrid.compensation.model_correction as module

    rng = np.random.default_rng(5)
    targets = rng.uniform(LO, HI, (40, 3))
    targets[[3, 17, 38]] = [5000.0, 0.0, 1500.0]
    abc = tilted(np.array([0.0, 90.0, 0.0]), rng.uniform(-14.0, 14.0, (40, 3)))
    whole = model_correct(CALIBRATED, targets, abc, STATUS, tol_mm=1e-7)
    monkeypatch.setattr(module, "BLOCK", 7)
    blocks = model_correct(CALIBRATED, targets, abc, STATUS, tol_mm=1e-7)
    assert whole.failed.tolist() == blocks.failed.tolist() == [3, 17, 38]
    np.testing.assert_array_equal(blocks.command, whole.command)
    np.testing.assert_array_equal(blocks.miss_mm, whole.miss_mm)
    assert blocks.reason.tolist() == whole.reason.tolist()
    assert blocks.iterations == whole.iterations


def _vertices(step: float = 400.0) -> np.ndarray:
    axes = [np.arange(LO[a], HI[a] + 1e-9, step) for a in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)


def test_residual_grid_makes_model_plus_grid_exact_at_the_vertices():
    # The "real" arm: kr210-realistic; the model: kr210-paper (geometric errors only), so the
    # residual is the compliance and reducer error. Noise-free measurement of the vertices.
    abc = np.array([0.0, 90.0, 0.0])
    vertices = _vertices()
    measured = drive(CALIBRATED, vertices, abc, STATUS)
    grid = residual_grid(CLAIMING, (vertices, measured, np.tile(abc, (len(vertices), 1))), STATUS)
    assert np.abs(grid.errors).max() > 0.1  # the model really leaves something
    # model + residual grid predicts the measured position at every vertex
    model_reach = drive(PAPER, vertices, abc, STATUS)
    predicted = model_reach - grid.predict(vertices)
    np.testing.assert_allclose(predicted, measured, atol=1e-9, rtol=0)


def test_model_plus_residual_grid_lands_exactly_when_the_residual_is_constant():
    # A real arm that is the model moved by a constant offset (e.g. an unmeasured base shift):
    # the residual grid holds that offset, interpolates it exactly, and the command lands on P.
    abc = np.array([0.0, 90.0, 0.0])
    offset = np.array([0.3, -0.2, 0.5])
    vertices = _vertices()
    measured = drive(PAPER, vertices, abc, STATUS) + offset
    grid = residual_grid(CLAIMING, (vertices, measured, np.tile(abc, (len(vertices), 1))), STATUS)
    rng = np.random.default_rng(3)
    targets = grid.origin + rng.uniform(0.05, 0.95, (20, 3)) * (grid.upper - grid.origin)
    for method in ("idw", "trilinear"):
        result = model_correct(
            PAPER, targets, abc, STATUS, grid, CorrectionSettings(method=method), tol_mm=1e-7
        )
        assert result.ok.all()
        reached = drive(PAPER, result.command, abc, STATUS) + offset
        np.testing.assert_allclose(reached, targets, atol=1e-6, rtol=0)


def _rows(path):
    body = [line for line in path.read_text().splitlines(True) if not line.startswith("#")]
    return list(csv.DictReader(io.StringIO("".join(body))))


def test_correct_cli_with_model_writes_commands_that_land(tmp_path, capsys):
    points = tmp_path / "points.csv"
    points.write_text(
        "id,x,y,z,a,b,c,note\n"
        "H1,1500,100,1400,0,90,0,first\n"
        "H2,1700,-300,1600,10,80,5,\n"
        "H3,1900,200,1300,-20,70,0,tilted 28 deg\n"
    )
    out = tmp_path / "out.csv"
    argv = ["correct", str(points), "--model", "kr210-realistic", "--status", "6", "-o", str(out)]
    assert main(argv) == 0
    rows = _rows(out)
    assert [r["note"] for r in rows] == ["first", "", "tilted 28 deg"]
    command = np.array([[float(r[k]) for k in ("x_cmd", "y_cmd", "z_cmd")] for r in rows])
    target = np.array([[float(r[k]) for k in "xyz"] for r in rows])
    abc = np.array([[float(r[k]) for k in "abc"] for r in rows])
    correction = np.array([[float(r[k]) for k in ("ex", "ey", "ez")] for r in rows])
    np.testing.assert_allclose(correction, command - target, atol=2e-4)
    # 4 decimals: within 0.0001 mm per axis of the exact command
    np.testing.assert_allclose(drive(CALIBRATED, command, abc, 6), target, atol=3e-4, rtol=0)
    assert "KUKA Status 6" in capsys.readouterr().out


def test_correct_cli_refuses_an_unreachable_point_and_writes_nothing(tmp_path, capsys):
    points = tmp_path / "points.csv"
    points.write_text("id,x,y,z\nH1,1500,100,1400\nFAR,4000,0,1400\n")
    out = tmp_path / "out.csv"
    assert main(["correct", str(points), "--model", "kr210-realistic", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "points.csv:3" in err and "FAR" in err and "unreachable" in err
    assert not out.exists()


def test_correct_cli_needs_a_grid_or_a_model(tmp_path, capsys):
    points = tmp_path / "points.csv"
    points.write_text("id,x,y,z\nH1,1500,100,1400\n")
    assert main(["correct", str(points), "-o", str(tmp_path / "out.csv")]) == 2
    assert "--grid MEAS, --model CAL.yaml or both" in capsys.readouterr().err


def test_correct_cli_residual_grid_of_a_perfect_model_changes_nothing(tmp_path, capsys):
    # The vertices measured on kr210-realistic's arm (noise-free, 4 decimals) and the model
    # kr210-realistic itself: the residual is only the rounding, so model + grid gives the
    # model's commands.
    grid = tmp_path / "grid.csv"
    argv = ["simulate", "--robot", "kr210-realistic", "--region", "1300", "2100", "-500", "500"]
    argv += ["1200", "2000", "--step", "400", "--abc", "0", "90", "0", "-o", str(grid)]
    assert main(argv) == 0
    points = tmp_path / "points.csv"
    points.write_text("id,x,y,z,a,b,c\nH1,1500,100,1400,0,90,0\nH2,1700,-300,1600,10,80,5\n")
    alone, both = tmp_path / "alone.csv", tmp_path / "both.csv"
    common = ["correct", str(points), "--model", "kr210-realistic", "--status", "6"]
    assert main([*common, "-o", str(alone)]) == 0
    assert main([*common, "--grid", str(grid), "-o", str(both)]) == 0
    out = capsys.readouterr().out
    residual = [line for line in out.splitlines() if line.startswith("error e")]
    assert len(residual) == 3
    for line in residual:  # "error ex   -0.0000 .. +0.0001 mm"
        low, high = (float(v) for v in line.split()[2:5:2])
        assert -1e-4 <= low <= high <= 1e-4
    keys = ("x_cmd", "y_cmd", "z_cmd")
    a = np.array([[float(r[k]) for k in keys] for r in _rows(alone)])
    b = np.array([[float(r[k]) for k in keys] for r in _rows(both)])
    np.testing.assert_allclose(a, b, atol=3e-4, rtol=0)
    assert "orientation 11.2 deg from the residual grid's" in _rows(both)[1]["flag"]


def test_correct_cli_drives_with_the_controllers_tool_not_the_identified_tcp(tmp_path, capsys):
    # A calibrated file as identify writes it: the identified TCP in 'tool', the TOOL_DATA the
    # controller used in identification.controller_tool. The controller solves with its own
    # tool; the arm's TCP is the identified one.
    robots = Path(__file__).resolve().parents[1] / "kinematics" / "robots"
    text = (robots / "kr210-paper.yaml").read_text()
    text += "tool: {x: 0.5, y: -0.3, z: 250.4, a: 0.0, b: 0.0, c: 0.0}\n"
    text += "identification:\n  controller_tool: {x: 0.0, y: 0.0, z: 250.0, a: 0, b: 0, c: 0}\n"
    model = tmp_path / "cal.yaml"
    model.write_text(text)
    points = tmp_path / "points.csv"
    points.write_text("id,x,y,z,a,b,c\nH1,1500,100,1400,0,90,0\nH2,1800,-200,1300,10,80,0\n")
    out = tmp_path / "out.csv"
    argv = ["correct", str(points), "--model", str(model), "--status", "6", "-o", str(out)]
    assert main(argv) == 0
    rows = _rows(out)
    command = np.array([[float(r[k]) for k in ("x_cmd", "y_cmd", "z_cmd")] for r in rows])
    target = np.array([[float(r[k]) for k in "xyz"] for r in rows])
    abc = np.array([[float(r[k]) for k in "abc"] for r in rows])
    calibrated = load_robot(model)
    controller = calibrated.with_tool(pose_from_xyzabc([0.0, 0.0, 250.0, 0.0, 0.0, 0.0]))
    poses = np.tile(np.eye(4), (2, 1, 1))
    poses[:, :3, :3], poses[:, :3, 3] = abc_to_matrix(abc), command
    sol = controller.ik(poses, status=6)
    landed = calibrated.true_robot().fk(sol.q)[:, :3, 3]
    np.testing.assert_allclose(landed, target, atol=3e-4, rtol=0)


# The one correction decision (compensation.policy): grid alone, model, model + residual.


def _box_targets(grid: GridModel, seed: int, n: int = 20) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return grid.origin + rng.uniform(0.05, 0.95, (n, 3)) * (grid.upper - grid.origin)


def _measured_grid(robot, offset: float | np.ndarray = 0.0) -> GridModel:
    """Noise-free measurement of the 27 vertices in STATUS at A 0 B 90 C 0 (+ ``offset`` mm)."""
    abc = np.array([0.0, 90.0, 0.0])
    vertices = _vertices()
    measured = drive(robot, vertices, abc, STATUS) + offset
    return GridModel.from_measurements((vertices, measured, np.tile(abc, (len(vertices), 1))))


def test_policy_model_only_lands_on_the_targets_in_the_first_points_status():
    targets = _box_targets(_measured_grid(CALIBRATED), seed=5)
    abc = np.tile([0.0, 90.0, 0.0], (len(targets), 1))
    policy = Policy.build(CorrectionSettings(), None, CALIBRATED, points=targets, abc_deg=abc)
    assert policy.grid is None and policy.status == STATUS
    verdict = policy.decide(targets, abc_to_matrix(abc))
    assert verdict.corrected.all() and ((verdict.flags | F_SINGULAR) == F_SINGULAR).all()
    reached = drive(CALIBRATED, verdict.command, abc, STATUS)
    assert np.linalg.norm(reached - targets, axis=1).max() < 1e-3
    assert np.linalg.norm(verdict.command - targets, axis=1).min() > 0.5  # it did correct


def test_policy_model_plus_residual_grid_lands_on_the_targets():
    # The real arm: the model kr210-paper moved by a constant offset the model does not know.
    offset = np.array([0.3, -0.2, 0.5])
    grid = _measured_grid(PAPER, offset)
    policy = Policy.build(CorrectionSettings(method="trilinear"), grid, CLAIMING)
    assert policy.status == STATUS == policy.grid_status  # the grid's measurement Status
    np.testing.assert_allclose(
        policy.grid.errors.reshape(-1, 3), np.tile(-offset, (27, 1)), atol=1e-9
    )
    targets = _box_targets(grid, seed=7)
    abc = np.tile([0.0, 90.0, 0.0], (len(targets), 1))
    verdict = policy.decide(targets, abc_to_matrix(abc))
    assert verdict.corrected.all()
    reached = drive(PAPER, verdict.command, abc, STATUS) + offset
    assert np.linalg.norm(reached - targets, axis=1).max() < 1e-3


def test_policy_keeps_a_given_status_and_reports_unreachable_targets():
    policy = Policy.build(CorrectionSettings(), None, CALIBRATED, status=STATUS)
    assert policy.status == STATUS
    targets = np.array([[1500.0, 0.0, 1500.0], [5000.0, 0.0, 1500.0]])
    verdict = policy.decide(targets, abc_to_matrix(np.tile([0.0, 90.0, 0.0], (2, 1))))
    assert verdict.corrected.tolist() == [True, False]
    assert verdict.code[1] == UNREACHABLE
    assert verdict.reason(1) == "not reachable in KUKA Status 6: unreachable"
    np.testing.assert_array_equal(verdict.command[1], targets[1])  # left as it is


def test_policy_without_a_model_is_the_grid_correction():
    grid = _measured_grid(CALIBRATED)  # the realistic arm's error field
    settings = CorrectionSettings(method="trilinear")
    policy = Policy.build(settings, grid)
    assert policy.calibrated is None and policy.grid is grid
    targets = _box_targets(grid, seed=9)
    verdict = policy.decide(targets, abc_to_matrix(np.tile([0.0, 90.0, 0.0], (len(targets), 1))))
    assert verdict.corrected.all()
    np.testing.assert_array_equal(verdict.command, grid.correct(targets, settings))


def test_policy_refuses_corrections_above_the_safety_limit_whatever_allow_partial():
    grid = _measured_grid(CALIBRATED)
    policy = Policy.build(CorrectionSettings(max_correction_mm=0.01), grid)
    targets = _box_targets(grid, seed=3, n=3)
    verdict = policy.decide(targets)
    assert (verdict.code == TOO_LONG).all()
    length = np.linalg.norm(grid.correct(targets) - targets, axis=1)
    np.testing.assert_allclose(verdict.value, length)
    with pytest.raises(InputError, match="exceeds the safety limit of 0.01 mm"):
        verdict.enforce(str, lambda i: (None,), allow_partial=True)


def test_residual_grid_setup_check_runs_for_a_model_without_identification():
    # A model file without an identification: section makes no accuracy claim; a residual grid
    # offset by 1 mm (measured with another tool or base) must still be refused, not added.
    grid = _measured_grid(PAPER, np.array([0.0, 0.0, 1.0]))
    assert PAPER.validated_max_mm is None
    with pytest.raises(InputError, match="offset from the model by"):
        Policy.build(CorrectionSettings(), grid, PAPER)
    small = _measured_grid(PAPER, np.array([0.0, 0.0, 0.1]))  # within the floor: accepted
    assert Policy.build(CorrectionSettings(), small, PAPER).grid is not None
