"""`accugrid correct`: the corrected-points CSV, its summary, and every refusal."""

from __future__ import annotations

import csv
import hashlib
import io

import numpy as np
import pytest
from conftest import EXAMPLES

import accugrid
from accugrid.app.cli import main
from accugrid.app.jobs import correct as corrected
from accugrid.app.jobs.correct import ADDED
from accugrid.compensation import GridModel

SHIFT = np.array([0.1, -0.2, 0.3])  # a constant error e = P - M of the synthetic grid


def write_grid(tmp_path, abc=(0.0, 90.0, 0.0), shift=SHIFT):
    """A 3 x 3 x 3 grid (X 1000..1400, Y -200..200, Z 1000..1400) whose error is ``shift``."""
    lines = ["id,x,y,z,a,b,c,x_meas,y_meas,z_meas"]
    for x in (1000, 1200, 1400):
        for y in (-200, 0, 200):
            for z in (1000, 1200, 1400):
                meas = np.array([x, y, z]) - shift
                nums = [x, y, z, *abc, *meas]
                lines.append("V," + ",".join(f"{v:.4f}" for v in nums))
    path = tmp_path / "grid.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


def write_points(tmp_path, text):
    path = tmp_path / "points.csv"
    path.write_text(text)
    return path


def read_rows(path):
    text = path.read_text()
    body = [line for line in text.splitlines(keepends=True) if not line.startswith("#")]
    return list(csv.reader(io.StringIO("".join(body))))


def run(tmp_path, points, *extra, grid=None):
    out = tmp_path / "out.csv"
    grid = grid or write_grid(tmp_path)
    code = main(["correct", str(points), "--grid", str(grid), "-o", str(out), *extra])
    return code, out


def test_constant_error_is_added_and_input_columns_are_untouched(tmp_path, capsys):
    points = write_points(
        tmp_path,
        "# two holes\nid,x,y,z,note,a,b,c\n"
        'H1,1100.5,-12,1399.25,"countersink, 100 deg",0,90,0\n'
        "H2,1400,200,1000,,0,90,0\n",
    )
    code, out = run(tmp_path, points)
    assert code == 0
    rows = read_rows(out)
    assert rows[0] == "id,x,y,z,note,a,b,c,x_cmd,y_cmd,z_cmd,ex,ey,ez,flag".split(",")
    assert rows[1][:8] == ["H1", "1100.5", "-12", "1399.25", "countersink, 100 deg", "0", "90", "0"]
    assert rows[1][8:] == ["1100.6000", "-12.2000", "1399.5500", "0.1000", "-0.2000", "0.3000", ""]
    assert rows[2][8:14] == ["1400.1000", "199.8000", "1000.3000", "0.1000", "-0.2000", "0.3000"]
    head = [line for line in out.read_text().splitlines() if line.startswith("#")]
    assert head[0] == f"# accugrid {accugrid.__version__} correct"
    grid = tmp_path / "grid.csv"  # written by run()
    grid_sha = hashlib.sha256(grid.read_bytes()).hexdigest()
    assert f"# grid grid.csv sha256 {grid_sha}" in head
    assert "# method idw, power 1, iterations 1" in head
    assert any(line.startswith("# largest correction ") for line in head)
    summary = capsys.readouterr().out
    assert "corrected  2 point(s), idw power 1, 1 iteration" in summary
    assert "largest correction 0.3742 mm" in summary and "flagged    0 point(s)" in summary


def test_the_demo_points_match_the_grid_model(tmp_path):
    points = EXAMPLES / "wing_panel_robot.csv"
    grid = EXAMPLES / "grid_200mm.csv"
    code, out = run(tmp_path, points, "--iterations", "3", "--method", "trilinear", grid=grid)
    assert code == 0
    rows = read_rows(out)
    header, body = rows[0], rows[1:]
    col = {name: i for i, name in enumerate(header)}
    xyz = np.array([[float(r[col[n]]) for n in "xyz"] for r in body])
    cmd = np.array([[float(r[col[n]]) for n in ("x_cmd", "y_cmd", "z_cmd")] for r in body])
    e = np.array([[float(r[col[n]]) for n in ("ex", "ey", "ez")] for r in body])
    expected = GridModel.from_measurements(grid).correct(xyz, iterations=3, method="trilinear")
    np.testing.assert_allclose(cmd, expected, atol=5e-5)
    np.testing.assert_allclose(cmd - xyz, e, atol=1.1e-4)
    source = read_rows(points)
    assert [r[: len(source[0])] for r in body] == source[1:]


def test_outside_points_are_named_or_clamped_and_flagged(tmp_path, capsys):
    points = write_points(tmp_path, "id,x,y,z\nin,1200,0,1200\nfar,1450,0,1200\n")
    code, out = run(tmp_path, points)
    err = capsys.readouterr().err
    assert code == 2 and not out.exists()
    assert "points.csv:3: 1 point(s) cannot be corrected (1 outside the grid)" in err
    assert "hole 'far'" in err and "outside the grid box by 50.000 mm" in err
    code, out = run(tmp_path, points, "--outside", "clamp")
    assert code == 0
    rows = read_rows(out)
    assert rows[2][4:] == ["1450.1000", "-0.2000", "1200.3000", "0.1000", "-0.2000", "0.3000"] + [
        "outside the grid box by 50.000 mm: the nearest cell's error used"
    ]
    assert "flagged    1 point(s)" in capsys.readouterr().out
    code, out = run(tmp_path, points, "--allow-partial", "--force")  # written, far left as is
    assert code == 0
    rows = read_rows(out)
    assert rows[2][4:] == ["1450.0000", "0.0000", "1200.0000", "0.0000", "0.0000", "0.0000"] + [
        "not corrected: outside the grid box by 50.000 mm"
    ]
    assert "1 point(s) cannot be corrected (1 outside the grid)" in capsys.readouterr().err


def test_safety_limit_refuses_the_job_and_keeps_the_old_output(tmp_path, capsys):
    grid = write_grid(tmp_path, shift=np.array([4.0, 3.0, 0.0]))  # 5 mm corrections
    points = write_points(tmp_path, "id,x,y,z\nA,1200,0,1200\n")
    out = tmp_path / "out.csv"
    out.write_text("old\n")
    code, _ = run(tmp_path, points, "--force", grid=grid)
    assert code == 0  # exactly 5 mm is allowed
    out.write_text("old\n")
    code, _ = run(tmp_path, points, "--force", "--max-correction", "4.9", grid=grid)
    assert code == 2 and out.read_text() == "old\n"
    assert "correction of 5.000 mm exceeds the safety limit of 4.9 mm" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("orientation", "args", "code", "flag"),
    [
        ("0,90,0", [], 0, ""),
        ("0,83,0", [], 0, "orientation 7.0 deg from the grid's"),
        ("20,90,0", [], 2, None),  # 20 deg about robot Z
        ("0,70,0", ["--allow-orientation"], 0, "orientation 20.0 deg from the grid's"),
        ("0,70,0", ["--orientation-limit", "25"], 0, "orientation 20.0 deg from the grid's"),
    ],
)
def test_orientation_far_from_the_grid_is_flagged_or_refused(
    tmp_path, capsys, orientation, args, code, flag
):
    points = write_points(tmp_path, f"id,x,y,z,a,b,c\nA,1200,0,1200,{orientation}\n")
    result, out = run(tmp_path, points, *args)
    assert result == code
    if code:
        assert "beyond the limit of 15 deg" in capsys.readouterr().err
        assert not out.exists()
    else:
        assert read_rows(out)[1][-1] == flag


def test_drill_axis_orientation_is_compared_with_the_grid_tool_axis(tmp_path):
    # grid at A 0 B 90 C 0: the tool Z axis (third column of Ry(90 deg)) is robot +X
    points = write_points(tmp_path, "id,x,y,z,i,j,k\nA,1200,0,1200,2,0,0\nB,1200,0,1200,1,1,0\n")
    code, out = run(tmp_path, points, "--allow-orientation")
    assert code == 0
    flags = [r[-1] for r in read_rows(out)[1:]]
    assert flags == ["", "orientation 45.0 deg from the grid's"]


@pytest.mark.parametrize(
    ("points", "args", "message"),
    [
        ("x,y,z,ex\n1200,0,1200,1\n", [], "column(s) ex would be written"),
        ("x,y,z\n1200,zero,1200\n", [], "points.csv:2:2: 'zero' in column 'y'"),
    ],
)
def test_bad_input_is_one_line_exit_2(tmp_path, capsys, points, args, message):
    code, out = run(tmp_path, write_points(tmp_path, points), *args)
    err = capsys.readouterr().err
    assert code == 2 and not out.exists()
    assert message in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--method", "idw", "--power", "0"], "--power: '0' must be > 0"),
        (["--iterations", "0"], "--iterations: '0' must be >= 1"),
        (["--max-correction", "0"], "--max-correction: '0' must be > 0 mm"),
    ],
)
def test_bad_option_values_are_refused_by_their_type(tmp_path, capsys, args, message):
    with pytest.raises(SystemExit) as stop:
        run(tmp_path, write_points(tmp_path, "x,y,z\n1200,0,1200\n"), *args)
    assert stop.value.code == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "out.csv").exists()


def test_existing_output_needs_force_and_inputs_are_never_targets(tmp_path, capsys):
    points = write_points(tmp_path, "x,y,z\n1200,0,1200\n")
    out = tmp_path / "out.csv"
    out.write_text("keep\n")
    code, _ = run(tmp_path, points)
    assert code == 2 and out.read_text() == "keep\n"
    grid = write_grid(tmp_path)
    code = main(["correct", str(points), "--grid", str(grid), "-o", str(points), "--force"])
    assert code == 2 and "refusing to overwrite an input file" in capsys.readouterr().err


def test_same_inputs_give_byte_identical_output_and_empty_points_work(tmp_path):
    points = write_points(tmp_path, "id,x,y,z\nA,1234.5,-67.8,1111.1\n")
    run(tmp_path, points)
    first = (tmp_path / "out.csv").read_bytes()
    code, out = run(tmp_path, points, "--force")
    assert code == 0 and out.read_bytes() == first
    empty = write_points(tmp_path, "id,x,y,z\n")
    code, out = run(tmp_path, empty, "--force")
    assert code == 0 and read_rows(out) == [["id", "x", "y", "z", *ADDED]]


def test_the_csv_in_blocks_and_through_either_reader_is_the_same(tmp_path, monkeypatch):
    """Rows written block by block (3 at a time) give the file written at once, and a file the
    fast reader takes gives the rows csv.writer writes for the same cells read by the csv
    module (the same file with every cell quoted)."""
    rng = np.random.default_rng(5)
    xyz = rng.uniform([1010, -190, 1010], [1390, 190, 1390], (10, 3))
    plain = "id,x,y,z,a,b,c\n" + "".join(
        f"P{i},{x:.3f},{y:.3f},{z:.3f},0,90,0\n" for i, (x, y, z) in enumerate(xyz)
    )
    quoted = "\n".join(
        ",".join(f'"{cell}"' for cell in line.split(",")) for line in plain.splitlines()
    )
    outputs = []
    for name, text, block in (("a", plain, 65536), ("b", plain, 3), ("c", quoted + "\n", 3)):
        monkeypatch.setattr(corrected, "BLOCK", block)
        points = tmp_path / f"{name}.csv"
        points.write_text(text)
        out = tmp_path / f"{name}_out.csv"
        assert (
            main(["correct", str(points), "--grid", str(write_grid(tmp_path)), "-o", str(out)]) == 0
        )
        outputs.append([ln for ln in out.read_text().splitlines() if not ln.startswith("#")])
    assert outputs[0] == outputs[1] == outputs[2] and len(outputs[0]) == 11
