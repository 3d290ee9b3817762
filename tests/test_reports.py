"""The HTML reports of identify and correct: self-contained (every figure inline, no URL), the
inputs with their SHA-256, the verdict; the size for 1e4 holes; bad report paths."""

from __future__ import annotations

import csv
import hashlib

import numpy as np
import pytest
import yaml
from conftest import EXAMPLES
from report_helpers import Page, check_report
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
    carry = summary["structure"]["carry_over"]
    assert "Held out by joint range" in text
    assert f"x {carry['dh_held_out_rms_mm']['x']:.4f}" in text


@pytest.mark.parametrize(("chosen", "warned"), [(0.05, False), (0.5, True)])
def test_identify_report_warns_when_the_terms_do_not_carry_over(chosen, warned):
    """The chosen model held out by joint range against DH + TCP (0.2 mm): worse, it is said."""
    from accugrid.app.reports.identify import _carry_over_lines

    xyz = dict.fromkeys("xyz", chosen)
    (line,) = _carry_over_lines(
        {"held_out_rms_mm": xyz, "dh_held_out_rms_mm": dict.fromkeys("xyz", 0.2)}
    )
    assert f"x {chosen:.4f}" in line and "DH + TCP only x 0.2000" in line
    assert ("do not hold beyond the joint combinations" in line) == warned


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
    assert page.verdict == ["4 of 40 drilling positions not corrected"]
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


def cell_pose_text(pose: dict) -> str:
    """A cell's tool or base record as the report writes it, formatted here."""
    xyz = " ".join(f"{k} {float(pose[k]):.3f}" for k in "xyz")
    abc = " ".join(f"{k} {float(pose[k]):.3f}" for k in "abc")
    return f"{pose['number']}: {xyz} mm, {abc} deg"


@pytest.mark.parametrize("dialect", ["krl", "gcode"])
def test_program_report_beside_the_same_program_bytes(tmp_path, dialect, monkeypatch):
    """The program is the same with a report or without; the report names every output with
    its SHA-256, the robot, tool, base and cell, the date (SOURCE_DATE_EPOCH when set), what
    was checked, and no PASS: generating a program measures nothing."""
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "86400")
    points, cell = EXAMPLES / "wing_panel_points.csv", EXAMPLES / "cell.yaml"
    plain, reported = tmp_path / "plain", tmp_path / "reported"
    out = {"krl": "", "gcode": "w.ngc"}[dialect]
    base = [dialect, str(points), "--cell", str(cell), "--grid", str(GRID)]
    assert main([*base, "-o", str(plain / out)]) == 0
    report = tmp_path / "r.html"
    assert main([*base, "-o", str(reported / out), "--report-html", str(report)]) == 0
    written = sorted(reported.rglob("*"))
    assert written
    for path in written:
        assert (plain / path.relative_to(reported)).read_bytes() == path.read_bytes()
    page = check_report(report, [points, cell, GRID, *written], figures=1)
    assert page.verdict == ["all 72 drilling positions corrected"]
    text = " ".join(page.text)
    assert "PASS" not in report.read_text().split("<body>")[1]
    for path in written:  # each output named beside its own hash
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
        assert f"{path} {digest}" in " ".join(" ".join(page.text).split())
    doc = yaml.safe_load(cell.read_text())
    assert "robot kr210-paper" in " ".join(text.split())
    assert "tool " + cell_pose_text(doc["tool"]) in " ".join(text.split())
    assert "base " + cell_pose_text(doc["base"]) in " ".join(text.split())
    assert f"cell {cell}" in " ".join(text.split())
    assert "date 1970-01-02 00:00:00 UTC" in " ".join(text.split())
    assert "Checked for every drilling position before writing: inside the grid box" in text
    assert "72 positions: 72 corrected" in text


def test_a_report_is_byte_identical_for_the_same_inputs_and_source_date_epoch(
    tmp_path, monkeypatch
):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    base = ["krl", str(EXAMPLES / "wing_panel_points.csv"), "--cell", str(EXAMPLES / "cell.yaml"),
            "--grid", str(GRID), "-o", str(tmp_path / "p"),
            "--report-html", str(tmp_path / "r.html"), "--force"]  # fmt: skip
    assert main(base) == 0
    first = (tmp_path / "r.html").read_bytes()
    assert main(base) == 0
    assert (tmp_path / "r.html").read_bytes() == first
    assert b"2023-11-14 22:13:20 UTC" in first


def test_the_plan_view_lies_in_the_holes_plane_not_robot_xy(tmp_path, monkeypatch):
    """A vertical panel (X constant in the robot frame) is drawn over its two in-plane axes
    (Y and Z), not collapsed onto a line of robot X-Y."""
    from accugrid.app.reports import correction as module

    drawn = []
    real = module.correction_map_png

    def spy(points, correction, *rest):
        drawn.append((np.array(points), np.array(correction)))
        return real(points, correction, *rest)

    monkeypatch.setattr(module, "correction_map_png", spy)
    ys, zs = np.meshgrid(np.linspace(-400, 400, 5), np.linspace(1200, 2000, 4))
    rows = ["id,x,y,z"] + [
        f"H{i},1700.000,{y:.3f},{z:.3f}"
        for i, (y, z) in enumerate(zip(ys.flat, zs.flat, strict=True))
    ]
    points = tmp_path / "vertical.csv"
    points.write_text("\n".join(rows) + "\n")
    report = tmp_path / "v.html"
    assert main(["correct", str(points), "--grid", str(GRID), "-o", str(tmp_path / "c.csv"),
                 "--report-html", str(report)]) == 0  # fmt: skip
    ((uv, correction),) = drawn
    assert np.ptp(uv[:, 0]) == pytest.approx(800.0) and np.ptp(uv[:, 1]) == pytest.approx(800.0)
    # u, v: robot Y and Z (the frame's axes after the normal X, cyclic); n along X
    yz = np.round(np.column_stack([ys.ravel(), zs.ravel()]), 3)  # as written
    centred = yz - yz.mean(axis=0)
    assert uv == pytest.approx(centred, abs=1e-6)
    with open(tmp_path / "c.csv", newline="") as f:
        out = list(csv.DictReader(line for line in f if not line.startswith("#")))
    command = np.array([[float(r[f"{k}_cmd"]) for k in "xyz"] for r in out])
    target = np.array([[float(r[k]) for k in "xyz"] for r in out])
    assert correction == pytest.approx((command - target)[:, [1, 2, 0]], abs=1e-4)
    text = " ".join(check_report(report, [points, GRID], figures=1).text)
    assert "u (+0.000 +1.000 +0.000), v (+0.000 +0.000 +1.000), n (+1.000 +0.000 +0.000)" in text


def test_identify_report_summary_is_tables_of_numbers_not_key_dumps(tmp_path):
    meas = write_csv(tmp_path / "meas.csv", joints(60, 1), noise=0.02)
    out, report = tmp_path / "cal.yaml", tmp_path / "ident.html"
    assert main(["identify", str(meas), "--robot", "kr210", "--tool", *TOOL, "-o", str(out),
                 "--structure", "dh", "--report-html", str(report)]) == 0  # fmt: skip
    check_report(report, [meas], figures=1)
    summary = yaml.safe_load(out.read_text())["identification"]
    body = Page()
    body.feed(report.read_text().split("<body>")[1])
    cells = [c.strip() for c in body.text if c.strip()]
    for dump in ("box_min_mm", "validated_max_mm", "joints_deg", "x: ", "{", "}"):
        assert not any(dump in c for c in cells), dump
    for name, key in (("residual RMS (fit)", "residual_rms_mm"),
                      ("residual max (fit)", "residual_max_mm")):  # fmt: skip
        at = cells.index(name)
        assert cells[at + 1 : at + 4] == [f"{summary[key][k]:.4f}" for k in "xyz"]
    validity = summary["validity"]
    for i, (lo, hi) in enumerate(validity["joints_deg"], 1):
        at = cells.index(f"A{i}")
        assert cells[at + 1 : at + 3] == [f"{lo:.2f}", f"{hi:.2f}"]
    at = cells.index("box min (mm)")
    assert cells[at + 1 : at + 4] == [f"{v:.3f}" for v in validity["box_min_mm"]]


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
    written = [tmp_path / "rw" / "cam_drill.src", tmp_path / "rw" / "cam_drill.dat"]
    page = check_report(report, [src, dat, cell, GRID, *written], figures=1)
    # the home PTP lies outside the grid and a LIN gives Z alone: both written as they were
    assert page.verdict == ["2 of 10 drilling positions not corrected"]
    text = " ".join(page.text)
    assert "cam_drill.src:20 PTP" in text and "outside the grid box by 250.000 mm" in text
    assert "cam_drill.dat:5 XHOME" in text and "joint-space target" in text
