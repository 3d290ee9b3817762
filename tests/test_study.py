"""The grid-step study (seed Sec. 4.4, Tables 4-5) on synthetic fields and constructed data."""

import numpy as np
import pytest

from accugrid.compensation.plans import experiment_plan
from accugrid.compensation.study import (
    Summary,
    analyse,
    choose_step,
    crossing,
    fit_curve,
    measured_residuals,
    read_experiment,
    simulate_study,
    simulate_validation,
    summarize,
)
from accugrid.infra.csvtable import parse_table
from accugrid.infra.errors import InputError

CENTRES = {"D": (1700.0, 0.0, 1500.0), "E": (2000.0, -350.0, 1800.0)}
STEPS = np.array([20.0, 80.0, 140.0, 200.0, 260.0, 320.0, 380.0, 440.0, 500.0])


def field_measure(field, noise_mm=0.0):
    """A synthetic robot: commanded P reaches M = P - e(P) (+ noise), rows repeated."""

    def measure(points, repeats, stream):
        reached = np.repeat(points - field(points), repeats, axis=0)
        rng = np.random.default_rng(100 + stream)
        return reached + noise_mm * rng.standard_normal(reached.shape)

    return measure


def run(field, noise_mm=0.0, repeats=3, steps=STEPS):
    names = list(CENTRES)
    cubes, residuals = simulate_study(
        field_measure(field, noise_mm), names, np.array(list(CENTRES.values())), steps, repeats
    )
    return analyse(cubes, residuals)


def test_constant_field_chooses_largest_step():
    result = run(lambda p: np.tile([0.8, -0.5, 1.2], (len(p), 1)), noise_mm=0.02)
    assert result.decision.step == 500.0
    assert np.all(np.isinf(result.decision.thresholds))
    # only the noise is left, far below the tolerance
    assert all(np.all(np.abs(r.max) < 0.1) and np.all(np.abs(r.min) < 0.1) for r in result.table)


def test_linear_field_idw_residual_grows_with_step():
    # small gradient keeps the second-order term e(P + e) - e(P) = G e below 1e-4 mm
    gradient = np.array([[2e-4, 0.5e-4, 0.0], [0.0, -1e-4, 1e-4], [1e-4, 0.0, 3e-4]])

    def field(p):
        return (p - [1700, 0, 1500]) @ gradient.T + 0.04

    result = run(field, repeats=1)
    worst = np.array([np.maximum(r.max, -r.min).max() for r in result.table])
    assert np.all(np.diff(worst) > 0)
    # IDW is not exact for a linear field: its error is linear in the step (to first order)
    np.testing.assert_allclose(worst / STEPS, worst[-1] / STEPS[-1], rtol=0.05)
    assert worst[0] > 1e-3
    # by symmetry IDW is exact at the cube centre P1 of a linear field: only G e(P1) is left
    centres = np.array(list(CENTRES.values()))
    second_order = field(centres) @ gradient.T
    want = np.broadcast_to(second_order[:, None, :], result.residuals[:, :, 0, 0].shape)
    np.testing.assert_allclose(result.residuals[:, :, 0, 0], want, atol=1e-9)


def test_steep_field_limits_the_step():
    # quadratic in x: IDW residual grows like step^2 and crosses 0.3 mm inside the range
    def field(p):
        x = (p[:, 0] - 1700.0) / 100.0
        return np.column_stack([0.2 * x**2, np.zeros(len(p)), np.zeros(len(p))])

    result = run(field, repeats=1)
    th = result.decision.thresholds
    assert 20.0 < th[0] < 500.0 and np.isinf(th[1]) and np.isinf(th[2])
    assert result.decision.step is not None and result.decision.step <= th[0]
    bigger = STEPS[STEPS > result.decision.step]
    assert any(str(int(s)) in " ".join(result.decision.reasons) for s in bigger)


def test_cubic_fit_and_crossing_on_constructed_data():
    steps = np.linspace(20, 500, 9)
    values = 0.1 + 1e-6 * steps**2  # crosses 0.3 at sqrt(2e5) = 447.21 mm
    curve = fit_curve(steps, values)
    np.testing.assert_allclose(curve(steps), values, atol=1e-12)
    assert crossing(curve, 20, 500, 0.3, above=True) == pytest.approx(np.sqrt(2e5), abs=1e-6)
    assert crossing(curve, 20, 500, 0.5, above=True) == np.inf
    assert crossing(curve, 20, 500, 0.05, above=True) == -np.inf
    low = fit_curve(steps, -values)
    assert crossing(low, 20, 500, -0.3, above=False) == pytest.approx(np.sqrt(2e5), abs=1e-6)
    # a curve that dips back inside after crossing: the first crossing counts
    bump = fit_curve(steps, 0.35 - 1e-5 * (steps - 260.0) ** 2 / 5)
    first = crossing(bump, 20, 500, 0.3, above=True)
    assert 20 < first < 260 and bump(first) == pytest.approx(0.3)


def test_choose_step_rejects_wide_spread_and_explains():
    steps = np.array([20.0, 80.0, 140.0, 200.0])
    table = [
        Summary(np.full(3, 0.1), np.full(3, -0.1), np.full(3, 0.05)),
        Summary(np.full(3, 0.1), np.full(3, -0.1), np.full(3, 0.05)),
        Summary(np.full(3, 0.1), np.full(3, -0.1), np.array([0.05, 0.2, 0.05])),
        Summary(np.full(3, 0.1), np.full(3, -0.1), np.array([0.05, 0.2, 0.05])),
    ]
    flat = [fit_curve(steps, np.full(4, 0.1)) for _ in range(3)]
    low = [fit_curve(steps, np.full(4, -0.1)) for _ in range(3)]
    decision = choose_step(steps, table, flat, low, 0.3, 0.5)
    assert decision.step == 80.0
    assert any("step 200 mm rejected: std above 0.150 mm in Y" in r for r in decision.reasons)
    loose = choose_step(steps, table, flat, low, 0.3, 1.0)
    assert loose.step == 200.0


def test_summarize_repeat_rules():
    # two points, two repeat rounds, x axis only matters
    res = np.zeros((2, 2, 3))
    res[:, :, 0] = [[0.1, 0.3], [-0.2, 0.0]]
    seed = summarize(res, "mean-of-extremes")
    assert seed.max[0] == pytest.approx((0.1 + 0.3) / 2)  # round maxima 0.1 and 0.3
    assert seed.min[0] == pytest.approx((-0.2 + 0.0) / 2)
    assert seed.std[0] == pytest.approx(np.std([0.1, 0.3, -0.2, 0.0], ddof=1))
    avg = summarize(res, "mean-of-repeats")
    assert avg.max[0] == pytest.approx(0.2) and avg.min[0] == pytest.approx(-0.1)
    with pytest.raises(InputError, match="repeat rule"):
        summarize(res, "median")


def smooth_field(p):
    q = (p - [1700.0, 0.0, 1500.0]) / 1000.0
    return np.column_stack(
        [0.4 * q[:, 0] + 0.5 * q[:, 1] ** 2, -0.3 * q[:, 1] * q[:, 2], 0.6 * q[:, 2] ** 2 - 0.2]
    )


def filled_plan_text(steps=(20.0, 140.0, 260.0), repeats=2, field=smooth_field):
    plan = experiment_plan(CENTRES, list(steps), repeats, (0, 90, 0))
    measured = plan.points - field(plan.points)
    lines = plan.csv_text().splitlines()
    out = [lines[0]]
    for line, m in zip(lines[1:], measured, strict=True):
        out.append(line[:-2] + ",".join(f"{v:.4f}" for v in m))
    return "\n".join(out) + "\n"


def write(tmp_path, text, name="plan.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_measured_plan_matches_simulation_to_first_order(tmp_path):
    steps = np.array([20.0, 140.0, 260.0])
    cubes = read_experiment(write(tmp_path, filled_plan_text()))
    assert cubes.names == list(CENTRES) and cubes.repeats == 2
    np.testing.assert_allclose(cubes.steps, steps)
    measured = measured_residuals(cubes)
    _, simulated = simulate_study(
        field_measure(smooth_field), list(CENTRES), np.array(list(CENTRES.values())), steps, 2
    )
    np.testing.assert_allclose(measured, simulated, atol=2e-3)
    assert np.abs(simulated).max() > 1e-3  # the comparison is not between zeros


def test_measured_plan_missing_measurement_names_line(tmp_path):
    lines = filled_plan_text().splitlines()
    lines[7] = ",".join(lines[7].split(",")[:-3] + ["", "", ""])
    with pytest.raises(InputError) as err:
        read_experiment(write(tmp_path, "\n".join(lines) + "\n"))
    assert "plan.csv:8:" in str(err.value)


def test_measured_plan_unequal_repeats(tmp_path):
    lines = filled_plan_text().splitlines()
    del lines[5]
    with pytest.raises(InputError, match="unequal repeats"):
        read_experiment(write(tmp_path, "\n".join(lines) + "\n"))


def test_measured_plan_missing_point(tmp_path):
    text = filled_plan_text(repeats=1)
    lines = [ln for ln in text.splitlines() if not ln.startswith("E_S140_R1_C5,")]
    with pytest.raises(InputError, match="centre E step 140 mm has no row for C5"):
        read_experiment(write(tmp_path, "\n".join(lines) + "\n"))


def test_measured_plan_moved_point(tmp_path):
    text = filled_plan_text(repeats=1)
    table = parse_table(text, "x")
    row = table.text("id").index("D_S20_R1_P3")
    lines = text.splitlines()
    parts = lines[row + 1].split(",")
    parts[1] = f"{float(parts[1]) + 5:.4f}"
    lines[row + 1] = ",".join(parts)
    with pytest.raises(InputError, match="P3 of centre D step 20 mm is not where the plan"):
        read_experiment(write(tmp_path, "\n".join(lines) + "\n"))


def test_validation_before_and_after():
    measure = field_measure(smooth_field, noise_mm=0.01)
    v = simulate_validation(measure, (1500, -300, 1300), (1900, 300, 1700), 100.0, 2, 50, seed=3)
    before, after = v.table()
    assert v.points.shape == (50, 3) and v.before.shape == (50, 2, 3)
    assert np.all(v.model.contains(v.points))
    assert np.abs(after.max).max() < 0.05 < np.abs(before.min).max()
    assert np.all(after.std < before.std)


def test_study_needs_two_steps():
    with pytest.raises(InputError, match="two steps"):
        run(lambda p: np.zeros_like(p), steps=np.array([100.0]))


# Seed Table 4 (published, real KR210): step, max X Y Z, min X Y Z, std X Y Z (mm).
SEED_TABLE4 = np.array(
    [
        [20, 0.165, 0.059, 0.167, -0.016, -0.098, -0.06, 0.05, 0.04, 0.073],
        [80, 0.182, 0.211, 0.21, -0.027, -0.266, -0.132, 0.055, 0.108, 0.081],
        [140, 0.228, 0.204, 0.226, -0.074, -0.248, -0.176, 0.064, 0.105, 0.109],
        [200, 0.279, 0.213, 0.265, -0.107, -0.224, -0.228, 0.084, 0.109, 0.121],
        [260, 0.283, 0.195, 0.278, -0.119, -0.245, -0.262, 0.102, 0.108, 0.13],
        [320, 0.393, 0.183, 0.461, -0.181, -0.261, -0.393, 0.127, 0.117, 0.177],
        [380, 0.406, 0.182, 0.464, -0.189, -0.233, -0.372, 0.13, 0.112, 0.198],
        [440, 0.493, 0.205, 0.556, -0.226, -0.235, -0.471, 0.153, 0.123, 0.22],
        [500, 0.45, 0.227, 0.648, -0.271, -0.251, -0.443, 0.16, 0.122, 0.238],
    ]
)


def test_decision_rule_on_the_seed_table_4_gives_the_seed_choice():
    """The seed reads thresholds of 200-250 mm in X and Z, none in Y, and picks 200 mm."""
    steps = SEED_TABLE4[:, 0]
    table = [Summary(r[1:4], r[4:7], r[7:10]) for r in SEED_TABLE4]
    max_curves = [fit_curve(steps, SEED_TABLE4[:, 1 + a]) for a in range(3)]
    min_curves = [fit_curve(steps, SEED_TABLE4[:, 4 + a]) for a in range(3)]
    decision = choose_step(steps, table, max_curves, min_curves, 0.3, 0.5)
    th = decision.thresholds
    assert 200 < th[0] < 250 and np.isinf(th[1]) and 200 < th[2] < 250
    assert decision.step == 200.0


# --- the `accugrid study` command ------------------------------------------------------------

from accugrid.app.cli import main  # noqa: E402

QUICK = ["--centre", "D", "1700", "0", "1500", "--steps", "20:380:120", "--repeats", "2"]
QUICK += ["--validation-points", "30", "--region", "1500", "1900", "-200", "200", "1300", "1700"]


def test_study_cli_simulated(tmp_path, capsys):
    out = tmp_path / "study"
    assert main(["study", "--robot", "kr210-paper", *QUICK, "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Table 4" in text and "Table 5" in text and "chosen" in text
    t4 = parse_table((out / "table4.csv").read_text(), "t4")
    np.testing.assert_allclose(t4.floats(["step_mm"])[:, 0], [20, 140, 260, 380])
    stats = t4.floats(["max_x", "min_x", "std_x"])
    assert np.all(stats[:, 0] >= stats[:, 1]) and np.all(stats[:, 2] >= 0)
    t5 = parse_table((out / "table5.csv").read_text(), "t5")
    assert t5.text("calibration") == ["before", "after"]
    before, after = t5.floats(["std_z"])[:, 0]
    assert after < before
    for name in ("fig12.png", "table5_hist.png"):
        assert (out / name).read_bytes().startswith(b"\x89PNG")
    report = (out / "report.md").read_text()
    assert "](fig12.png)" in report and "](table5_hist.png)" in report
    # same settings, same numbers
    again = tmp_path / "again"
    assert main(["study", "--robot", "kr210-paper", *QUICK, "-o", str(again)]) == 0
    assert (again / "table4.csv").read_bytes() == (out / "table4.csv").read_bytes()


def test_study_cli_cube_outside_reach(tmp_path, capsys):
    argv = ["study", "--robot", "kr210-paper", "--centre", "FAR", "3400", "0", "1500"]
    assert main([*argv, "--steps", "20,80", "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "cube of centre FAR at step 20 mm is outside the reach of kr210-paper" in err
    assert not (tmp_path / "o").exists()


def test_study_cli_measured(tmp_path, capsys):
    plan = write(tmp_path, filled_plan_text(steps=(20.0, 140.0, 260.0, 380.0)))
    assert main(["study", "--measured", str(plan), "-o", str(tmp_path / "m")]) == 0
    text = capsys.readouterr().out
    assert "Table 5: not computed (no --validate files given)" in text
    t4 = parse_table((tmp_path / "m" / "table4.csv").read_text(), "t4")
    assert len(t4) == 4


def test_study_cli_measured_missing_value(tmp_path, capsys):
    lines = filled_plan_text().splitlines()
    lines[3] = lines[3][: lines[3].rindex(",")] + ","
    plan = write(tmp_path, "\n".join(lines) + "\n")
    assert main(["study", "--measured", str(plan), "-o", str(tmp_path / "m")]) == 2
    assert "plan.csv:4:" in capsys.readouterr().err


def test_study_cli_option_errors(tmp_path, capsys):
    plan = write(tmp_path, filled_plan_text())
    argv = ["study", "--measured", str(plan), "-o", str(tmp_path / "m")]
    assert main([*argv, "--validation-step", "200"]) == 2
    assert (
        "--validation-step goes with a simulated study, not --measured" in capsys.readouterr().err
    )
    assert main(["study", "--robot", "kr210-paper", "--steps", "100", "-o", str(tmp_path)]) == 2
    assert "two steps" in capsys.readouterr().err


def test_study_cli_measured_with_validation(tmp_path, capsys):
    from accugrid.compensation.plans import grid_plan
    from accugrid.compensation.study import random_points

    grid = grid_plan((1500, -300, 1300), (1900, 300, 1700), 100.0, (0, 90, 0))
    meas = grid.points - smooth_field(grid.points)
    lines = grid.csv_text().splitlines()
    body = [
        ln[:-2] + ",".join(f"{v:.4f}" for v in m) for ln, m in zip(lines[1:], meas, strict=True)
    ]
    grid_csv = write(tmp_path, "\n".join([lines[0], *body]) + "\n", "grid.csv")
    pts = random_points((1500, -300, 1300), (1900, 300, 1700), 40, seed=5)
    rows = [
        ",".join(f"{v:.4f}" for v in (*p, *(p - e)))
        for p, e in zip(pts, smooth_field(pts), strict=True)
    ]
    points_csv = write(tmp_path, "x,y,z,x_meas,y_meas,z_meas\n" + "\n".join(rows) + "\n", "pts.csv")
    plan = write(tmp_path, filled_plan_text(steps=(20.0, 140.0, 260.0, 380.0)))
    argv = ["study", "--measured", str(plan), "--validate", str(grid_csv), str(points_csv)]
    assert main([*argv, "-o", str(tmp_path / "m")]) == 0
    t5 = parse_table((tmp_path / "m" / "table5.csv").read_text(), "t5")
    (bx, bz), (ax, az) = t5.floats(["std_x", "std_z"])
    assert ax < 0.2 * bx and az < 0.5 * bz
