"""The error budget of every corrected position (``compensation.budget``): each term against what
it claims, the bound's coverage, and the budget through identify, correct, the programs' headers
and validate on a simulated arm."""

from __future__ import annotations

import csv
import re

import numpy as np
import pytest
from conftest import EXAMPLES
from hypothesis import given, settings
from hypothesis import strategies as st

from accugrid.app.cli import main
from accugrid.compensation.budget import FrameBudget, grid_variance
from accugrid.compensation.grid import GridModel
from accugrid.compensation.measurements import build_grid, measurements_from_arrays
from accugrid.infra.bounds import length_bound_95
from accugrid.kinematics.part_frame import frame_jacobian

ORIGIN, STEP = np.array([1000.0, -200.0, 1200.0]), np.array([100.0, 100.0, 100.0])


def _vertices(counts=(4, 3, 3)) -> np.ndarray:
    axes = [ORIGIN[a] + STEP[a] * np.arange(counts[a]) for a in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)


def test_the_grid_curvature_term_is_the_interpolation_miss_of_a_quadratic_error():
    """An error quadratic along grid X: trilinear interpolation misses it by c h² t (1 - t),
    which is what the term claims, point by point (and nothing at the vertices)."""
    c = 2e-5  # mm per mm²
    vertices = _vertices()
    errors = np.zeros_like(vertices)
    errors[..., 0] = c * (vertices[..., 0] - ORIGIN[0]) ** 2
    grid = GridModel(ORIGIN, STEP, errors)
    rng = np.random.default_rng(1)
    points = ORIGIN + rng.uniform(0, 1, (200, 3)) * STEP * (np.array(grid.counts) - 1)
    miss = grid.predict(points, method="trilinear")[:, 0] - c * (points[:, 0] - ORIGIN[0]) ** 2
    sigma = np.sqrt(grid_variance(grid, points)[:, 0])
    np.testing.assert_allclose(sigma, np.abs(miss), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(grid_variance(grid, vertices.reshape(-1, 3)), 0.0, atol=1e-15)


def test_the_grid_noise_term_is_the_vertex_mean_interpolated():
    """Rows of noise sigma, r repeats per vertex: at a vertex the mean's variance sigma² / r, at
    a cell's centre an eighth of it (eight vertices weighted 1/8 each)."""
    vertices = _vertices((2, 2, 2)).reshape(-1, 3)
    repeats, sigma = 4, 0.03
    rng = np.random.default_rng(2)
    commanded = np.repeat(vertices, repeats, axis=0)
    measured = commanded + rng.normal(0, sigma, commanded.shape)
    built = build_grid(measurements_from_arrays(commanded, measured, None))
    assert built.noise_mm == pytest.approx(sigma, rel=0.25)  # 24 rows, 72 numbers
    grid = GridModel(
        built.origin, built.step, built.errors, repeats=built.repeats, noise_mm=built.noise_mm
    )
    at_vertex = grid_variance(grid, vertices[:1])[0]
    np.testing.assert_allclose(at_vertex, built.noise_mm**2 / repeats, rtol=1e-12)
    centre = grid_variance(grid, (vertices.min(axis=0) + vertices.max(axis=0))[None] / 2)[0]
    np.testing.assert_allclose(centre, built.noise_mm**2 / repeats / 8, rtol=1e-12)


@settings(max_examples=20, deadline=None)
@given(
    scales=st.tuples(*[st.floats(0.001, 1.0)] * 3),
    seed=st.integers(0, 2**16),
)
def test_the_95_bound_holds_95_percent_of_gaussian_errors(scales, seed):
    """Any covariance: the Satterthwaite bound holds 95 % of its errors' lengths (within 1.5 %:
    the approximation and 40 000 samples)."""
    rng = np.random.default_rng(seed)
    rotation = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    cov = rotation @ np.diag(np.square(scales)) @ rotation.T
    bound = length_bound_95(cov[None])[0]
    errors = rng.multivariate_normal(np.zeros(3), cov, 40000)
    assert np.mean(np.linalg.norm(errors, axis=1) <= bound) == pytest.approx(0.95, abs=0.015)


def test_the_frame_term_carries_the_part_rotation_to_the_hole():
    """A part frame uncertain only in its rotation about z by s rad: a hole r mm from the
    centroid along x moves along y by r s; the tool's sigma adds on every axis."""
    from accugrid.compensation.budget import Budget

    s, r = 1e-4, 500.0
    cov = np.zeros((6, 6))
    cov[5, 5] = s**2
    frames = FrameBudget(np.array([0.01, 0.02, 0.02]), cov, np.zeros(3))
    numbers = {}
    model = np.zeros((1, 3, 3))  # a model of no uncertainty corrects the hole
    Budget(modelled=True, frames=frames).assess(numbers, 1, np.array([0]), [[r, 0, 0]], None, model)
    tool = np.mean(np.square([0.01, 0.02, 0.02]))
    sigma = [numbers[k][0] for k in ("sigma_x", "sigma_y", "sigma_z")]
    np.testing.assert_allclose(np.square(sigma), [tool, tool + (r * s) ** 2, tool], rtol=1e-12)
    assert not frame_jacobian(np.zeros((1, 3)), np.zeros(3))[0, :, 3:].any()


def _rows(path):
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    return list(csv.DictReader(lines))


def test_max_u95_flags_and_refuses_unless_partial(tmp_path, capsys):
    points, grid = EXAMPLES / "wing_panel_robot.csv", EXAMPLES / "grid_200mm.csv"
    out = tmp_path / "out.csv"
    base = ["correct", str(points), "--grid", str(grid), "-o", str(out)]
    assert main(base) == 0
    u95 = np.array([float(r["u95_mm"]) for r in _rows(out)])
    assert (u95 > 0).all()
    limit = float(np.median(u95))
    out.unlink()
    assert main([*base, "--max-u95", f"{limit}"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "wing_panel_robot.csv:" in err
    assert f"beyond --max-u95 {limit:g} mm" in err and "--allow-partial" in err
    assert not out.exists()
    assert main([*base, "--max-u95", f"{limit}", "--allow-partial"]) == 0
    rows = _rows(out)
    flagged = [r for r in rows if "beyond --max-u95" in r["flag"]]
    assert len(flagged) == int(np.sum(u95 > limit)) > 0
    assert all(r["x_cmd"] != r["x"] for r in flagged)  # written corrected, not left as they are


@pytest.mark.parametrize("value", ["0", "-0.1", "inf", "nan"])
def test_max_u95_must_be_a_positive_length(tmp_path, capsys, value):
    out = tmp_path / "out.csv"
    args = ["correct", str(EXAMPLES / "wing_panel_robot.csv"), "--grid"]
    args += [str(EXAMPLES / "grid_200mm.csv"), "-o", str(out), "--max-u95", value]
    with pytest.raises(SystemExit) as done:
        main(args)
    assert done.value.code == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]  # after argparse's usage
    assert last.startswith("accugrid correct: error: argument --max-u95:") and value in last
    assert not out.exists()


def test_the_policy_refuses_a_bound_that_is_not_a_positive_length():
    """The library's own check (the Python API has no argparse)."""
    from accugrid.compensation.policy import PolicyRequest
    from accugrid.infra.errors import InputError

    for value in (0.0, -1.0, float("inf"), float("nan")):
        with pytest.raises(InputError, match="--max-u95 .*positive length"):
            PolicyRequest(max_u95_mm=value).check()


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    """kr210-paper (DH errors only) calibrated DH + TCP from 40 poses x 2 repeats (tracker
    0.02 mm, repeatability 0.03 mm), as the commands run it; the folder."""
    folder = tmp_path_factory.mktemp("budget")
    tool = ["--tool", "0", "0", "250", "0", "0", "0"]
    assert main(["plan", "identify", "--robot", "kr210", *tool, "--count", "40", "--tilt", "25",
                 "--name", "IDENT", "-o", str(folder / "plan")]) == 0  # fmt: skip
    assert main(["simulate", "--robot", "kr210-paper", "--poses",
                 str(folder / "plan" / "ident.csv"), *tool, "--repeats", "2",
                 "--noise-tracker", "0.02", "--noise-repeat", "0.03", "--seed", "5",
                 "-o", str(folder / "ident.csv")]) == 0  # fmt: skip
    assert main(["identify", str(folder / "ident.csv"), "--robot", "kr210", *tool,
                 "--structure", "dh", "-o", str(folder / "cal.yaml")]) == 0  # fmt: skip
    return folder


def test_identify_scales_the_budget_on_its_folds_and_validate_finds_it_calibrated(
    calibrated, capsys
):
    """A model of the right form: the scale from the held-out folds is near 1, and the 95 %
    bounds of the holes corrected by it hold about 95 % of where the arm lands (tracker noise
    included), as validate reports."""
    import yaml

    doc = yaml.safe_load((calibrated / "cal.yaml").read_text())
    assert doc["identification"]["budget"]["scale"] == pytest.approx(1.0, abs=0.25)
    out = calibrated / "holes_corrected.csv"
    assert main(["correct", str(EXAMPLES / "wing_panel_robot.csv"), "--model",
                 str(calibrated / "cal.yaml"), "-o", str(out)]) == 0  # fmt: skip
    header = [ln for ln in out.read_text().splitlines() if ln.startswith("# largest u95")]
    assert len(header) == 1
    after = calibrated / "after.csv"
    assert main(["simulate", "--robot", "kr210-paper", "--poses", str(out), "--tool", "0", "0",
                 "250", "0", "0", "0", "--repeats", "4", "--noise-tracker", "0.02",
                 "--noise-repeat", "0.03", "--seed", "6", "-o", str(after)]) == 0  # fmt: skip
    capsys.readouterr()
    assert main(["validate", str(after), "--model", str(calibrated / "cal.yaml")]) == 0
    line = next(ln for ln in capsys.readouterr().out.splitlines() if "error budget" in ln)
    share = float(re.search(r"(\d+\.\d) % of 288 rows", line).group(1))
    # 72 targets x 4 repeats: a 95 % share is known to 3 binomial standard errors of 72 targets
    assert 87.0 <= share <= 100.0 and line.endswith("calibrated (87-100 % expected at 72 targets)")


def test_rewrite_refuses_positions_beyond_max_u95_unless_partial(tmp_path, capsys):
    """The header names the largest bound; a bound below it refuses the rewrite at the worst
    position's line, nothing written; --allow-partial writes it and reports the flag."""
    program, cell = EXAMPLES / "cam_drill.ngc", EXAMPLES / "cell.yaml"
    out = tmp_path / "out.ngc"
    base = ["rewrite", str(program), "--cell", str(cell), "-o", str(out), "--header"]
    base.append("--allow-partial")
    assert main(base) == 0
    found = re.search(r"\(largest u95 (\d+\.\d+) mm over (\d+) positions", out.read_text())
    largest = float(found.group(1))
    assert 0 < largest < 0.3 and int(found.group(2)) > 0
    out.unlink()
    capsys.readouterr()
    strict = [a for a in base if a != "--allow-partial"] + ["--max-u95", f"{largest - 0.002}"]
    assert main(strict) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "cam_drill.ngc:" in err and "--max-u95" in err
    assert not out.exists()
    report = tmp_path / "report.csv"
    assert main([*base, "--max-u95", f"{largest - 0.002}", "--report", str(report)]) == 0
    assert "beyond --max-u95" in report.read_text()
    rows = list(csv.DictReader(report.open()))
    bounds = [float(r["u95_mm"]) for r in rows if r["status"] == "corrected"]
    assert len(bounds) == int(found.group(2))
    assert abs(max(bounds) - largest) <= 0.00055  # the header has 3 decimals, the report 4
    assert all(r["u95_mm"] == "" for r in rows if r["status"] != "corrected")


def test_a_program_report_maps_the_bounds_and_counts_those_beyond_the_tolerance(tmp_path):
    points, cell = EXAMPLES / "wing_panel_points.csv", EXAMPLES / "cell.yaml"
    out, report = tmp_path / "w.ngc", tmp_path / "w.html"
    assert main(["gcode", str(points), "--cell", str(cell), "-o", str(out),
                 "--report-html", str(report)]) == 0  # fmt: skip
    largest = re.search(r"\(largest u95 (\d+\.\d+) mm over 72 positions", out.read_text())
    html = report.read_text()
    assert "<h2>Error budget</h2>" in html and html.count("data:image/png;base64,") == 2
    said = re.search(r"72 positions with a bound: largest (\d+\.\d+) mm, median (\d+\.\d+) mm; "
                     r"0 beyond the tolerance of 0.3 mm", html)  # fmt: skip
    assert said and abs(float(said.group(1)) - float(largest.group(1))) <= 0.0005


def test_the_tabulated_chi_square_quantile_is_scipys():
    from scipy.stats import chi2

    from accugrid.infra.bounds import bound_from_moments

    lam = np.array([[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 1.0, 1.0], [4.0, 1.0, 0.3]])
    total, square = lam.sum(axis=1), (lam**2).sum(axis=1)
    h = total**2 / square
    exact = np.sqrt(total * chi2.ppf(0.95, h) / h)
    np.testing.assert_allclose(bound_from_moments(total, square), exact, rtol=3e-4)


def test_the_calibrated_range_widens_with_few_targets_only():
    """Many targets: 90-98 %; 72 targets: three binomial standard errors of a 95 % share
    (sqrt(0.95 * 0.05 / 72) = 2.57 %), so an honest bound is not called too narrow by chance."""
    from accugrid.compensation.budget import coverage_range

    assert coverage_range(100_000) == (0.90, 0.98)
    lo, hi = coverage_range(72)
    assert lo == pytest.approx(0.95 - 3 * 0.025685, abs=1e-5) and hi == 1.0
    widths = [np.subtract(*coverage_range(n)[::-1]) for n in (10, 72, 300, 3000)]
    assert widths == sorted(widths, reverse=True)
