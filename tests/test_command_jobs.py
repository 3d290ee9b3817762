"""The domain calls behind the commands (issue 10: a command parses, calls one function, writes,
prints): what moved out of app/commands/ keeps its rules, and a failing job prints nothing."""

from __future__ import annotations

import numpy as np
import pytest

from accugrid.app.cli import main
from accugrid.app.jobs.study import StudyRequest, study_files
from accugrid.compensation.plans import Plan, grid_vertices, reach_in_one_status
from accugrid.infra.errors import InputError
from accugrid.kinematics.robot import load_robot


def test_grid_vertices_start_at_each_minimum_and_name_an_off_step_maximum():
    points, notes = grid_vertices((0.0, 10.0, 0.0, 8.0, 5.0, 6.0), 4.0)
    # X 0, 4, 8 (10 is off the step); Y 0, 4, 8; Z 5 (6 is off the step); x outermost
    assert points.shape == (9, 3)
    np.testing.assert_array_equal(points[:3], [[0, 0, 5], [0, 4, 5], [0, 8, 5]])
    np.testing.assert_array_equal(points[-1], [8, 8, 5])
    assert notes == [
        "X stops at 8 (region maximum 10 is off the step)",
        "Z stops at 5 (region maximum 6 is off the step)",
    ]
    with pytest.raises(InputError, match="--region: Y minimum 3 must be below maximum 3"):
        grid_vertices((0.0, 1.0, 3.0, 3.0, 0.0, 1.0), 1.0)


def test_reach_in_one_status_names_the_first_position_out_of_reach():
    robot = load_robot("kr210")
    points = np.array([[1700.0, 0.0, 1500.0], [1800.0, 0.0, 1500.0], [9000.0, 0.0, 1500.0]])
    plan = Plan(points, np.array([0.0, 90.0, 0.0]), ["A", "B", "FAR"])
    with pytest.raises(InputError, match=r"1 of 3 plan positions .*first: FAR X 9000\.000"):
        reach_in_one_status(plan, robot)
    configuration, used = reach_in_one_status(Plan(points[:2], plan.abc, ["A", "B"]), robot)
    assert used == 6 and (configuration.code == 6).all() and configuration.quarter.shape == (2, 6)


def test_a_study_validates_by_itself_only_when_simulated():
    with pytest.raises(InputError, match="--validate goes with --measured"):
        study_files(StudyRequest(validate=("g.csv", "p.csv"), region=(0,) * 6), "out")


def test_a_failing_job_prints_nothing_and_writes_nothing(tmp_path, capsys):
    # the grid is reachable, Fig. 3's plane is not with a 250 mm tool: before, the grid's notes
    # and error summary were printed before the error
    csv, png = tmp_path / "m.csv", tmp_path / "f.png"
    code = main(
        ["simulate", "--region", "1200", "1600", "-200", "200", "1100", "1500", "--step", "130"]
        + ["--tool", "0", "0", "250", "0", "0", "0", "-o", str(csv), "--plot", str(png)]
    )
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "cannot be reached" in err
    assert list(tmp_path.iterdir()) == []
