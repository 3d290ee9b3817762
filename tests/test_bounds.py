"""Issue 12 items 6, 7, 9, 15, 16: every speed, distance and count bounded with a located error;
grid-structure and fit-frame errors name the right file and line."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from conftest import EXAMPLES

from accugrid.app.cli import main
from accugrid.codegen.cell import load_cell
from accugrid.codegen.points import parse_points
from accugrid.compensation.measurements import build_grid, read_measurements
from accugrid.infra.errors import InputError
from accugrid.infra.yamlfile import YamlDoc

POINTS = "id,x,y,z,i,j,k,feed\nH1,0,150,-10,0,0,-1,{feed}\n"


@pytest.mark.parametrize("feed", ["1e6", "6e302", "9" * 310, "2000.5"])
def test_per_hole_feed_is_bounded_at_its_cell(feed):
    with pytest.raises(InputError) as info:
        parse_points(POINTS.format(feed=feed), "p.csv")
    err = info.value
    assert (err.path, err.line, err.column) == ("p.csv", 2, 8)
    assert "feed" in err.message


def test_feed_at_the_limit_and_below_is_accepted():
    for feed in ("2000", "0.5"):
        assert parse_points(POINTS.format(feed=feed), "p.csv").feed[0] == float(feed)


def test_feed_of_zero_is_refused():
    with pytest.raises(InputError, match="feed must be positive"):
        parse_points(POINTS.format(feed="0.0000"), "p.csv")


@pytest.mark.parametrize("column, value", [("x", "1e308"), ("z", "-2e6")])
def test_coordinates_are_bounded(column, value):
    text = "x,y,z\n1,2,3\n" + ",".join(value if c == column else "0" for c in "xyz") + "\n"
    with pytest.raises(InputError) as info:
        parse_points(text, "p.csv")
    assert (info.value.line, info.value.column) == (3, "xyz".index(column) + 1)


def test_huge_ijk_keep_their_direction():
    """Item 15: (1e300, 0, -1e300) overflowed the norm to infinity and became the reference."""
    text = "x,y,z,i,j,k\n0,0,0,1e300,0,-1e300\n0,0,0,1e-300,0,-1e-300\n"
    with pytest.raises(InputError, match="zero length") as info:
        parse_points(text, "p.csv")
    assert info.value.line == 3
    points = parse_points(text.rsplit("0,0,0,1e-300", 1)[0], "p.csv")
    np.testing.assert_allclose(points.axis, [[np.sqrt(0.5), 0.0, -np.sqrt(0.5)]])


@pytest.mark.parametrize(
    "key, value",
    [
        ("apo_cdis", "1e300"),
        ("peck", "1e9"),
        ("depth", "20000"),
        ("approach", "1e5"),
        ("peck", "9" * 400),
    ],
)
def test_cell_drilling_distances_are_bounded_and_located(tmp_path, key, value):
    text = (EXAMPLES / "cell.yaml").read_text()
    lines = text.splitlines()
    row = next(i for i, t in enumerate(lines) if t.strip().startswith(f"{key}:"))
    lines[row] = f"  {key}: {value}"
    path = tmp_path / "cell.yaml"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError) as info:
        load_cell(path)
    assert (info.value.path, info.value.line) == (str(path), row + 1)


def test_cell_frames_are_bounded(tmp_path):
    path = tmp_path / "cell.yaml"
    path.write_text(
        (EXAMPLES / "cell.yaml")
        .read_text()
        .replace(
            "tool: {number: 1, x: 0, y: 0, z: 250,", "tool: {number: 1, x: 0, y: 0, z: 1.0e+300,"
        )
    )
    with pytest.raises(InputError, match="tool.z: must be <= 1e"):
        load_cell(path)


def test_integers_beyond_float_range_are_refused_in_yaml():
    with pytest.raises(InputError, match="integer out of range") as info:
        YamlDoc.parse("x: 1\ny: " + "1" * 309 + "\n", "r.yaml")
    assert (info.value.line, info.value.column) == (2, 4)


@pytest.mark.parametrize(
    "argv",
    [
        ["simulate", "--region", "0", "1000", "0", "1000", "0", "1000", "--step", "1e-6"],
        ["plan", "grid", "--step", "1e-300"],
    ],
)
def test_a_step_too_small_for_memory_is_refused_before_any_array(tmp_path, capsys, argv):
    code = main([*argv, "-o", str(tmp_path / "out")])
    assert code == 2
    assert "vertices, more than 1,000,000: use a larger step" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_repeat_tol_nan_is_refused(tmp_path, capsys):
    argv = ["correct", str(EXAMPLES / "wing_panel_robot.csv"), "--grid"]
    argv += [str(EXAMPLES / "grid_200mm.csv"), "-o", str(tmp_path / "o.csv")]
    with pytest.raises(SystemExit) as stop:  # refused by the option's type
        main([*argv, "--repeat-tol", "nan"])
    assert stop.value.code == 2
    assert "--repeat-tol: 'nan' is not a finite number (mm)" in capsys.readouterr().err
    assert not (tmp_path / "o.csv").exists()


# ---------------------------------------------------------------- locations (item 9)


def grid_text():
    return (EXAMPLES / "grid_200mm.csv").read_text()


def test_a_stray_point_is_located_at_its_line(tmp_path):
    text = grid_text()
    n = len(text.splitlines())
    path = tmp_path / "g.csv"
    path.write_text(text + "S,1250,0,1500,0,90,0,6,1250,0,1500\n")
    with pytest.raises(InputError, match="uneven grid spacing along x") as info:
        build_grid(read_measurements(path))
    assert (info.value.path, info.value.line) == (str(path), n + 1)


def test_a_single_level_is_located(tmp_path):
    path = tmp_path / "g.csv"
    path.write_text("x,y,z,x_meas,y_meas,z_meas\n0,0,0,0,0,0\n0,1,0,0,1,0\n")
    with pytest.raises(InputError, match="single x value") as info:
        build_grid(read_measurements(path))
    assert (info.value.path, info.value.line) == (str(path), 2)


def test_a_1e308_row_is_blamed_on_its_own_line(tmp_path):
    lines = grid_text().splitlines()
    lines[40] = lines[40].replace(lines[40].split(",")[2], "1e308", 1)
    path = tmp_path / "g.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError) as info:
        read_measurements(path)
    assert (info.value.line, info.value.column) == (41, 3)


def test_fit_frame_blames_the_base_plane_for_a_stray_base_plane_point(tmp_path, capsys):
    tracker = EXAMPLES / "tracker"
    plane = tmp_path / "base_plane.csv"
    lines = (tracker / "base_plane.csv").read_text().splitlines()
    cells = lines[5].split(",")
    cells[3] = f"{float(cells[3]) + 900:.4f}"
    lines[5] = ",".join(cells)
    plane.write_text("\n".join(lines) + "\n")
    shutil.copy(tracker / "a1_circle.csv", tmp_path / "a1.csv")
    shutil.copy(tracker / "flange_holes.csv", tmp_path / "flange.csv")
    code = main(
        [
            "fit-frame",
            "--base-plane",
            str(plane),
            "--a1-circle",
            str(tmp_path / "a1.csv"),
            "--flange-holes",
            str(tmp_path / "flange.csv"),
            "-o",
            str(tmp_path / "frame.yaml"),
        ]
    )
    err = capsys.readouterr().err
    assert code == 2
    assert f"error: {plane}: base plane: point 3 lies" in err


def test_a_single_link_urdf_is_a_located_input_error(tmp_path):
    """Item 6: a URDF without a joint ended in an internal error."""
    from accugrid.kinematics.robot import load_robot

    (tmp_path / "one.urdf").write_text(
        '<?xml version="1.0"?><robot name="one"><link name="flange"/></robot>\n'
    )
    (tmp_path / "robot.yaml").write_text("name: one\nurdf: one.urdf\ntip: flange\n")
    with pytest.raises(InputError, match="no movable joint") as info:
        load_robot(tmp_path / "robot.yaml")
    assert info.value.path == str(tmp_path / "one.urdf")


def test_urdf_parser_output_does_not_precede_the_error(tmp_path, capfd):
    """Item 8: tinyxml/urdfdom print to file descriptor 2 before our message; now their words
    are in the one line, with the line they name."""
    (tmp_path / "bad.urdf").write_text('<?xml version="1.0"?><robot name="x"><link name="a"/>\n')
    (tmp_path / "robot.yaml").write_text("name: x\nurdf: bad.urdf\ntip: a\n")
    argv = ["simulate", "--robot", str(tmp_path / "robot.yaml"), "--region", "0", "1", "0", "1"]
    code = main([*argv, "0", "1", "--step", "1", "-o", str(tmp_path / "s.csv")])
    err = capfd.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("accugrid simulate: error: ")
    assert f"{tmp_path / 'bad.urdf'}:" in err and "cannot read the URDF" in err
