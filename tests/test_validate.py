"""`accugrid validate`: a model calibrated by the CLI on a simulated robot, new targets corrected
with it, "measured" after correction on the simulated true robot, then validated; statistics
checked against a computation written here, the HTML report's structure, the refusals."""

from __future__ import annotations

import csv
import math
import shlex
import statistics

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from report_helpers import check_report

from accugrid.app.cli import main
from accugrid.compensation.validation import validate_positions

TOOL = ["0", "0", "250", "0", "0", "0"]


def run(*argv) -> int:
    return main([str(a) for a in argv])


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    """plan identify -> simulate -> identify (kr210-paper, Table 1 errors) -> correct 24 new
    targets by the model -> simulate the measurement after correction (3 repeats)."""
    d = tmp_path_factory.mktemp("validate")
    assert run("plan", "identify", "--robot", "kr210-paper", "--tool", *TOOL, "--count", 40,
               "--name", "IDENT", "-o", d / "plan") == 0  # fmt: skip
    assert run("simulate", "--robot", "kr210-paper", "--poses", d / "plan" / "ident.csv",
               "--tool", *TOOL, "--noise-tracker", 0.01, "--seed", 2,
               "-o", d / "ident.csv") == 0  # fmt: skip
    assert run("identify", d / "ident.csv", "--robot", "kr210", "--tool", *TOOL,
               "-o", d / "cal.yaml") == 0  # fmt: skip
    xs, ys = np.meshgrid(np.linspace(1500, 2000, 6), np.linspace(-300, 300, 4))
    rows = ["id,x,y,z,a,b,c"] + [
        f"H{i},{x:.3f},{y:.3f},1500.000,0,90,0"
        for i, (x, y) in enumerate(zip(xs.flat, ys.flat, strict=True))
    ]
    (d / "targets.csv").write_text("\n".join(rows) + "\n")
    assert run("correct", d / "targets.csv", "--model", d / "cal.yaml",
               "-o", d / "corrected.csv") == 0  # fmt: skip
    assert run("simulate", "--robot", "kr210-paper", "--poses", d / "corrected.csv",
               "--tool", *TOOL, "--repeats", 3, "--noise-repeat", 0.02, "--seed", 5,
               "-o", d / "after.csv") == 0  # fmt: skip
    return d


def read_rows(path):
    """(target, measured) float lists of a measurement CSV, comments skipped."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    target = [[float(r[k]) for k in "xyz"] for r in rows]
    measured = [[float(r[f"{k}_meas"]) for k in "xyz"] for r in rows]
    return target, measured


def independent_stats(target, measured):
    """Per axis (max |d|, mean, stdev), 3D (max, mean), and per pose AP, RP (ISO 9283)."""
    dev = [
        [m - t for m, t in zip(mr, tr, strict=True)]
        for tr, mr in zip(target, measured, strict=True)
    ]
    axes = [
        (max(abs(r[k]) for r in dev), statistics.mean(r[k] for r in dev),
         statistics.stdev(r[k] for r in dev))
        for k in range(3)
    ]  # fmt: skip
    dist = [math.dist(m, t) for t, m in zip(target, measured, strict=True)]
    poses: dict[tuple, list] = {}
    for t, m in zip(target, measured, strict=True):
        poses.setdefault(tuple(t), []).append(m)
    ap, rp = [], []
    for t, ms in poses.items():
        bary = [statistics.mean(m[k] for m in ms) for k in range(3)]
        ap.append(math.dist(bary, t))
        ls = [math.dist(m, bary) for m in ms]
        rp.append(statistics.mean(ls) + 3 * statistics.stdev(ls))
    return axes, (max(dist), statistics.mean(dist)), ap, rp


def test_validate_statistics_match_an_independent_computation(cell, capsys):
    report = cell / "report.html"
    code = run("validate", cell / "after.csv", "--model", cell / "cal.yaml",
               "--report-html", report)  # fmt: skip
    printed = capsys.readouterr().out
    target, measured = read_rows(cell / "after.csv")
    axes, (dist_max, dist_mean), ap, rp = independent_stats(target, measured)
    assert len(target) == 72 and len(ap) == 24
    lines = {line.split()[0]: line.split() for line in printed.splitlines() if line[:2] == "  "}
    for k, axis in enumerate("XYZ"):
        _, lo, hi, max_abs, mean, std = lines[axis]
        assert float(max_abs) == pytest.approx(axes[k][0], abs=6e-4)
        assert float(mean) == pytest.approx(axes[k][1], abs=6e-4)
        assert float(std) == pytest.approx(axes[k][2], abs=6e-4)
    assert float(lines["3D"][2]) == pytest.approx(dist_max, abs=6e-4)
    assert float(lines["3D"][3]) == pytest.approx(dist_mean, abs=6e-4)
    assert f"AP: max {max(ap):.3f} mm" in printed
    assert f"RP: max {max(rp):.3f} mm over 24 poses with 3 repeats" in printed
    # the model corrects the Table 1 errors (millimetres) to within the tolerance
    within = all(
        abs(m - t) <= 0.3
        for tr, mr in zip(target, measured, strict=True)
        for t, m in zip(tr, mr, strict=True)
    )
    assert within and code == 0 and "PASS: 0 of 72 rows" in printed
    result = validate_positions(target, measured, [str(i) for i in range(len(target))])
    assert sorted(result.ap_mm) == pytest.approx(sorted(ap), abs=1e-9)
    assert sorted(result.rp_mm) == pytest.approx(sorted(rp), abs=1e-9)


def test_a_failed_validation_exits_3_and_still_writes_its_report(cell, capsys):
    report = cell / "fail.html"
    code = run("validate", cell / "after.csv", "--model", cell / "cal.yaml",
               "--tolerance", 0.001, "--report-html", report)  # fmt: skip
    assert code == 3
    assert "FAIL:" in capsys.readouterr().out
    assert '<div class="verdict FAIL">FAIL</div>' in report.read_text()


def test_the_report_is_self_contained_and_names_every_input_with_its_sha256(cell):
    report = cell / "structure.html"
    from conftest import EXAMPLES

    grid = EXAMPLES / "grid_200mm.csv"  # the residual grid is read and named with its hash
    assert run("validate", cell / "after.csv", "--model", cell / "cal.yaml", "--grid", grid,
               "--report-html", report) == 0  # fmt: skip
    page = check_report(report, [cell / "after.csv", cell / "cal.yaml", grid], figures=2)
    text = " ".join(page.text)
    assert page.verdict == ["PASS"]
    assert "±0.3 mm per axis" in text
    assert "step (200.000, 200.000, 200.000) mm: 0 of 24 poses outside its box" in text


def shifted(cell, name, offset):
    """after.csv with x_meas moved by ``offset`` mm."""
    lines = (cell / "after.csv").read_text().splitlines()
    out = []
    for line in lines:
        cells = line.split(",")
        if not line.startswith(("#", "id")):
            cells[8] = f"{float(cells[8]) + offset:.4f}"
        out.append(",".join(cells))
    (cell / name).write_text("\n".join(out) + "\n")
    return cell / name


def test_a_file_from_another_base_frame_or_tool_is_refused(cell, capsys):
    moved = shifted(cell, "moved.csv", 25.0)
    report = cell / "moved.html"
    code = run("validate", moved, "--model", cell / "cal.yaml", "--report-html", report)
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith(f"accugrid validate: error: {moved}: mean deviation")
    assert "another base frame or with another tool" in err and len(err.splitlines()) == 1
    assert not report.exists()
    # an offset of a few tenths is a failed validation, not another frame
    assert run("validate", shifted(cell, "drift.csv", 0.5), "--model", cell / "cal.yaml") == 3


def test_bad_report_paths_and_models_are_located_errors(cell, capsys):
    meas = cell / "after.csv"
    before = meas.read_bytes()
    for target in (meas, cell):  # an input, a folder
        code = run("validate", meas, "--model", cell / "cal.yaml", "--report-html", target,
                   "--force")  # fmt: skip
        assert code == 2
        assert str(target) in capsys.readouterr().err
    assert meas.read_bytes() == before
    assert run("validate", meas, "--model", cell / "plan" / "ident.csv") == 2
    assert run("validate", meas, "--model", cell / "targets.csv") == 2  # not a calibrated model
    # a --grid that is no grid measurement
    assert run("validate", meas, "--model", cell / "cal.yaml", "--grid", meas) == 2


@settings(max_examples=50, deadline=None)
@given(
    st.lists(st.floats(-1.0, 1.0), min_size=12, max_size=12),
    st.tuples(*[st.floats(-50.0, 50.0)] * 3),
)
def test_ap_moves_with_a_shift_and_rp_does_not(values, shift):
    """ISO 9283: shifting every attained position by c moves each pose's AP vector by c and
    leaves RP unchanged."""
    target = np.repeat(np.array([[0.0, 0, 0], [100.0, 0, 0]]), 2, axis=0)
    measured = target + np.array(values).reshape(4, 3)
    labels = [str(i) for i in range(4)]
    a = validate_positions(target, measured, labels)
    b = validate_positions(target, measured + np.array(shift), labels)
    assert np.allclose(b.ap_xyz, a.ap_xyz + np.array(shift), atol=1e-9)
    assert np.allclose(b.rp_mm, a.rp_mm, atol=1e-9)
    assert (a.repeats == 2).all()


def test_the_validation_page_runs_as_written(tmp_path, monkeypatch, capsys):
    """docs/validation.md: every `accugrid` line of its sh blocks runs from a folder holding the
    examples, exits 0, and the last writes the report."""
    from conftest import ROOT

    page = (ROOT / "docs" / "validation.md").read_text()
    blocks = page.split("```sh\n")[1:]
    commands = [line for b in blocks for line in b.split("```")[0].splitlines() if line.strip()]
    assert len(commands) == 6 and all(c.startswith("accugrid ") for c in commands)
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    monkeypatch.chdir(tmp_path)
    for command in commands:
        assert main(shlex.split(command)[1:]) == 0, command
    assert "PASS: 0 of 216 rows" in capsys.readouterr().out
    check_report(tmp_path / "out" / "validation" / "validation.html",
                 [tmp_path / "out" / "validation" / "after.csv"], figures=2)  # fmt: skip


def test_text_from_the_files_reaches_the_report_escaped(cell):
    lines = (cell / "after.csv").read_text().splitlines()
    rows = [ln for ln in lines if not ln.startswith(("#", "id"))]
    hostile = ["id,x,y,z,a,b,c,s,x_meas,y_meas,z_meas"] + [
        '<script>alert("x")</script>,' + row.split(",", 1)[1] for row in rows
    ]
    path = cell / "hostile.csv"
    path.write_text("\n".join(hostile) + "\n")
    report = cell / "hostile.html"
    assert run("validate", path, "--model", cell / "cal.yaml", "--report-html", report) == 0
    page = check_report(report, [path, cell / "cal.yaml"], figures=2)
    assert "<script" not in report.read_text()
    assert '<script>alert("x")</script>' in " ".join(page.text)  # shown as text


def in_inch(cell, name, header_units):
    """after.csv with every length in inch (6 decimals); the header names the unit or not."""
    lines = [ln for ln in (cell / "after.csv").read_text().splitlines() if not ln.startswith("#")]
    rows = list(csv.reader(lines))
    lengths = {"x", "y", "z", "x_meas", "y_meas", "z_meas"}
    header = [f"{n} [in]" if header_units and n in lengths else n for n in rows[0]]
    scaled = [i for i, n in enumerate(rows[0]) if n in lengths]
    body = [
        [f"{float(c) / 25.4:.6f}" if i in scaled else c for i, c in enumerate(r)] for r in rows[1:]
    ]
    (cell / name).write_text("\n".join(",".join(r) for r in [header, *body]) + "\n")
    return cell / name


def test_an_inch_file_is_read_in_inch_or_refused_naming_the_unit(cell, capsys):
    """Read as mm, an inch file's deviations are 25.4x too small and would PASS: refused (exit 2,
    one line naming inch); with [in] headers it gives the mm file's statistics."""
    plain = in_inch(cell, "inch.csv", header_units=False)
    assert run("validate", plain, "--model", cell / "cal.yaml") == 2
    err = capsys.readouterr().err
    assert err.startswith(f"accugrid validate: error: {plain}:") and len(err.splitlines()) == 1
    assert "are the file's lengths in in? (read them with --units in)" in err
    assert run("validate", cell / "after.csv", "--model", cell / "cal.yaml") == 0
    mm_lines = capsys.readouterr().out.splitlines()
    named = in_inch(cell, "inch_named.csv", header_units=True)
    for argv in ([named], [plain, "--units", "in"]):
        assert run("validate", *argv, "--model", cell / "cal.yaml") == 0
        lines = capsys.readouterr().out.splitlines()
        table = [ln.split() for ln in lines if ln[:2] == "  "]
        expected = [ln.split() for ln in mm_lines if ln[:2] == "  "]
        assert [row[0] for row in table] == [row[0] for row in expected] and len(table) >= 4
        for got, want in zip(table, expected, strict=True):  # 1e-6 in is 2.5e-5 mm
            numbers = [(float(g), float(w)) for g, w in zip(got, want, strict=True)
                       if g.replace(".", "").lstrip("-").isdigit()]  # fmt: skip
            assert all(abs(g - w) <= 1.01e-3 for g, w in numbers), (got, want)
            assert numbers or got == want
