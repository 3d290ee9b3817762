"""`accugrid simulate`: the measurement CSV of contracts.md, the Fig. 3 picture, every refusal."""

from __future__ import annotations

import csv

import numpy as np
import pytest
from conftest import ROOT

from accugrid.app.cli import main
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.robot import load_robot
from accugrid.kinematics.simulation import reached_positions

REGION = ["1400", "1800", "-200", "200", "1300", "1500"]


def simulate(tmp_path, *extra, region=REGION, step="200"):
    out = tmp_path / "meas.csv"
    code = main(["simulate", "--region", *region, "--step", step, "-o", str(out), *extra])
    return code, out


def refused(capsys, code, out, message):
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("accugrid simulate: error: ")
    assert message in err
    assert {p.name for p in out.parent.iterdir()} <= {"bad.yaml"}  # nothing written
    return err


def test_good_run_writes_the_measurement_csv(tmp_path):
    code, out = simulate(tmp_path, "--tool", "0", "0", "250", "0", "0", "0", "--repeats", "2")
    assert code == 0
    lines = out.read_text().splitlines()
    assert lines[0].startswith("# accugrid simulate: robot kr210-paper")
    rows = list(csv.DictReader(lines[1:]))
    assert list(rows[0]) == "id x y z a b c s x_meas y_meas z_meas".split()  # s: the Status
    assert len(rows) == 3 * 3 * 2 * 2  # 18 vertices x 2 repeats, consecutive
    assert [r["id"] for r in rows[:4]] == ["P1", "P1", "P2", "P2"]
    assert rows[0]["x"] == "1400.0000" and rows[0]["z"] == "1300.0000"
    assert (rows[0]["a"], rows[0]["b"], rows[0]["c"]) == ("0.0000", "90.0000", "0.0000")
    commanded = np.array([[float(r[k]) for k in "xyz"] for r in rows])
    measured = np.array([[float(r[f"{k}_meas"]) for k in "xyz"] for r in rows])
    robot = load_robot("kr210-paper").with_tool(pose_from_xyzabc([0, 0, 250, 0, 0, 0]))
    expected = reached_positions(robot, commanded[::2], [0, 90, 0])
    np.testing.assert_allclose(measured[::2], expected, atol=5e-5)  # no noise: 4 decimals


def test_noise_is_seeded(tmp_path):
    args = ("--repeats", "3", "--noise-tracker", "0.02", "--noise-repeat", "0.03", "--seed", "4")
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    assert simulate(tmp_path / "a", *args)[0] == 0
    assert simulate(tmp_path / "b", *args)[0] == 0
    text = (tmp_path / "a" / "meas.csv").read_text()
    assert text == (tmp_path / "b" / "meas.csv").read_text()
    assert simulate(tmp_path / "a", *args[:-1], "5", "--force")[0] == 0
    assert (tmp_path / "a" / "meas.csv").read_text() != text


def test_plot_writes_a_png(tmp_path):
    out = tmp_path / "fig3.png"
    assert main(["simulate", "--plot", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_demo_grid_is_what_the_demo_command_writes():
    # examples/demo.sh compares this file byte for byte with a fresh run; check the header here
    head = (ROOT / "examples" / "grid_200mm.csv").read_text().splitlines()[0]
    assert "status 6" in head and "region 1200 2200 -600 600 1100 2100" in head


def test_unknown_robot(tmp_path, capsys):
    code, out = simulate(tmp_path, "--robot", "kr999")
    refused(capsys, code, out, "unknown robot 'kr999'")


def test_malformed_robot_yaml_names_the_key(tmp_path, capsys):
    text = (ROOT / "kinematics" / "robots" / "kr210.yaml").read_text()
    path = tmp_path / "bad.yaml"
    path.write_text(text.replace("a_mm: 1150.0", "a_mm: long"))
    code, out = simulate(tmp_path, "--robot", str(path))
    err = refused(capsys, code, out, "'dh[1].a_mm' must be a finite number")
    assert f"{path}:12:" in err


@pytest.mark.parametrize("axis", [0, 2, 4])
def test_region_min_not_below_max(tmp_path, capsys, axis):
    region = list(REGION)
    region[axis + 1] = region[axis]
    code, out = simulate(tmp_path, region=region)
    refused(capsys, code, out, f"{'XYZ'[axis // 2]} minimum {region[axis]} must be below maximum")


@pytest.mark.parametrize("step", ["0", "-50"])
def test_non_positive_step(tmp_path, capsys, step):
    with pytest.raises(SystemExit) as stop:  # refused by the option's type
        simulate(tmp_path, step=step)
    assert stop.value.code == 2
    assert f"--step: '{step}' must be > 0 mm" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_unreachable_corner(tmp_path, capsys):
    code, out = simulate(tmp_path, region=["1400", "3600", "-200", "200", "1300", "1500"])
    refused(capsys, code, out, "cannot be reached by kr210-paper")


def test_existing_output_is_kept_without_force(tmp_path, capsys):
    out = tmp_path / "meas.csv"
    out.write_text("keep\n")
    code, _ = simulate(tmp_path)
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "exists" in err
    assert out.read_text() == "keep\n"
