"""The correction of a cell's job, the same for every command and the Python API: the calibrated
model file as every command reads it (``ModelFile``, ``read_model``), the grid and model a cell
names (``cell_grid``, ``cell_model``) and the one builder of the correction policy
(``policy_for``: ``compensation.policy.Policy`` from the cell, the grid, the model and what the
command asks, ``PolicyRequest``). ``krl``, ``gcode``, ``rapid``, ``rewrite`` and
``build_program`` build their policy here; ``correct``, which has no cell, builds it from its
own options with the same ``PolicyRequest``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from accugrid.codegen.cell_record import Cell
from accugrid.compensation.budget import Budget, ModelBudget
from accugrid.compensation.grid import GridModel
from accugrid.compensation.policy import Policy, PolicyRequest
from accugrid.infra.csvtable import declared_or

if TYPE_CHECKING:  # a grid-only job never loads the robot modules
    from accugrid.kinematics.model import RobotModel
    from accugrid.kinematics.robot import Robot
    from accugrid.kinematics.validity import Validity

__all__ = ["FROM_CELL", "ModelFile", "cell_grid", "cell_model", "policy_for", "read_model"]


class _FromCell:
    """``FROM_CELL``: a grid or model argument that means "the one the cell names"."""

    def __repr__(self) -> str:
        return "FROM_CELL"


FROM_CELL = _FromCell()


@dataclass(frozen=True)
class ModelFile:
    """A calibrated model as every command reads it: the robot (its ``true_robot()`` the arm,
    its tool the identified TCP: the SMR it was measured with), where it holds (``validity``,
    None without a record), the controller's tool of its measurements (flange_T_tool (4, 4)
    mm, None when the file does not record it) and its error budget (``compensation.budget``,
    None without a record)."""

    path: str
    robot: Robot
    validity: Validity | None
    measured_with: np.ndarray | None
    budget: ModelBudget | None = None

    @property
    def smr_tools(self) -> tuple[np.ndarray | None, np.ndarray]:
        """(controller, arm) tools that land the SMR the model was measured with."""
        return self.measured_with, self.robot.flange_T_tool


def read_model(path: str | os.PathLike[str], nominal: RobotModel | None = None) -> ModelFile:
    """Load a calibrated robot YAML (or a built-in robot name) once for a job; with
    ``nominal`` (the cell's robot) InputError unless it is a model of that robot."""
    from accugrid.infra.yamlfile import load_yaml
    from accugrid.kinematics.calibrated import check_dh_model, check_same_robot
    from accugrid.kinematics.frames import pose_from_xyzabc
    from accugrid.kinematics.robot import load_robot

    text = os.fspath(path)
    robot = load_robot(text)
    check_dh_model(robot, text)
    if nominal is not None:
        check_same_robot(robot, nominal, text)
    validity, tool, budget = None, None, None
    if Path(text).is_file():
        doc = load_yaml(text)
        structure = _structure(doc, robot)
        validity = _validity(doc, robot, structure)
        budget = ModelBudget.from_doc(doc, robot, structure)
        if doc.has("identification", "controller_tool"):
            keys = ("identification", "controller_tool")
            tool = pose_from_xyzabc([doc.number(*keys, k) for k in "xyzabc"])
    return ModelFile(text, robot, validity, tool, budget)


def _structure(doc, robot):
    """The parameters the calibrated file's model was identified with (``support.Structure``)."""
    from accugrid.kinematics.calibrated import model_structure
    from accugrid.kinematics.support import Structure

    chosen = doc.get("identification", "structure", "chosen", default=[]) or []
    compliance, harmonics, gravity = model_structure(robot, chosen)
    base_frame = doc.has("identification", "tracker_T_robot")
    return Structure(base_frame, compliance, harmonics, gravity)


def _validity(doc, robot, structure) -> Validity | None:
    """Where the calibrated file's model holds: its poses' region and, when it records one,
    its support among them (``kinematics.support``)."""
    from accugrid.kinematics.support import Support
    from accugrid.kinematics.validity import Validity

    validity = Validity.from_doc(doc)
    if validity is None or not doc.has("identification", "support"):
        return validity
    return replace(validity, support=Support.from_doc(doc, robot, structure))


def cell_grid(cell: Cell, path: str | os.PathLike[str] | None = None) -> GridModel | None:
    """The measured grid of a job on ``cell``: ``path`` (--grid), else the cell's ``grid``, read
    as the cell's tracker writes it; None when there is neither."""
    path = cell.grid_path if path is None else Path(path)
    if path is None:
        return None
    return GridModel.from_measurements(path, fmt=declared_or(cell.tracker))


def cell_model(cell: Cell, path: str | os.PathLike[str] | None = None) -> ModelFile | None:
    """The calibrated model of a job on ``cell``: ``path`` (--model), else the cell's
    ``correction.model``; None without one (``policy_for`` checks it is the cell robot's)."""
    path = cell.model_path if path is None else path
    return None if path is None else read_model(path)


def policy_for(
    cell: Cell,
    grid: GridModel | None,
    model: ModelFile | None,
    request: PolicyRequest,
    robot: RobotModel | None = None,
    targets: tuple[np.ndarray, np.ndarray] | None = None,
) -> Policy:
    """The correction policy of a job on ``cell`` (``compensation.policy``): ``grid`` the measured
    grid (the residual after ``model`` is computed here; None: none), ``model`` the calibrated model
    (None: none), ``request`` the command's options, checked here. From the cell: the correction
    settings (``request.outside`` in them), the job's KUKA Status and Turn, the wrist-singularity
    limit, the tool (the drill as taught, on the controller and on the calibrated arm), the measured
    tool's and part's uncertainty (the error budget's). ``robot``: the controller's robot with the
    cell's tool (None: the cell's robot, loaded when the model or a grid without its Status needs
    it); ``targets``: robot-frame points (N, 3) mm and their A, B, C (N, 3) deg, whose first gives a
    model's Status when neither the cell nor the grid does. InputError for bad options, a model of
    another robot, a residual grid the model cannot compute."""
    request.check()
    if robot is None and (model is not None or (grid is not None and grid.status is None)):
        from accugrid.kinematics.robot import load_robot

        robot = load_robot(cell.robot_name).with_tool(cell.flange_T_tool)
    nominal = None
    if robot is not None:
        from accugrid.kinematics.robot import Robot

        nominal = robot if isinstance(robot, Robot) else None  # a URDF robot has no Status
    if model is not None:
        from accugrid.kinematics.calibrated import check_same_robot

        check_same_robot(model.robot, robot, model.path)
    points, abc = (None, None) if targets is None else targets
    return Policy.build(
        cell.correction.but(outside=request.outside),
        grid,
        None if model is None else model.robot,
        cell.configuration.status,
        (cell.flange_T_tool, cell.flange_T_tool),
        points=points,
        abc_deg=abc,
        turn=cell.configuration.turn,
        nominal=nominal,
        validity=None if model is None else model.validity,
        budget=Budget(None if model is None else model.budget, frames=cell.frames),
        singular_deg=cell.configuration.singular_a5_deg,
        **request.limits(),
    )
