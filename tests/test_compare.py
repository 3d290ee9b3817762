"""`accugrid compare` (compensation.comparison): grid only vs model vs model + residual grid on a
simulated kr210-realistic, on a tiny run. Invariants, not copied numbers: every correction
leaves less than the uncorrected error, and on tilted targets the model (which holds at any
orientation) beats the grid measured at one orientation."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from accugrid.app.cli import main
from accugrid.compensation.comparison import (
    METHODS,
    grid_counts,
    joint_residual,
    joint_residual_cv,
    lattice,
)

TINY = ["--budgets", "27", "--targets", "40", "--candidates", "300", "--repeats", "1"]
TINY += ["--robot", "kr210-realistic", "--tool", "0", "0", "250", "0", "0", "0"]


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("compare")
    assert main(["compare", *TINY, "-o", str(out)]) == 0
    return out


def rows_of(out):
    lines = (out / "comparison.csv").read_text().splitlines()
    assert lines[0].startswith("# accugrid compare: kr210-realistic")
    return list(csv.DictReader(lines[1:]))


def values(row, kind):
    return np.array([float(row[f"{kind}_{axis}"]) for axis in "xyz"])


def test_every_method_leaves_less_than_the_uncorrected_error(tiny_run):
    rows = rows_of(tiny_run)
    methods = {(r["targets"], r["method"]) for r in rows}
    plain = [m for m in METHODS if "harmonics" not in m]  # no --harmonics: no such rows
    assert methods == {(t, m) for t in ("grid orientation", "tilted") for m in plain}
    for targets in ("grid orientation", "tilted"):
        mine = [r for r in rows if r["targets"] == targets]
        before = next(r for r in mine if r["method"] == "uncorrected")
        for r in mine:
            if r is not before:
                assert (values(r, "max") < values(before, "max")).all(), r["method"]
                assert (values(r, "std") < values(before, "std")).all(), r["method"]


def test_on_tilted_targets_the_model_beats_the_grid(tiny_run):
    tilted = {r["method"]: r for r in rows_of(tiny_run) if r["targets"] == "tilted"}
    model = np.linalg.norm(values(tilted["model"], "std"))
    for grid in ("grid idw", "grid trilinear"):
        assert model < np.linalg.norm(values(tilted[grid], "std")), grid


def test_the_points_column_counts_what_was_measured(tiny_run):
    rows = [r for r in rows_of(tiny_run) if r["budget"] == "27"]
    points = {r["targets"] + r["method"]: int(r["points"]) for r in rows}
    assert points["tiltedgrid idw"] == 27 and points["tiltedmodel"] == 27
    assert points["tiltedmodel + residual grid"] == 27 + 27
    for stat in ("max", "std"):
        assert (tiny_run / f"comparison_{stat}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("budget", [8, 27, 60, 125, 252, 1000])
def test_grid_counts_stay_within_the_budget(budget):
    lo, hi = np.array([1200.0, -600.0, 1100.0]), np.array([2200.0, 600.0, 2100.0])
    counts = grid_counts(lo, hi, budget)
    assert (counts >= 2).all() and np.prod(counts) <= budget
    vertices = lattice(lo, hi, counts)
    assert len(vertices) == np.prod(counts)
    np.testing.assert_allclose(vertices.min(axis=0), lo)
    np.testing.assert_allclose(vertices.max(axis=0), hi)


def test_a_budget_below_a_grid_is_refused_and_nothing_written(tmp_path, capsys):
    out = tmp_path / "cmp"
    assert main(["compare", "--budgets", "5", "-o", str(out)]) == 2
    assert "at least 8" in capsys.readouterr().err
    assert not out.exists()


def test_the_seed_grids_are_found_at_their_budgets():
    lo, hi = np.array([1200.0, -600.0, 1100.0]), np.array([2200.0, 600.0, 2100.0])
    assert grid_counts(lo, hi, 27).tolist() == [3, 3, 3]  # 500 x 600 x 500 mm
    assert grid_counts(lo, hi, 252).tolist() == [6, 7, 6]  # the seed's 200 mm grid


def test_the_joint_residual_reproduces_a_residual_linear_in_a1_a3():
    rng = np.random.default_rng(2)
    q, new = rng.uniform(-1.0, 1.0, (40, 6)), rng.uniform(-0.8, 0.8, (10, 6))
    slope = np.array([[0.1, -0.2, 0.05], [0.3, 0.0, -0.1], [-0.05, 0.2, 0.2]])  # mm per deg
    linear = lambda joints: np.degrees(joints[:, :3]) @ slope  # noqa: E731
    np.testing.assert_allclose(joint_residual(q, linear(q))(new), linear(new), atol=1e-6)
    # ... and A4..A6 do not enter it
    moved = new.copy()
    moved[:, 3:] += 0.5
    np.testing.assert_allclose(joint_residual(q, linear(q))(moved), linear(new), atol=1e-6)
    without, with_layer = joint_residual_cv(q, linear(q))
    assert (with_layer < 1e-6).all() and (without > 1.0).all()


def test_a_model_with_the_order_7_harmonics_beats_the_plain_model(tmp_path, capsys):
    # kr210-realistic's largest reducer terms are order 7 on A2 and A3 (1.8e-4, 8e-5 rad)
    assert main(["compare", *TINY, "--harmonics", "A2:7", "A3:7", "-o", str(tmp_path)]) == 0
    tilted = {r["method"]: r for r in rows_of(tmp_path) if r["targets"] == "tilted"}
    assert int(tilted["model + harmonics + residual grid"]["points"]) == 27 + 27
    plain = np.linalg.norm(values(tilted["model"], "std"))
    assert np.linalg.norm(values(tilted["model + harmonics"], "std")) < 0.8 * plain
    assert "skipped" not in capsys.readouterr().out


def test_a_budget_too_small_for_the_harmonic_model_skips_its_rows(tmp_path, capsys):
    every = ["A1:1,40,150", "A2:1,7,160", "A3:1,7,160", "A4:2", "A5:2", "A6:2"]
    assert main(["compare", *TINY, "--harmonics", *every, "-o", str(tmp_path)]) == 0
    assert not any("harmonics" in r["method"] for r in rows_of(tmp_path))
    out = capsys.readouterr().out
    assert "skipped budget 27: model + harmonics: 27 distinct poses for" in out


def test_harmonics_must_name_an_axis_and_orders(tmp_path, capsys):
    for bad, why in (
        ("A7:1", "axis 1..6"),
        ("A2:0", "order 1..100000"),
        ("A2:100001", "order 1..100000"),
        ("2:7", "is not AXIS:ORDERS"),
        ("A2:x", "is not AXIS:ORDERS"),
    ):
        with pytest.raises(SystemExit) as stop:
            main(["compare", "--harmonics", bad, "-o", str(tmp_path)])
        assert stop.value.code == 2
        err = capsys.readouterr().err
        assert "--harmonics" in err and why in err
    assert not any(tmp_path.iterdir())


def test_the_report_holds_the_table_and_both_figures(tmp_path, capsys):
    from report_helpers import check_report

    report = tmp_path / "compare.html"
    assert main(["compare", *TINY, "-o", str(tmp_path / "c"), "--report-html", str(report)]) == 0
    page = check_report(report, [], figures=2)
    assert page.verdict == ["no pass criterion"]
    text = " ".join(page.text)
    for row in rows_of(tmp_path / "c"):
        assert row["method"] in text and row["max_x"] in text
    assert f"wrote {report}" in capsys.readouterr().out
