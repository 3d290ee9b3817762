"""`accugrid fit-part`: the part frame from datums, its sigma, its refusals (exit 2, one located
line, nothing written), the base-frame line of each dialect and a cell whose base is the part
file."""

from __future__ import annotations

import re
import shutil

import numpy as np
import pytest
from conftest import EXAMPLES
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from accugrid.app.cli import main
from accugrid.codegen.cell import load_cell
from accugrid.codegen.dialects import plugin_of
from accugrid.codegen.part_file import load_part
from accugrid.infra.digest import file_sha256
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import pose_from_xyzabc, transform_points
from accugrid.kinematics.part_frame import fit_part_frame
from accugrid.kinematics.robot_family import NOISE_TRACKER_MM

DATUMS, NOMINAL = EXAMPLES / "panel_datums.csv", EXAMPLES / "panel_nominal.csv"
# the frame panel_datums.csv was simulated at (its comment says so)
EXAMPLE_TRUE = pose_from_xyzabc(np.array([1701.8, 298.8, 1000.9, -89.88, -0.08, 90.05]))


def _csv(path, rows, header="id,x,y,z"):
    path.write_text(header + "\n" + "".join(",".join(map(str, r)) + "\n" for r in rows))
    return path


def _one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err


def _fit_part(tmp_path, datums, nominal=NOMINAL, *extra):
    out = tmp_path / "part.yaml"
    code = main(["fit-part", str(datums), "--nominal", str(nominal), "-o", str(out), *extra])
    return code, out


def _holes() -> np.ndarray:
    """The example panel's holes (N, 3) mm, CAD frame."""
    from accugrid.codegen.points import read_points

    return read_points(EXAMPLES / "wing_panel_points.csv").xyz


def test_example_part_within_0_03_mm_at_the_holes(tmp_path, capsys):
    code, out = _fit_part(tmp_path, DATUMS)
    assert code == 0
    printed = capsys.readouterr().out
    fitted = load_part(out).robot_T_base
    holes = _holes()
    error = np.linalg.norm(
        transform_points(fitted, holes) - transform_points(EXAMPLE_TRUE, holes), axis=1
    )
    # 5 tooling balls, 0.02 mm tracker noise per axis
    assert error.max() < 0.03
    assert "BASE_DATA[1]={X 1701.780,Y 298.815,Z 1000.914," in printed
    assert "G10 L2 P1 X1701.780 Y298.815 Z1000.914 R-89.8790" in printed
    assert 'PERS wobjdata wobj1:=[FALSE,TRUE,"",[[1701.780,298.815,1000.914],' in printed
    assert "largest miss: datum TB2" in printed


@settings(max_examples=40, deadline=None)
@given(
    xyz=st.tuples(*[st.floats(-2500, 2500)] * 3),
    abc=st.tuples(st.floats(-180, 180), st.floats(-89, 89), st.floats(-180, 180)),
    n=st.integers(3, 7),
    seed=st.integers(0, 2**31),
    scale=st.one_of(st.none(), st.floats(0.999, 1.001)),
)
def test_random_frame_is_recovered_exactly(xyz, abc, n, seed, scale):
    """Noise-free datums anywhere on a 1 m part: the frame (and a fitted scale) come back, the
    residuals vanish and no datum is called moved."""
    rng = np.random.default_rng(seed)
    nominal = rng.uniform([-500, -300, -50], [500, 300, 150], (n, 3))
    spread = np.linalg.svd(nominal - nominal.mean(axis=0), compute_uv=False)
    assume(spread[1] > 0.2 * spread[0])  # off one line (a line is refused, tested below)
    true = pose_from_xyzabc(np.array([*xyz, *abc]))
    s = 1.0 if scale is None else scale
    measured = transform_points(true, s * nominal)
    fit = fit_part_frame(nominal, measured, [f"D{i}" for i in range(n)], scale=None if scale else 1)
    np.testing.assert_allclose(fit.robot_T_base, true, atol=1e-8)
    assert fit.scale == pytest.approx(s, abs=1e-12)
    assert fit.residuals_mm.max() < 1e-8
    assert fit.moved is None


def test_sigma_bound_covers_95_percent_of_the_actual_errors():
    """Over random frames, 4-6 datums and 0.02 mm tracker noise: the 95 % bound at the holes
    holds the actual error of the fitted frame in 93-97 % of the cases (2000 hole errors from
    400 fits; the binomial spread is 0.5 %)."""
    rng = np.random.default_rng(7)
    inside, total = 0, 0
    for _ in range(400):
        n = int(rng.integers(4, 7))
        nominal = rng.uniform([-500, -300, 0], [500, 300, 200], (n, 3))
        holes = rng.uniform([-500, -300, 0], [500, 300, 0], (5, 3))
        true = pose_from_xyzabc(
            rng.uniform([-3, -3, -3, -0.2, -0.2, -0.2], [3, 3, 3, 0.2, 0.2, 0.2])
        )
        measured = transform_points(true, nominal) + rng.normal(0, NOISE_TRACKER_MM, nominal.shape)
        fit = fit_part_frame(nominal, measured, [str(i) for i in range(n)])
        error = np.linalg.norm(
            transform_points(fit.robot_T_base, holes) - transform_points(true, holes), axis=1
        )
        inside += int((error <= fit.sigma_at(holes)[1]).sum())
        total += len(holes)
    assert 0.93 <= inside / total <= 0.97


def test_known_scale_and_fitted_scale(tmp_path, capsys):
    """A part 0.2 mm/m larger than its CAD: --scale fit finds it; --cte/--temperature give it."""
    nominal = np.loadtxt(NOMINAL, delimiter=",", skiprows=3, usecols=(1, 2, 3))
    measured = transform_points(EXAMPLE_TRUE, 1.0002 * nominal)
    ids = [f"TB{i + 1}" for i in range(len(nominal))]
    datums = _csv(tmp_path / "d.csv", [[i, *p] for i, p in zip(ids, measured, strict=True)])
    code, out = _fit_part(tmp_path, datums, NOMINAL, "--scale", "fit")
    assert code == 0
    printed = capsys.readouterr().out
    assert "scale 1.000200000" in printed
    assert "the part is 1.000200000 times its CAD size: scale the x, y, z" in printed
    assert "fit again without --scale/--cte for a cell" in printed
    np.testing.assert_allclose(load_part(out).robot_T_base, EXAMPLE_TRUE, atol=1e-5)
    # 1 + 20e-6 * (30 - 20) = 1.0002
    code, out = _fit_part(
        tmp_path, datums, NOMINAL, "--cte", "20e-6", "--temperature", "30", "--force"
    )
    assert code == 0
    assert "residual RMS 0.0000 mm" in capsys.readouterr().out


def _rows():
    nominal = np.loadtxt(NOMINAL, delimiter=",", skiprows=3, usecols=(1, 2, 3))
    return nominal, transform_points(EXAMPLE_TRUE, nominal)


@pytest.mark.parametrize(
    ("case", "expected"),
    [
        ("two", r"datums\.csv:2:1: 2 datum\(s\) \(TB1, TB2\): the part frame needs at least 3"),
        ("line", r"datums\.csv:2:1: datums TB1, TB2, TB3 lie on one line"),
        ("unknown", r"datums\.csv:4:1: datum TB9 is not in nominal\.csv \(its ids: TB1, TB2,"),
        ("moved", r"datums\.csv:4:1: datum TB3 is [01]\.\d{3} mm from where the other datums put "),
        ("repeat", r"nominal\.csv:3:1: datum TB1 repeats line 2"),
        ("cte", r"--cte and --temperature go together"),
    ],
)
def test_bad_input_one_located_line_exit_2_nothing_written(tmp_path, capsys, case, expected):
    nominal, measured = _rows()
    ids = ["TB1", "TB2", "TB3", "TB4", "TB5"]
    extra = []
    if case == "two":
        ids, nominal, measured = ids[:2], nominal[:2], measured[:2]
    elif case == "line":
        ids, nominal = ids[:3], np.array([[0, 0, 0], [500, 0, 0], [1000, 1, 0.5]])
        measured = transform_points(EXAMPLE_TRUE, nominal)
    elif case == "unknown":
        ids = ["TB1", "TB2", "TB9", "TB4", "TB5"]
    elif case == "moved":
        rng = np.random.default_rng(3)
        measured = measured + rng.normal(0, NOISE_TRACKER_MM, measured.shape)
        measured[2] += [0.6, -0.8, 0.0]  # 1 mm, 50x the noise
    elif case == "cte":
        extra = ["--cte", "23e-6"]
    nominal_ids = ["TB1", "TB1", "TB3"] if case == "repeat" else ids
    if case == "unknown":
        nominal_ids = ["TB1", "TB2", "TB3", "TB4", "TB5"]
    nominal_file = _csv(
        tmp_path / "nominal.csv", [[i, *p] for i, p in zip(nominal_ids, nominal, strict=False)]
    )
    datums = _csv(tmp_path / "datums.csv", [[i, *p] for i, p in zip(ids, measured, strict=True)])
    code, out = _fit_part(tmp_path, datums, nominal_file, *extra)
    assert code == 2
    assert re.search(expected, _one_line(capsys))
    assert not out.exists()


def test_moved_datum_is_named_and_an_unmoved_one_is_not():
    """A 1 mm move (50x the noise) is refused at any of 5 datums and named; without it, none
    is."""
    nominal, measured = _rows()
    ids = ["TB1", "TB2", "TB3", "TB4", "TB5"]
    noisy = measured + np.random.default_rng(5).normal(0, NOISE_TRACKER_MM, measured.shape)
    assert fit_part_frame(nominal, noisy, ids).moved is None
    for k in range(5):
        moved = noisy.copy()
        moved[k] += [0.0, 1.0, 0.0]
        with pytest.raises(InputError, match=rf"datum {ids[k]} is [01]\.\d+ mm from"):
            fit_part_frame(nominal, moved, ids)


def _cell(tmp_path, base_line: str):
    """A copy of examples/cell.yaml (and the grid it names) with the given base line."""
    folder = tmp_path / "cell"
    folder.mkdir(parents=True)
    shutil.copy(EXAMPLES / "grid_200mm.csv", folder)
    text = (EXAMPLES / "cell.yaml").read_text()
    text, count = re.subn(r"^base: \{.*\}$", base_line, text, flags=re.M)
    assert count == 1
    path = folder / "cell.yaml"
    path.write_text(text)
    return path


def test_cell_with_part_file_writes_the_program_of_the_same_base_typed_in(tmp_path, capsys):
    code, part = _fit_part(tmp_path, DATUMS)
    assert code == 0
    base = part.read_text().split("base:\n")[1].split("scale:")[0]
    typed = dict(line.strip().split(": ") for line in base.strip().splitlines())
    keys = ", ".join(f"{k}: {v}" for k, v in typed.items())
    cells = {
        "file": _cell(tmp_path / "a", "base: {file: ../part.yaml, number: 1}"),
        "typed": _cell(tmp_path / "b", f"base: {{number: 1, {keys}}}"),
    }
    shutil.copy(part, tmp_path / "a")
    assert np.array_equal(
        load_cell(cells["file"]).robot_T_base, load_cell(cells["typed"]).robot_T_base
    )
    programs = {}
    for name, cell in cells.items():
        out = tmp_path / name / "krl"
        args = ["krl", str(EXAMPLES / "wing_panel_points.csv"), "--cell", str(cell), "-o", str(out)]
        assert main(args) == 0
        programs[name] = {
            p.name: p.read_text().replace(file_sha256(cell), "CELL").replace(str(cell), "CELL")
            for p in sorted(out.iterdir())
        }
    assert set(programs["file"]) == {"WING_PANEL.src", "WING_PANEL.dat"}
    # the same program; only the error budget's bound grows by the part frame's uncertainty
    bounds = {}
    for name, files in programs.items():
        found = [re.search(r"^; largest u95 (\S+) mm.*\n", t, re.M) for t in files.values()]
        bounds[name] = {float(m.group(1)) for m in found}
        programs[name] = {
            k: t.replace(m.group(0), "") for (k, t), m in zip(files.items(), found, strict=True)
        }
    assert programs["file"] == programs["typed"]
    assert len(bounds["file"]) == len(bounds["typed"]) == 1
    assert bounds["file"].pop() > bounds["typed"].pop()


def _krl_refused_with_the_part(tmp_path, capsys) -> str:
    """``accugrid krl`` with a cell whose base is the fitted part.yaml: exit 2, nothing written;
    its one error line."""
    capsys.readouterr()
    cell = _cell(tmp_path, "base: {file: ../part.yaml, number: 1}")
    out = tmp_path / "krl"
    args = ["krl", str(EXAMPLES / "wing_panel_points.csv"), "--cell", str(cell), "-o", str(out)]
    assert main(args) == 2
    assert not out.exists()
    return _one_line(capsys)


def test_cell_refuses_a_part_out_of_the_robots_reach(tmp_path, capsys):
    """Datums given in the tracker frame (metres away) without --frame: the cell names
    base.file at its line."""
    nominal, measured = _rows()
    far = measured + [4000.0, 3000.0, 0.0]
    ids = ["TB1", "TB2", "TB3", "TB4", "TB5"]
    datums = _csv(tmp_path / "d.csv", [[i, *p] for i, p in zip(ids, far, strict=True)])
    code, part = _fit_part(tmp_path, datums)
    assert code == 0
    line = _krl_refused_with_the_part(tmp_path, capsys)
    assert re.search(r"cell\.yaml:\d+: base\.file: part\.yaml: datum TB\d lies \d+ mm from", line)
    assert "beyond its reach" in line


def test_cell_refuses_a_part_of_another_size_than_its_cad(tmp_path, capsys):
    """A cell's base is rigid: a part fitted 0.2 mm/m larger than its CAD would put every hole
    off by its distance from the origin x 2e-4, so the cell refuses it naming the fix."""
    nominal = np.loadtxt(NOMINAL, delimiter=",", skiprows=3, usecols=(1, 2, 3))
    measured = transform_points(EXAMPLE_TRUE, 1.0002 * nominal)
    ids = [f"TB{i + 1}" for i in range(len(nominal))]
    datums = _csv(tmp_path / "d.csv", [[i, *p] for i, p in zip(ids, measured, strict=True)])
    code, part = _fit_part(tmp_path, datums, NOMINAL, "--scale", "fit")
    assert code == 0
    line = _krl_refused_with_the_part(tmp_path, capsys)
    assert re.search(r"cell\.yaml:\d+: base\.file: part\.yaml: the part is 1\.000200 times", line)
    assert "fit the part again without --scale/--cte" in line


def test_base_lines_of_each_dialect_byte_for_byte():
    """The example cell's base (x 1700, y 300, z 1000, a -90, b 0, c 90): Rz(-90) Rx(90) is the
    quaternion [0.5, 0.5, -0.5, -0.5]."""
    pose = pose_from_xyzabc(np.array([1700.0, 300.0, 1000.0, -90.0, 0.0, 90.0]))
    assert plugin_of("krl").base_line(3, pose) == (
        "BASE_DATA[3]={X 1700.000,Y 300.000,Z 1000.000,A -90.0000,B 0.0000,C 90.0000}"
    )
    assert plugin_of("rapid").base_line(3, pose) == (
        'PERS wobjdata wobj3:=[FALSE,TRUE,"",[[1700.000,300.000,1000.000],'
        "[0.500000000,0.500000000,-0.500000000,-0.500000000]],[[0,0,0],[1,0,0,0]]];"
    )
    assert plugin_of("gcode").base_line(3, pose) == (
        "G10 L2 P3 X1700.000 Y300.000 Z1000.000 R-90.0000 (tilted: B 0.0000 C 90.0000 deg have "
        "no G10 form; program in the robot frame or a program_frame)"
    )
    flat = pose_from_xyzabc(np.array([10.0, -20.0, 0.5, 30.0, 0.0, 0.0]))
    assert plugin_of("gcode").base_line(12, flat) == (
        "G10 L2 P12 X10.000 Y-20.000 Z0.500 R30.0000 (work offsets are P1..P9)"
    )


def test_tracker_frame_datums_with_frame_file_give_the_robot_frame_part(tmp_path, capsys):
    """The example datums moved into a tracker frame, read as an export with semicolons,
    decimal commas and the tracker's own column names: --frame and the reading options give
    the part of the robot-frame file."""
    tracker_T_robot = pose_from_xyzabc(np.array([-2500.0, 1200.0, -300.0, 35.0, 0.4, -0.3]))
    frame = tmp_path / "frame.yaml"
    frame.write_text("tracker_T_robot: {x: -2500, y: 1200, z: -300, a: 35, b: 0.4, c: -0.3}\n")
    text = DATUMS.read_text().splitlines()
    rows = [line.split(",") for line in text if line and not line.startswith(("#", "id"))]
    robot = np.array([[float(v) for v in r[1:]] for r in rows])
    tracker = transform_points(tracker_T_robot, robot)
    export = tmp_path / "export.csv"
    export.write_text(
        "Point;X [mm];Y [mm];Z [mm]\n"
        + "".join(
            f"{r[0]};" + ";".join(f"{v:.6f}".replace(".", ",") for v in p) + "\n"
            for r, p in zip(rows, tracker, strict=True)
        )
    )
    code, direct = _fit_part(tmp_path, DATUMS)
    assert code == 0
    out = tmp_path / "via_tracker.yaml"
    argv = ["fit-part", str(export), "--nominal", str(NOMINAL), "--frame", str(frame)]
    argv += ["--columns", "id=Point,x=X [mm],y=Y [mm],z=Z [mm]", "-o", str(out)]
    argv += ["--delimiter", "semicolon", "--decimal", "comma"]
    assert main(argv) == 0, capsys.readouterr().err
    np.testing.assert_allclose(
        load_part(out).robot_T_base, load_part(direct).robot_T_base, atol=2e-5
    )


def test_cell_names_the_bad_key_of_a_part_file(tmp_path, capsys):
    code, part = _fit_part(tmp_path, DATUMS)
    assert code == 0
    capsys.readouterr()
    part.write_text(part.read_text().replace("  z: ", "  zz: ", 1))
    cell = _cell(tmp_path, "base: {file: ../part.yaml, number: 1}")
    out = tmp_path / "krl"
    args = ["krl", str(EXAMPLES / "wing_panel_points.csv"), "--cell", str(cell), "-o", str(out)]
    assert main(args) == 2
    assert re.search(r"part\.yaml:8:3: base\.zz: unknown key; did you mean z\?", _one_line(capsys))
    assert not out.exists()


def test_simulate_measures_the_datums_where_the_part_stands(tmp_path):
    """simulate --datums/--part -> fit-part: the frame comes back within the noise's reach, its
    covariance about the datums' centre read back for the error budget."""
    true = np.array([1702.5, 297.9, 1001.4, -89.9, 0.12, 90.1])
    datums = tmp_path / "datums.csv"
    assert main(["simulate", "--datums", str(NOMINAL), "--part", *map(str, true),
                 "--repeats", "3", "--noise-tracker", "0.02", "--seed", "3",
                 "-o", str(datums)]) == 0  # fmt: skip
    rows = [ln for ln in datums.read_text().splitlines() if not ln.startswith("#")]
    assert rows[0] == "id,x,y,z" and len(rows) == 1 + 5 * 3
    code, part = _fit_part(tmp_path, datums)
    assert code == 0
    fitted = load_part(part)
    at_holes = transform_points(fitted.robot_T_base, _holes())
    truth = transform_points(pose_from_xyzabc(true), _holes())
    assert np.linalg.norm(at_holes - truth, axis=1).max() < 0.05  # 15 rows of 0.02 mm noise
    assert fitted.covariance.shape == (6, 6) and np.allclose(
        fitted.centroid, fitted.measured.mean(axis=0)
    )


def test_simulate_datums_needs_the_part_frame(tmp_path, capsys):
    out = tmp_path / "datums.csv"
    assert main(["simulate", "--datums", str(NOMINAL), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--part" in err and not out.exists()
