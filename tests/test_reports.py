"""The HTML reports of identify and correct: self-contained (every figure inline, no URL), the
inputs with their SHA-256, the verdict; the size for 1e4 holes; bad report paths."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from conftest import EXAMPLES
from report_helpers import check_report
from test_identify_cli import TOOL, joints, write_csv

from accugrid.app.cli import main

GRID = EXAMPLES / "grid_200mm.csv"
MAX_REPORT_BYTES = 2_000_000


def test_identify_report_shows_what_the_calibrated_file_records(tmp_path):
    csv = write_csv(tmp_path / "meas.csv", joints(60, 1), noise=0.02)
    out, report = tmp_path / "cal.yaml", tmp_path / "ident.html"
    code = main(["identify", str(csv), "--robot", "kr210", "--tool", *TOOL, "-o", str(out),
                 "--report-html", str(report)])  # fmt: skip
    assert code == 0
    page = check_report(report, [csv], figures=1)
    summary = yaml.safe_load(out.read_text())["identification"]
    held_out = max(summary["structure"]["nested"]["held_out_max_mm"].values())  # not the CV score
    assert page.verdict == ["PASS" if held_out <= 0.3 else "FAIL"]
    text = " ".join(page.text)
    for step in summary["structure"]["cv_curve"]:
        assert step["added"] in text
    for p in summary["parameters"]:
        assert p["name"] in text
    for direction in summary["unidentifiable_directions"]:
        assert direction in text
    assert f"{summary['condition_number']:.6g}" in text


def test_identify_without_cross_validation_has_no_verdict(tmp_path):
    csv = write_csv(tmp_path / "meas.csv", joints(60, 1), noise=0.02)
    report = tmp_path / "ident.html"
    assert main(["identify", str(csv), "--robot", "kr210", "--tool", *TOOL, "--folds", "0",
                 "--structure", "dh",
                 "-o", str(tmp_path / "cal.yaml"), "--report-html", str(report)]) == 0  # fmt: skip
    assert check_report(report, [csv], figures=1).verdict == ["no pass criterion"]


def points_csv(path, n, seed=1, outside=0.0):
    """``n`` random holes in the example grid's box (X 1200..2200, Y -600..600, Z 1100..2100),
    a fraction ``outside`` of them moved 50 mm beyond its X end."""
    rng = np.random.default_rng(seed)
    xyz = rng.uniform([1200, -600, 1100], [2200, 600, 2100], (n, 3))
    xyz[: int(n * outside), 0] = 2250.0
    lines = ["id,x,y,z"] + [f"H{i},{x:.3f},{y:.3f},{z:.3f}" for i, (x, y, z) in enumerate(xyz)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_correct_report_lists_the_positions_left_uncorrected_with_their_reason(tmp_path):
    points = points_csv(tmp_path / "p.csv", 40, outside=0.1)
    report = tmp_path / "c.html"
    code = main(["correct", str(points), "--grid", str(GRID), "-o", str(tmp_path / "c.csv"),
                 "--allow-partial", "--report-html", str(report)])  # fmt: skip
    assert code == 0
    page = check_report(report, [points, GRID], figures=1)
    assert page.verdict == ["FAIL"]
    text = " ".join(page.text)
    for i in range(4):  # the four holes moved out of the grid, each with the policy's words
        assert f"hole 'H{i}' ({points}:{i + 2})" in text
    assert text.count("not corrected") >= 4 and "outside the grid box by 50.000 mm" in text
    assert "36 corrected" in text


def test_correct_report_of_1e4_holes_stays_under_2_mb(tmp_path):
    points = points_csv(tmp_path / "p.csv", 10_000, outside=0.05)
    report = tmp_path / "c.html"
    assert main(["correct", str(points), "--grid", str(GRID), "-o", str(tmp_path / "c.csv"),
                 "--allow-partial", "--report-html", str(report)]) == 0  # fmt: skip
    check_report(report, [points, GRID], figures=1)
    assert report.stat().st_size <= MAX_REPORT_BYTES


@pytest.mark.parametrize("which", ["input", "folder"])
def test_a_report_path_that_is_an_input_or_a_folder_writes_nothing(tmp_path, capsys, which):
    points = points_csv(tmp_path / "p.csv", 10)
    before = points.read_bytes()
    target = points if which == "input" else tmp_path
    out = tmp_path / "c.csv"
    code = main(["correct", str(points), "--grid", str(GRID), "-o", str(out),
                 "--report-html", str(target), "--force"])  # fmt: skip
    assert code == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and str(target) in err
    assert not out.exists() and points.read_bytes() == before


@pytest.mark.parametrize("dialect", ["krl", "gcode"])
def test_program_report_beside_the_same_program_bytes(tmp_path, dialect):
    points, cell = EXAMPLES / "wing_panel_points.csv", EXAMPLES / "cell.yaml"
    plain, reported = tmp_path / "plain", tmp_path / "reported"
    out = {"krl": "", "gcode": "w.ngc"}[dialect]
    base = [dialect, str(points), "--cell", str(cell), "--grid", str(GRID)]
    assert main([*base, "-o", str(plain / out)]) == 0
    report = tmp_path / "r.html"
    assert main([*base, "-o", str(reported / out), "--report-html", str(report)]) == 0
    for path in sorted(plain.rglob("*")):
        assert (reported / path.relative_to(plain)).read_bytes() == path.read_bytes()
    page = check_report(report, [points, cell, GRID], figures=1)
    assert page.verdict == ["PASS"]
    assert "72 positions: 72 corrected" in " ".join(page.text)


def test_no_correction_has_no_report(tmp_path, capsys):
    base = ["gcode", str(EXAMPLES / "wing_panel_points.csv"), "--cell", str(EXAMPLES / "cell.yaml")]
    out = tmp_path / "w.ngc"
    code = main([*base, "--no-correction", "-o", str(out), "--report-html", str(tmp_path / "r")])
    assert code == 2 and not out.exists()
    assert "--no-correction" in capsys.readouterr().err


def test_rewrite_report_names_each_position_left_as_it_is(tmp_path):
    src, dat = EXAMPLES / "cam_drill.src", EXAMPLES / "cam_drill.dat"
    cell = EXAMPLES / "cell.yaml"
    base = ["rewrite", str(src), str(dat), "--cell", str(cell), "--allow-partial"]
    assert main([*base, "-o", str(tmp_path / "plain")]) == 0
    report = tmp_path / "rw.html"
    assert main([*base, "-o", str(tmp_path / "rw"), "--report-html", str(report)]) == 0
    for name in ("cam_drill.src", "cam_drill.dat"):
        assert (tmp_path / "rw" / name).read_bytes() == (tmp_path / "plain" / name).read_bytes()
    page = check_report(report, [src, dat, cell, GRID], figures=1)
    assert page.verdict == ["FAIL"]  # the home PTP lies outside the grid: written as it was
    text = " ".join(page.text)
    assert "cam_drill.src:20 PTP" in text and "outside the grid box by 250.000 mm" in text
    assert "cam_drill.dat:5 XHOME" in text and "joint-space target" in text
