"""The one correction decision (compensation.corrector): grid alone, model, model + residual."""

from __future__ import annotations

import numpy as np

from accugrid.compensation.corrector import Corrector
from accugrid.compensation.grid import GridModel
from accugrid.compensation.settings import CorrectionSettings
from accugrid.kinematics.frames import abc_to_matrix
from accugrid.kinematics.robot import load_robot

CALIBRATED = load_robot("kr210-realistic")  # its true robot stands for the calibrated arm
PAPER = load_robot("kr210-paper")  # geometric errors only
STATUS = 6  # the Status of the region at A 0 B 90 C 0 (test_model_correction.py)
ABC = np.array([0.0, 90.0, 0.0])
LO, HI = np.array([1300.0, -500.0, 1200.0]), np.array([2100.0, 300.0, 2000.0])  # grid box


def drive(robot, commands: np.ndarray, abc: np.ndarray, status: int) -> np.ndarray:
    """Where the arm goes: the controller's nominal IK in ``status``, then the true FK (mm)."""
    poses = np.tile(np.eye(4), (len(commands), 1, 1))
    poses[:, :3, :3] = abc_to_matrix(abc)
    poses[:, :3, 3] = commands
    sol = robot.ik(poses, status=status)
    assert sol.ok.all()
    return robot.true_robot().fk(sol.q)[:, :3, 3]


def _vertices(step: float = 400.0) -> np.ndarray:
    axes = [np.arange(LO[a], HI[a] + 1e-9, step) for a in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)


def _targets(n: int = 20, seed: int = 5) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return LO + rng.uniform(0.05, 0.95, (n, 3)) * (HI - LO)


def test_model_only_lands_on_the_targets_in_the_first_points_status():
    targets = _targets()
    abc = np.tile(ABC, (len(targets), 1))
    corrector = Corrector.build(CorrectionSettings(), None, CALIBRATED, points=targets, abc_deg=abc)
    assert corrector.grid is None and corrector.status == STATUS
    result = corrector.correct(targets, abc)
    assert result.ok.all() and (result.reason == "").all()
    reached = drive(CALIBRATED, result.command, ABC, STATUS)
    assert np.linalg.norm(reached - targets, axis=1).max() < 1e-3
    assert np.linalg.norm(result.command - targets, axis=1).min() > 0.5  # it did correct


def test_model_plus_residual_grid_lands_on_the_targets():
    # The real arm: the model kr210-paper moved by a constant offset the model does not know;
    # noise-free measurement of the vertices in STATUS. The residual grid holds the offset.
    offset = np.array([0.3, -0.2, 0.5])
    vertices = _vertices()
    measured = drive(PAPER, vertices, ABC, STATUS) + offset
    grid = GridModel.from_measurements((vertices, measured, np.tile(ABC, (len(vertices), 1))))
    corrector = Corrector.build(CorrectionSettings(method="trilinear"), grid, PAPER)
    assert corrector.status == STATUS  # the grid's measurement Status
    np.testing.assert_allclose(
        corrector.grid.errors.reshape(-1, 3), np.tile(-offset, (27, 1)), atol=1e-9
    )
    targets = _targets(seed=7)
    result = corrector.correct(targets, np.tile(ABC, (len(targets), 1)))
    assert result.ok.all()
    reached = drive(PAPER, result.command, ABC, STATUS) + offset
    assert np.linalg.norm(reached - targets, axis=1).max() < 1e-3


def test_a_given_status_wins_and_unreachable_targets_are_not_ok():
    corrector = Corrector.build(CorrectionSettings(), None, CALIBRATED, status=STATUS)
    assert corrector.status == STATUS
    targets = np.array([[1500.0, 0.0, 1500.0], [5000.0, 0.0, 1500.0]])
    result = corrector.correct(targets, np.tile(ABC, (2, 1)))
    assert result.ok.tolist() == [True, False]
    assert result.reason[1] == "unreachable"


def test_without_a_model_it_is_the_grid_correction():
    vertices = _vertices()
    measured = drive(CALIBRATED, vertices, ABC, STATUS)  # the realistic arm's error field
    grid = GridModel.from_measurements((vertices, measured, np.tile(ABC, (len(vertices), 1))))
    settings = CorrectionSettings(method="trilinear")
    corrector = Corrector.build(settings, grid)
    assert corrector.calibrated is None and corrector.grid is grid
    targets = _targets(seed=9)
    result = corrector.correct(targets, np.tile(ABC, (len(targets), 1)))
    assert result.ok.all()
    np.testing.assert_array_equal(result.command, grid.correct(targets, settings))


def test_too_long_masks_corrections_above_the_safety_limit():
    corrector = Corrector(CorrectionSettings(max_correction_mm=1.0), None)
    points = np.zeros((3, 3))
    command = np.array([[0.6, 0.8, 0.0], [3.0, 4.0, 0.0], [np.nan, np.nan, np.nan]])
    length, over = corrector.too_long(points, command)
    np.testing.assert_allclose(length, [1.0, 5.0, 0.0])
    assert over.tolist() == [False, True, False]
