"""Sampling plans: grid order, experiment design and the plan CSV."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from accugrid.compensation.cube_points import cube_test_points, cube_vertices
from accugrid.compensation.plans import (
    SEED_CENTRES,
    SEED_STEPS,
    experiment_plan,
    grid_axes,
    grid_plan,
    path_length,
    serpentine_order,
)
from accugrid.infra.csvtable import parse_table
from accugrid.infra.errors import InputError

counts = st.integers(1, 6)


@given(counts, counts, counts)
def test_serpentine_visits_every_vertex_once_by_unit_moves(nx, ny, nz):
    order = serpentine_order((nx, ny, nz))
    assert sorted(order.tolist()) == list(range(nx * ny * nz))
    ijk = np.column_stack(np.unravel_index(order, (nx, ny, nz)))
    if len(ijk) > 1:
        moves = np.abs(np.diff(ijk, axis=0)).sum(axis=1)
        assert np.all(moves == 1)


def test_grid_plan_path_is_shortest_and_beats_naive_order():
    lo, hi, step = (0.0, 0.0, 0.0), (400.0, 600.0, 800.0), 200.0
    snake = grid_plan(lo, hi, step, (0, 90, 0))
    naive = grid_plan(lo, hi, step, (0, 90, 0), order="naive")
    n = 3 * 4 * 5
    assert len(snake.points) == len(naive.points) == n
    # same set of vertices, each once
    key = lambda p: sorted(map(tuple, np.round(p, 6)))  # noqa: E731
    assert key(snake.points) == key(naive.points)
    assert len(set(map(tuple, snake.points))) == n
    assert snake.path_length() == pytest.approx((n - 1) * step)
    # raster order: per x level, 4*5 points; y rows return, x levels return
    assert naive.path_length() > snake.path_length()


def test_grid_axes_shrink_the_step_to_partition_the_region():
    axes = grid_axes((0, 0, 0), (100, 250, 200), 100)
    np.testing.assert_allclose(axes[0], [0, 100])
    np.testing.assert_allclose(axes[1], [0, 250 / 3, 500 / 3, 250])
    np.testing.assert_allclose(axes[2], [0, 100, 200])


def test_path_length():
    assert path_length(np.array([[0.0, 0, 0], [3, 4, 0], [3, 4, 12]])) == pytest.approx(17.0)
    assert path_length(np.zeros((1, 3))) == 0.0


def test_experiment_plan_holds_every_cube_point_repeats_times():
    plan = experiment_plan(SEED_CENTRES, SEED_STEPS, 5, (0, 90, 0))
    assert len(plan.points) == 5 * 9 * 5 * 17
    cen, stp = np.array(plan.extra["centre"]), np.array(plan.extra["step"], dtype=float)
    lab, rep = np.array(plan.extra["label"]), np.array(plan.extra["repeat"], dtype=int)
    for name, centre in SEED_CENTRES.items():
        for step in SEED_STEPS:
            sel = (cen == name) & (stp == step)
            assert sel.sum() == 5 * 17
            want = np.concatenate(
                [
                    cube_vertices(np.array([centre]), step)[0],
                    cube_test_points(np.array([centre]), step)[0],
                ]
            )
            labels = [f"C{i}" for i in range(1, 9)] + [f"P{i}" for i in range(1, 10)]
            for r in range(1, 6):
                rows = sel & (rep == r)
                got = dict(zip(lab[rows], plan.points[rows], strict=True))
                assert sorted(got) == sorted(labels)
                for k, label in enumerate(labels):
                    np.testing.assert_allclose(got[label], want[k])
    # rows of a cube are contiguous: the operator finishes one cube before the next
    key = [f"{c}/{s}" for c, s in zip(cen, stp, strict=True)]
    changes = sum(a != b for a, b in zip(key, key[1:], strict=False))
    assert changes == 5 * 9 - 1


def test_plan_csv_round_trips():
    plan = experiment_plan({"D": (1700, 0, 1500)}, [20, 80], 2, (0, 90, 0))
    table = parse_table(plan.csv_text(), "plan.csv")
    assert table.header[:7] == ["id", "x", "y", "z", "a", "b", "c"]
    assert table.header[-3:] == ["x_meas", "y_meas", "z_meas"]
    np.testing.assert_allclose(table.floats(["x", "y", "z"]), plan.points)
    np.testing.assert_allclose(
        table.floats(["a", "b", "c"]), np.tile([0, 90, 0], (len(plan.ids), 1))
    )
    assert table.text("id") == plan.ids and len(set(plan.ids)) == len(plan.ids)


@pytest.mark.parametrize(
    "centres, steps, repeats, match",
    [
        ({}, [20], 1, "at least one centre"),
        ({"A,B": (0, 0, 0)}, [20], 1, "centre name"),
        ({"A": (0, 0, 0)}, [20, 20], 1, "distinct"),
        ({"A": (0, 0, 0)}, [20], 0, "repeats"),
        ({"A": (0, 0, 0)}, [-20], 1, "step"),
    ],
)
def test_experiment_plan_bad_inputs(centres, steps, repeats, match):
    with pytest.raises(InputError, match=match):
        experiment_plan(centres, steps, repeats, (0, 90, 0))


def test_grid_plan_bad_inputs():
    with pytest.raises(InputError, match="min < max"):
        grid_plan((0, 0, 0), (0, 100, 100), 50, (0, 0, 0))
    with pytest.raises(InputError, match="step"):
        grid_plan((0, 0, 0), (100, 100, 100), 0, (0, 0, 0))
    with pytest.raises(InputError, match="order"):
        grid_plan((0, 0, 0), (100, 100, 100), 50, (0, 0, 0), order="random")


# --- the `accugrid plan` command -------------------------------------------------------------

import re  # noqa: E402

from accugrid.app.cli import main  # noqa: E402
from accugrid.codegen.krl.parse import parse_krl  # noqa: E402


def test_plan_cube_writes_csv_and_krl(tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["plan", "cube", "--centre", "1700", "0", "1500", "--step", "200"]
    argv += ["--repeats", "2", "-o", str(out), "--wait-input", "7"]
    assert main(argv) == 0
    table = parse_table((out / "measure_cube.csv").read_text(), "csv")
    assert len(table) == 34
    raw = (out / "measure_cube.src").read_bytes()
    assert raw.count(b"\r\n") == raw.count(b"\n")  # CRLF, like the drilling programs
    src = (out / "measure_cube.src").read_text()
    dat = (out / "measure_cube.dat").read_text()
    assert src.startswith("&ACCESS RVP\n&REL 1\nDEF measure_cube( )\n; accugrid ")
    assert "BAS(#INITMOV,0)" in src
    assert src.rstrip().endswith("END") and "$BASE = $NULLFRAME" in src
    moves = re.findall(r"^(PTP|LIN) (XMP\d+) ; (\S+)$", src, flags=re.M)
    assert [m[0] for m in moves] == ["PTP"] + ["LIN"] * 33
    assert [m[2] for m in moves] == table.text("id")
    assert src.count("WAIT FOR $IN[7] ; tracker done") == 34
    pattern = r"^DECL E6POS (XMP\d+)=\{X ([-\d.]+),Y ([-\d.]+),Z ([-\d.]+),"
    decl = {m[0]: m[1:] for m in re.findall(pattern, dat, re.M)}
    assert len(decl) == 17  # one declaration per distinct position
    xyz = table.floats(["x", "y", "z"])
    for (_, name, _), p in zip(moves, xyz, strict=True):
        np.testing.assert_allclose([float(v) for v in decl[name]], p, atol=5e-4)
    assert all(re.fullmatch(r"-?\d+\.\d{3}", v) for d in decl.values() for v in d)
    assert len(set(re.findall(r",S (\d+),T ", dat))) == 1  # one Status for the whole plan
    # the REWRITE engineer's KRL parser reads every declared position back
    parsed = [p for p in parse_krl(dat, "measure_cube.dat") if p.kind == "decl"]
    assert sorted(p.name for p in parsed) == sorted(decl)
    # refuses to overwrite without --force, then works with it
    assert main(argv) == 2
    assert main([*argv, "--force"]) == 0


def test_plan_grid_reports_path_lengths(tmp_path, capsys):
    argv = ["plan", "grid", "--region", "1500", "1900", "-200", "200", "1300", "1700"]
    assert main([*argv, "--step", "200", "-o", str(tmp_path), "--wait-sec", "1.5"]) == 0
    text = capsys.readouterr().out
    assert "path 5200.0 mm (serpentine 5200.0 mm, naive raster" in text
    src = (tmp_path / "measure_grid.src").read_text()
    assert src.count("WAIT SEC 1.500 ; tracker measures") == 27


def test_plan_unreachable_cube_is_input_error(tmp_path, capsys):
    argv = ["plan", "experiment", "--centre", "FAR", "3500", "0", "1500", "--steps", "20,80"]
    assert main([*argv, "-o", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "cannot be reached" in err and "FAR_S20_R1_C1" in err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    "extra, match",
    [
        (["--steps", "500:20:60"], "--steps"),
        (["--steps", "a,b"], "--steps"),
        (["--centre", "D", "1", "2", "x"], "numbers"),
    ],
)
def test_plan_bad_options(tmp_path, capsys, extra, match):
    assert main(["plan", "experiment", *extra, "-o", str(tmp_path)]) == 2
    assert match in capsys.readouterr().err


def test_a_negative_dwell_is_refused_by_the_option_type(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["plan", "experiment", "--wait-sec", "-1", "-o", str(tmp_path)])
    assert stop.value.code == 2
    assert "--wait-sec: '-1' must be >= 0 s" in capsys.readouterr().err


def test_experiment_step_column_keeps_precision():
    plan = experiment_plan({"A": (1700, 0, 1500)}, [12.5, 1234567.0], 1, (0, 90, 0))
    assert sorted(set(plan.extra["step"])) == ["12.5", "1234567"]
