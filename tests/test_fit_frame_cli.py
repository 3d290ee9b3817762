"""`accugrid fit-frame` and `accugrid transform`: outputs, round trips and refusals (exit 2)."""

from __future__ import annotations

import importlib.util
import re

import numpy as np
import pytest
from conftest import EXAMPLES

from accugrid.app.cli import main
from accugrid.app.jobs.robot_frame import load_frame
from accugrid.kinematics.frames import invert, pose_from_xyzabc, transform_points

TRACKER = EXAMPLES / "tracker"
FILES = {
    "--base-plane": TRACKER / "base_plane.csv",
    "--a1-circle": TRACKER / "a1_circle.csv",
    "--flange-holes": TRACKER / "flange_holes.csv",
}


def _example_true_frame() -> np.ndarray:
    """tracker_T_robot the example files were generated from (make_tracker_points.py)."""
    spec = importlib.util.spec_from_file_location(
        "make_tracker", TRACKER / "make_tracker_points.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return pose_from_xyzabc(module.TRUE_XYZABC)


def fit_frame(tmp_path, *extra, files=None):
    out = tmp_path / "robot_frame.yaml"
    args = [x for flag, path in (files or FILES).items() for x in (flag, str(path))]
    return main(["fit-frame", *args, "-o", str(out), *extra]), out


def _error_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err


@pytest.fixture(scope="module")
def frame_file(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("frame")
    code, out = fit_frame(tmp, "--plot", str(tmp / "fit.png"))
    assert code == 0
    return out


def test_example_frame_is_recovered(frame_file):
    true = _example_true_frame()
    got = load_frame(frame_file)
    # 0.02 mm noise, 120° arc: 9.4 sigma = 0.19 mm is the worst origin error measured.
    assert np.linalg.norm(got[:3, 3] - true[:3, 3]) < 0.2
    angle = np.degrees(np.arccos(np.clip((np.trace(got[:3, :3].T @ true[:3, :3]) - 1) / 2, -1, 1)))
    assert angle < 0.01
    text = frame_file.read_text()
    assert re.search(r"a1_circle: \{points: 24, radius_mm: 178\d\.\d{4}, arc_deg: 120\.00", text)
    assert "smr_radius_mm: 19.0500" in text
    png = frame_file.parent / "fit.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_smr_radius_option_moves_the_origin(tmp_path, frame_file):
    code, out = fit_frame(tmp_path, "--smr-radius", "12.7")
    assert code == 0
    shift = invert(load_frame(frame_file)) @ load_frame(out)
    np.testing.assert_allclose(shift[:3, 3], [0.0, 0.0, 19.05 - 12.7], atol=1e-5)


def test_bad_cell_exit_2_names_file_line_column_and_writes_nothing(tmp_path, capsys):
    bad = tmp_path / "a1.csv"
    lines = FILES["--a1-circle"].read_text().splitlines(keepends=True)
    cells = lines[5].rstrip("\n").split(",")
    cells[2] = "1.5mm"
    lines[5] = ",".join(cells) + "\n"
    bad.write_text("".join(lines))
    code, out = fit_frame(tmp_path, files={**FILES, "--a1-circle": bad})
    assert code == 2
    assert re.search(
        rf"{re.escape(str(bad))}:6:3: '1.5mm' in column 'y' is not a number", _error_line(capsys)
    )
    assert not out.exists()


def test_degenerate_file_exit_2_names_the_file(tmp_path, capsys):
    short = tmp_path / "holes.csv"
    short.write_text("id,x,y,z\nH1,0,0,0\nH2,1,0,0\n")
    code, out = fit_frame(tmp_path, files={**FILES, "--flange-holes": short})
    assert code == 2
    assert f"{short}: flange-hole circle: 2 point(s), at least 3 are needed" in _error_line(capsys)
    assert not out.exists()


def test_existing_output_kept_without_force(tmp_path, capsys):
    out = tmp_path / "robot_frame.yaml"
    out.write_text("keep me\n")
    code, _ = fit_frame(tmp_path)
    assert code == 2
    assert "output exists" in _error_line(capsys)
    assert out.read_text() == "keep me\n"
    assert fit_frame(tmp_path, "--force")[0] == 0
    assert out.read_text() != "keep me\n"


def transform(src, frame, out, *extra):
    return main(["transform", str(src), "--frame", str(frame), "-o", str(out), *extra])


def test_transform_measurement_round_trip(tmp_path, frame_file):
    src = TRACKER / "meas_tracker.csv"
    robot, back = tmp_path / "robot.csv", tmp_path / "back.csv"
    assert transform(src, frame_file, robot) == 0
    assert transform(robot, frame_file, back, "--inverse") == 0
    original = src.read_text().splitlines()
    mapped = robot.read_text().splitlines()
    assert mapped[0].startswith(
        "# accugrid transform: x_meas,y_meas,z_meas mapped from the tracker"
    )
    assert mapped[1:5] == original[:4]  # comments and header kept
    pose = load_frame(frame_file)
    for line_in, line_out, line_back in zip(
        original[4:], mapped[5:], back.read_text().splitlines()[6:], strict=True
    ):
        cells_in, cells_out = line_in.split(","), line_out.split(",")
        assert cells_out[:7] == cells_in[:7]  # id, commanded x,y,z and a,b,c untouched
        tracker = np.array(cells_in[7:], dtype=float)
        expected = transform_points(invert(pose), tracker[None])[0]
        np.testing.assert_allclose(np.array(cells_out[7:], dtype=float), expected, atol=5e-5)
        np.testing.assert_allclose(
            np.array(line_back.split(",")[7:], dtype=float), tracker, atol=2e-4
        )
        # The example's TCP error is a few tenths of a mm: mapped points sit near the commands.
        np.testing.assert_allclose(expected, np.array(cells_in[1:4], dtype=float), atol=0.6)


def test_transform_xyz_default_and_quoted_cells(tmp_path, frame_file):
    src = tmp_path / "pts.csv"
    src.write_text('# points\nid,note,x,y,z\nP1,"a, b",1,2,3\n\nP2,,,,\nP3,c,4,5,6\n')
    out = tmp_path / "out.csv"
    assert transform(src, frame_file, out) == 0
    lines = out.read_text().splitlines()
    assert lines[1:3] == ["# points", "id,note,x,y,z"]
    assert lines[3].startswith('P1,"a, b",')
    assert lines[4:6] == ["", "P2,,,,"]  # blank line and an all-empty triple kept
    pose = invert(load_frame(frame_file))
    got = np.array([lines[3].split(",")[3:], lines[6].split(",")[2:]], dtype=float)
    np.testing.assert_allclose(got, transform_points(pose, [[1, 2, 3], [4, 5, 6]]), atol=5e-5)


def test_transform_triples_both(tmp_path, frame_file, capsys):
    """--triples both maps both triples; --columns is the column mapping of every command that
    reads positions, so its former meaning here (a triple) is refused, exit 2."""
    src = TRACKER / "meas_tracker.csv"
    new, old = tmp_path / "new.csv", tmp_path / "old.csv"
    assert transform(src, frame_file, new, "--triples", "both") == 0
    first = new.read_text().splitlines()[5].split(",")
    original = src.read_text().splitlines()[4].split(",")
    assert first[1:4] != original[1:4] and first[7:] != original[7:]  # both triples mapped
    capsys.readouterr()
    with pytest.raises(SystemExit) as exit_info:
        transform(src, frame_file, old, "--columns", "both")
    assert exit_info.value.code == 2 and not old.exists()
    assert "'both' is not NAME=HEADER" in capsys.readouterr().err


def test_transform_writes_an_export_as_it_came(tmp_path, frame_file):
    """A semicolon, decimal-comma export in metres with its own column names and a trailing
    delimiter: read with --columns/--units like any reader, mapped, and written back in its own
    delimiter, decimal mark and unit; every other cell as it was."""
    src = tmp_path / "export.csv"
    src.write_text(
        "# tracker export\nName;MX;MY;MZ;Temp;\nP1;1,5;0,25;-0,125;21,5;\nP2;;;;22;\n"
        "P3;2;-0,5;0,75;21,75;\n"
    )
    out = tmp_path / "out.csv"
    options = ["--columns", "x_meas=MX,y_meas=MY,z_meas=MZ", "--units", "m"]
    assert transform(src, frame_file, out, *options) == 0
    lines = out.read_text().splitlines()
    assert lines[1:3] == ["# tracker export", "Name;MX;MY;MZ;Temp;"]
    assert lines[4] == "P2;;;;22;"
    rows = [lines[3].split(";"), lines[5].split(";")]
    assert [r[0] for r in rows] == ["P1", "P3"] and [r[4:] for r in rows] == [
        ["21,5", ""],
        ["21,75", ""],
    ]
    got_m = np.array([[float(c.replace(",", ".")) for c in r[1:4]] for r in rows])
    assert all(len(c.split(",")[1]) == 7 for r in rows for c in r[1:4])  # 4 decimals of mm, in m
    expected_mm = transform_points(
        invert(load_frame(frame_file)), [[1500, 250, -125], [2000, -500, 750]]
    )
    np.testing.assert_allclose(got_m * 1000, expected_mm, atol=5e-5)


def test_transform_refusals(tmp_path, frame_file, capsys):
    out = tmp_path / "out.csv"
    partial = tmp_path / "partial.csv"
    partial.write_text("id,x,y,z\nP1,1,,3\n")
    assert transform(partial, frame_file, out) == 2
    assert f"{partial}:2:3: empty cell in column 'y'" in _error_line(capsys)
    no_cols = tmp_path / "nocols.csv"
    no_cols.write_text("id,x,y\nP1,1,2\n")
    assert transform(no_cols, frame_file, out) == 2
    assert f"{no_cols}:1: missing column(s) z" in _error_line(capsys)
    frame = tmp_path / "frame.yaml"
    frame.write_text("tracker_T_robot:\n  x: 1\n  y: 2\n  z: 3\n  a: 0\n  b: oops\n  c: 0\n")
    assert transform(partial, frame, out) == 2
    assert f"{frame}:6: key 'tracker_T_robot.b' must be a finite number" in _error_line(capsys)
    assert not out.exists()


def test_frame_matrix_must_agree_with_xyzabc(tmp_path, frame_file, capsys):
    edited = tmp_path / "edited.yaml"
    text = frame_file.read_text()
    line_a = next(line for line in text.splitlines() if line.startswith("  a: "))
    edited.write_text(text.replace(line_a, "  a: 10.0"))
    matrix_line = text.splitlines().index("  matrix:") + 1
    assert transform(TRACKER / "meas_tracker.csv", edited, tmp_path / "out.csv") == 2
    err = _error_line(capsys)
    assert f"{edited}:{matrix_line}: key 'tracker_T_robot.matrix' disagrees" in err
    missing = tmp_path / "missing.csv"
    code, out = fit_frame(tmp_path, files={**FILES, "--base-plane": missing})
    assert code == 2
    assert f"{missing}: cannot read" in _error_line(capsys)
    assert not out.exists()
