"""Drilling programs corrected by a calibrated model (cell key correction.model, --model)."""

from __future__ import annotations

import numpy as np
import pytest
from program_helpers import CELL, POINTS, cell, robot

from accugrid.app.cli import main
from accugrid.codegen.cell import load_cell
from accugrid.codegen.points import read_points
from accugrid.codegen.program import build_program
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import transform_points
from accugrid.kinematics.robot import load_robot


def test_every_hole_point_lands_when_the_calibrated_arm_drives_the_program():
    points = read_points(POINTS)
    model = load_robot("kr210-realistic").with_tool(cell().flange_T_tool)
    program = build_program(points, cell(), robot(), None, model=model)
    assert program.corrected
    holes = transform_points(cell().robot_T_base, points.xyz)  # robot frame
    command = holes + program.correction
    poses = np.tile(np.eye(4), (len(holes), 1, 1))
    poses[:, :3, :3] = cell().robot_T_base[:3, :3] @ program.rotations
    poses[:, :3, 3] = command
    status = int(program.configuration.code[0, 0])
    sol = robot().ik(poses, status=status)  # the controller: nominal model, the cell's tool
    assert sol.ok.all()
    landed = model.true_robot().fk(sol.q)[:, :3, 3]
    np.testing.assert_allclose(landed, holes, atol=1e-3, rtol=0)
    # the same vector moves every stage of a hole
    stages = program.positions - program.nominal
    np.testing.assert_allclose(stages, stages[:, :1].repeat(4, axis=1), atol=1e-9)


def test_cell_correction_model_is_a_path_next_to_the_cell(tmp_path):
    text = CELL.read_text().replace("correction:", "correction:\n  model: cal/robot-cal.yaml", 1)
    assert text != CELL.read_text()
    path = tmp_path / "cell.yaml"
    path.write_text(text)
    assert load_cell(path).model_path == tmp_path / "cal" / "robot-cal.yaml"
    path.write_text(text.replace("model: cal/robot-cal.yaml", "model: 3"))
    with pytest.raises(
        InputError, match=r"cell.yaml:70: correction.model: must be a calibrated robot YAML"
    ):
        load_cell(path)


def test_krl_with_a_model_names_it_in_the_header_and_refuses_no_correction(tmp_path, capsys):
    out = tmp_path / "krl"
    argv = ["krl", str(POINTS), "--cell", str(CELL), "--model", "kr210-paper", "-o", str(out)]
    assert main(argv) == 0
    src = next(out.glob("*.src")).read_text()
    assert "; model kr210-paper sha256 built-in" in src
    assert "corrected by model kr210-paper and the residual grid" in src
    assert main([*argv[:-2], "--no-correction", "-o", str(tmp_path / "k2")]) == 2
    assert "--model and --no-correction exclude each other" in capsys.readouterr().err


def test_a_model_of_another_robot_is_refused(tmp_path, capsys):
    other = tmp_path / "other.yaml"
    text = (CELL.parent.parent / "kinematics" / "robots" / "kr210.yaml").read_text()
    other.write_text(text.replace("a_mm: 1150.0", "a_mm: 1100.0", 1))
    out = tmp_path / "o.ngc"
    argv = ["gcode", str(POINTS), "--cell", str(CELL), "--model", str(other), "-o", str(out)]
    assert main(argv) == 2
    assert "is of another robot" in capsys.readouterr().err
    assert not out.exists()
