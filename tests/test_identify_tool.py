"""The drill's TCP measured on the calibrated arm: identify-tool, its file in a cell, the
controllers' tool lines, bad input; and the split of the last link against the TCP."""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from accugrid.app.cli import main
from accugrid.codegen.cell import load_cell
from accugrid.codegen.dialects import plugin_of
from accugrid.infra.errors import InputError
from accugrid.kinematics.calibrated import calibrated_yaml
from accugrid.kinematics.candidates import reference_joints
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.identification import LAST_LINK, identify, pose_set
from accugrid.kinematics.robot import load_robot
from accugrid.kinematics.robot_family import (
    NOISE_REPEAT_MM,
    NOISE_TRACKER_MM,
    FamilyRobot,
    random_robot,
)
from accugrid.kinematics.tool_calibration import fit_point, flange_poses_of, plan_tool_poses

TAUGHT = [10.0, -5.0, 320.0, 0.0, 0.0, 0.0]
TRUE_TIP = np.array([10.7, -5.4, 320.6])  # the real drill: 0.98 mm off the taught TCP
TRUE_AXIS = np.array([np.sin(np.radians(0.4)), 0.0, np.cos(np.radians(0.4))])  # 0.4 deg off Z
BACK_MM = 60.0
NOISE_MM = 0.02
CENTRE = np.array([1500.0, 0.0, 1500.0])


@pytest.fixture(scope="module")
def model_path(tmp_path_factory):
    """A calibrated kr210: seed Table 1's errors on the arm, the SMR at 250 mm."""
    paper = load_robot("kr210-paper")
    robot = load_robot("kr210").with_tool(pose_from_xyzabc([0, 0, 250, 0, 0, 0]))
    model = replace(robot, errors=paper.errors, name="kr210-calibrated")
    path = tmp_path_factory.mktemp("model") / "cal.yaml"
    validity = {
        "box_min_mm": [1200, -400, 1200],
        "box_max_mm": [1800, 400, 1800],
        "tool_axis": [0, 0, -1],
        "tilt_deg": 40,
        "joints_deg": [[-60, 60], [-130, -40], [20, 150], [-180, 180], [-125, 125], [-180, 180]],
    }
    path.write_text(calibrated_yaml(model, {"robot": "kr210", "poses": 60, "validity": validity}))
    return path


def measurement_csv(path, model_path, orientations=8, axis=True, joints=True, point_word="axis"):
    """The SMR at the real drill's tip (and 60 mm back on its axis) measured 3 times at
    ``orientations`` planned orientations; the model is the real arm."""
    model = load_robot(model_path)
    taught = pose_from_xyzabc(TAUGHT)
    _, q = plan_tool_poses(model, taught, CENTRE, orientations)
    q = np.repeat(q, 3, axis=0)
    flange = flange_poses_of(model, q)
    commanded = (model.with_tool(taught).fk(q))[:, :3, 3]
    rng = np.random.default_rng(5)
    rows = []
    points = [("tip", TRUE_TIP)] + ([(point_word, TRUE_TIP - BACK_MM * TRUE_AXIS)] if axis else [])
    for word, point in points:
        measured = flange[:, :3, :3] @ point + flange[:, :3, 3]
        measured += rng.normal(0.0, NOISE_MM, measured.shape)
        for c, m, j in zip(commanded, measured, np.degrees(q), strict=True):
            cells = [f"{v:.4f}" for v in (*c, *m)] + ([f"{v:.5f}" for v in j] if joints else [])
            rows.append(",".join([*cells, word]))
    header = "x,y,z,x_meas,y_meas,z_meas" + (",a1,a2,a3,a4,a5,a6" if joints else "") + ",point"
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


def run(*args):
    return main(["identify-tool", *map(str, args)])


def test_tip_and_axis_found_within_their_sigma(tmp_path, model_path, capsys):
    meas = measurement_csv(tmp_path / "tool.csv", model_path)
    out = tmp_path / "tool.yaml"
    assert run(meas, "--model", model_path, "--tool", *TAUGHT, "--number", 3, "-o", out) == 0
    doc = yaml.safe_load(out.read_text())
    tool = pose_from_xyzabc([doc["tool"][k] for k in "xyzabc"])
    sigma = np.array([doc["sigma"][k] for k in "xyz"])
    # 8 pose means of 3 rows: sigma = 0.02 / sqrt(3 * 8) per axis
    assert sigma == pytest.approx(NOISE_MM / np.sqrt(24), rel=0.5)
    assert np.all(np.abs(tool[:3, 3] - TRUE_TIP) < 4 * sigma)
    angle = np.degrees(np.arccos(tool[:3, 2] @ TRUE_AXIS))
    assert angle < 4 * doc["sigma"]["axis_deg"] and doc["sigma"]["axis_deg"] < 0.05
    assert doc["measured_on"]["robot"] == "kr210"
    printed = capsys.readouterr().out
    krl = re.search(r"TOOL_DATA\[3\]=\{X (\S+),Y (\S+),Z (\S+),A (\S+),B (\S+),C (\S+)\}", printed)
    assert krl and np.allclose(
        [float(v) for v in krl.groups()], [doc["tool"][k] for k in "xyzabc"], atol=6e-4
    )
    assert "tool3.tframe:=[[" in printed
    assert f"cell: tool: {{file: {out}, number: 3}}" in printed


def test_tool_lines_of_each_dialect():
    pose = pose_from_xyzabc([1.5, -2.0, 300.25, 0.0, 0.0, 0.0])
    assert (
        plugin_of("krl").tool_line(2, pose)
        == "TOOL_DATA[2]={X 1.500,Y -2.000,Z 300.250,A 0.0000,B 0.0000,C 0.0000}"
    )
    assert plugin_of("rapid").tool_line(2, pose) == (
        "tool2.tframe:=[[1.500,-2.000,300.250],[1.000000000,0.000000000,0.000000000,0.000000000]];"
    )
    assert plugin_of("gcode").tool_line(2, pose) == "G10 L1 P2 X1.500 Y-2.000 Z300.250"
    turned = pose_from_xyzabc([0.0, 0.0, 200.0, 0.0, 90.0, 0.0])  # about Y by 90 deg
    assert plugin_of("rapid").tool_line(1, turned) == (
        "tool1.tframe:=[[0.000,0.000,200.000],[0.707106781,0.000000000,0.707106781,0.000000000]];"
    )
    assert plugin_of("gcode").tool_line(1, turned) == (
        "G10 L1 P1 X0.000 Y0.000 Z200.000 (turned: A 0.0000 B 90.0000 C 0.0000 deg have no "
        "tool-table form)"
    )


def write_cell(tmp_path, tool_file, model=None, robot="kr210"):
    cell = tmp_path / "cell.yaml"
    text = f"robot: {robot}\ntool: {{file: {tool_file}, number: 4}}\nbase: {{x: 0, number: 1}}\n"
    if model:
        text += f"correction: {{model: {model}}}\n"
    cell.write_text(text)
    return cell


def test_a_cell_takes_the_tool_file_of_its_model(tmp_path, model_path):
    meas = measurement_csv(tmp_path / "tool.csv", model_path, axis=False)
    out = tmp_path / "tool.yaml"
    assert run(meas, "--model", model_path, "-o", out) == 0
    doc = yaml.safe_load(out.read_text())
    cell = load_cell(write_cell(tmp_path, out.name, model_path))
    assert cell.tool_number == 4
    np.testing.assert_allclose(cell.flange_T_tool[:3, 3], [doc["tool"][k] for k in "xyz"])
    assert load_cell(write_cell(tmp_path, out.name)).tool_number == 4  # same robot, no model
    other = tmp_path / "other.yaml"
    other.write_text(model_path.read_text() + "# another calibration\n")
    with pytest.raises(InputError, match=r"tool\.file.*not on the cell's other\.yaml") as e:
        load_cell(write_cell(tmp_path, out.name, other))
    assert e.value.line == 2
    with pytest.raises(InputError, match="measured on robot kr210, the cell's robot is irb6700"):
        load_cell(write_cell(tmp_path, out.name, robot="irb6700"))


@pytest.mark.parametrize(
    "change, message",
    [
        ({"orientations": 5}, "at 5 distinct orientations"),
        ({"joints": False}, "needs the joints the controller logged"),
        ({"point_word": "back"}, "point 'back': one of tip, axis"),
    ],
)
def test_bad_input_is_one_located_line_and_writes_nothing(
    tmp_path, model_path, capsys, change, message
):
    meas = measurement_csv(tmp_path / "tool.csv", model_path, **change)
    out = tmp_path / "tool.yaml"
    assert run(meas, "--model", model_path, "-o", out) == 2
    err = capsys.readouterr().err
    assert message in err and str(meas) in err and len(err.strip().splitlines()) == 1
    assert "Traceback" not in err and not out.exists()


def test_joints_not_reaching_the_taught_tcp_are_refused(tmp_path, model_path, capsys):
    meas = measurement_csv(tmp_path / "tool.csv", model_path, axis=False)
    wrong = [*TAUGHT[:2], TAUGHT[2] + 5.0, *TAUGHT[3:]]
    assert run(meas, "--model", model_path, "--tool", *wrong, "-o", tmp_path / "t.yaml") == 2
    err = capsys.readouterr().err  # the tool that does explain the joints is named
    assert "a tool at x 10.000 y -5.000 z 320.000 mm on the flange" in err
    assert len(err.strip().splitlines()) == 1


def test_the_last_link_share_goes_to_the_tcp():
    """Position data see link 6's errors only with the TCP: identify holds them at zero and the
    TCP takes the whole share, with the fit as good as before."""
    drawn = random_robot(3)  # its DH errors and SMR offset, no joint errors: DH + TCP fit it all
    family = FamilyRobot(3, replace(drawn.robot, joint_errors=None), drawn.tcp_offset_mm)
    q = reference_joints(family.nominal, 60)
    s = family.session(q, repeats=1, seed=1)
    data = pose_set(family.nominal, s.commanded, s.measured, s.abc_deg, s.joints_deg)
    result = identify(family.nominal, data)
    assert np.all(result.x[LAST_LINK] == 0.0)
    assert "da6 dd6 dalpha6 dtheta6 (in the TCP)" in result.unidentifiable_text
    assert not result.identifiable[LAST_LINK].any() and result.identifiable[24:27].all()
    noise = np.hypot(NOISE_REPEAT_MM, NOISE_TRACKER_MM)
    assert np.sqrt(np.mean(result.residuals**2)) < 1.2 * noise


def test_planned_orientations_measured_without_logged_joints(tmp_path, model_path, capsys):
    """plan tool -> the operator's measurements (a,b,c kept, no joints) -> identify-tool --tool."""
    model = model_path
    assert main(["plan", "tool", "--model", str(model), "--tool", *map(str, TAUGHT),
                 "--axis-point", "-o", str(tmp_path / "plan")]) == 0  # fmt: skip
    printed = capsys.readouterr().out
    assert "tool plan: 8 orientations x 3 repeats about X 1500.0 Y 0.0 Z 1500.0" in printed
    plan = (tmp_path / "plan" / "measure_tool.csv").read_text().splitlines()
    header = plan[0].split(",")
    assert header[:8] == ["id", "x", "y", "z", "a", "b", "c", "point"] and len(plan) == 49
    assert (tmp_path / "plan" / "measure_tool.src").exists()
    robot = load_robot(model).with_tool(pose_from_xyzabc(TAUGHT))
    rows = [line.split(",") for line in plan[1:]]
    xyzabc = np.array([[float(v) for v in row[1:7]] for row in rows])
    q = robot.ik(pose_from_xyzabc(xyzabc)).q
    flange = flange_poses_of(robot, q)
    point = np.where(
        np.array([row[7] == "axis" for row in rows])[:, None],
        TRUE_TIP - BACK_MM * TRUE_AXIS,
        TRUE_TIP,
    )
    measured = np.einsum("nij,nj->ni", flange[:, :3, :3], point) + flange[:, :3, 3]
    lines = ["x,y,z,a,b,c,point,x_meas,y_meas,z_meas"] + [
        ",".join([*row[1:8], *(f"{v:.4f}" for v in m)])
        for row, m in zip(rows, measured, strict=True)
    ]
    meas = tmp_path / "meas.csv"
    meas.write_text("\n".join(lines) + "\n")
    out = tmp_path / "tool.yaml"
    assert main(["identify-tool", str(meas), "--model", str(model), "--tool",
                 *map(str, TAUGHT), "-o", str(out)]) == 0  # fmt: skip
    doc = yaml.safe_load(out.read_text())
    np.testing.assert_allclose([doc["tool"][k] for k in "xyz"], TRUE_TIP, atol=2e-4)  # 4 decimals
    tool = pose_from_xyzabc([doc["tool"][k] for k in "xyzabc"])
    assert np.degrees(np.arccos(tool[:3, 2] @ TRUE_AXIS)) < 1e-3


def test_simulate_measures_a_tool_off_its_taught_tcp(tmp_path, model_path):
    """plan tool -> simulate --smr/--smr-axis (the real drill on the model's arm, joints logged,
    column point carried) -> identify-tool finds that drill."""
    assert main(["plan", "tool", "--model", str(model_path), "--tool", *map(str, TAUGHT),
                 "--axis-point", "--repeats", "1", "-o", str(tmp_path / "plan")]) == 0  # fmt: skip
    axis_point = TRUE_TIP - BACK_MM * TRUE_AXIS
    session = tmp_path / "session.csv"
    assert main(["simulate", "--robot", str(model_path), "--tool", *map(str, TAUGHT),
                 "--poses", str(tmp_path / "plan" / "measure_tool.csv"),
                 "--smr", *map(str, TRUE_TIP), "--smr-axis", *map(str, axis_point),
                 "-o", str(session)]) == 0  # fmt: skip
    header = session.read_text().splitlines()[1].split(",")
    assert header[8:16] == ["a1", "a2", "a3", "a4", "a5", "a6", "point", "x_meas"]
    out = tmp_path / "tool.yaml"
    assert main(["identify-tool", str(session), "--model", str(model_path), "-o", str(out)]) == 0
    doc = yaml.safe_load(out.read_text())
    np.testing.assert_allclose([doc["tool"][k] for k in "xyz"], TRUE_TIP, atol=2e-4)
    tool = pose_from_xyzabc([doc["tool"][k] for k in "xyzabc"])
    assert np.degrees(np.arccos(tool[:3, 2] @ TRUE_AXIS)) < 1e-3


@settings(max_examples=25, deadline=None)
@given(
    tip=st.tuples(st.floats(-80, 80), st.floats(-80, 80), st.floats(50, 450)),
    seed=st.integers(0, 2**16),
)
def test_any_tip_comes_back_from_exact_measurements(tip, seed):
    """Noise-free: the fitted point is the SMR's, whatever it is, and the residuals vanish."""
    model = load_robot("kr210-paper")
    q = reference_joints(model, 7, seed)
    flange = flange_poses_of(model, q)
    measured = flange[:, :3, :3] @ np.array(tip) + flange[:, :3, 3]
    fit = fit_point(model, q, measured)
    np.testing.assert_allclose(fit.point_mm, tip, atol=1e-9)
    rot = flange[:, :3, :3]  # random joints: two flange orientations may lie within 5 deg
    cos = (np.einsum("ikl,jkl->ij", rot, rot) - 1) / 2  # cos of the angle between rot i and j
    apart = np.degrees(np.arccos(np.clip(cos, -1, 1))) >= 5
    kept: list[int] = []  # each orientation 5 deg or more from every one kept before it
    for i in range(len(rot)):
        kept += [i] if apart[i, kept].all() else []
    distinct = len(kept)
    assert fit.noise_mm < 1e-9 and fit.orientations == distinct
