"""The statistical grid-step study of the seed (Sec. 4.2-4.4, Sec. 5, Tables 4-5, Fig. 12).

For every step and every centre, the cube's grid model is built from its 8 measured vertices, its
9 test points (compensation.cube_points) are corrected (P' = P + e, Eq. 14) and the remaining
error r = P - M (target minus reached, the sign of docs/formats.md) is collected over all centres.

- Table 4: per step and axis, the max, min and standard deviation of r. Repeats follow the seed
  (Sec. 5, "the mean maximum and minimum values of 5 measurements are used as the maximum and
  minimum values of the sample"): max and min are taken within each repeat round and averaged
  over the rounds; the standard deviation is that of all samples (``REPEAT_RULES``).
- Fig. 12: per axis, cubic polynomials (least squares, numpy.polynomial) of max and min against
  the step; the threshold step of an axis is the smallest step at which either curve leaves the
  tolerance band.
- Sec. 4.4 step 4: the chosen step is the largest tested step that is not beyond any threshold,
  whose measured max/min lie in the band, and whose standard deviation is "relatively small",
  made explicit here as std <= ``std_fraction`` * tolerance on every axis (default 0.5: then
  +-tolerance is two standard deviations).
- Table 5: a grid at the chosen step over the whole region, r before and after correction at
  random points.

Measurements come from a ``measure(points (N,3), repeats, stream) -> (N*repeats, 3)`` callable
(a simulated robot; ``stream`` selects an independent noise stream) or from a filled-in
experiment plan (``read_experiment``). With a measured plan the test points were measured without
correction, so r = (P - M) - e_pred(P): the correction's effect to first order (the error field
changes by micrometres over the sub-millimetre correction).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np
from numpy.polynomial import Polynomial

from accugrid.compensation.cube_points import (
    TEST_LABELS,
    VERTEX_LABELS,
    cube_test_points,
    cube_vertices,
)
from accugrid.compensation.grid import GridModel
from accugrid.compensation.plans import grid_axes
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM
from accugrid.infra.csvtable import read_table
from accugrid.infra.errors import InputError
from accugrid.infra.units import mm_text
from accugrid.kinematics.configuration import solve_in_one_status
from accugrid.kinematics.model import RobotModel
from accugrid.kinematics.simulation import commanded_poses, simulate_measurements

__all__ = [
    "AXES",
    "DEFAULT_STD_FRACTION",
    "REPEAT_RULES",
    "Cubes",
    "Decision",
    "Measure",
    "Progress",
    "Progress",
    "StudyResult",
    "Summary",
    "Validation",
    "analyse",
    "check_reach",
    "choose_step",
    "crossing",
    "design",
    "fit_curve",
    "measured_residuals",
    "measured_validation",
    "no_progress",
    "random_points",
    "read_experiment",
    "simulate_study",
    "simulate_validation",
    "simulated_measure",
    "summarize",
]

Measure = Callable[[np.ndarray, int, int], np.ndarray]
Progress = Callable[[Iterable, str, int], Iterable]

#: "mean-of-extremes": the seed's rule (max/min per repeat round, averaged over the rounds);
#: "mean-of-repeats": average the repeats of each point first, then max/min/std over points.
REPEAT_RULES = ("mean-of-extremes", "mean-of-repeats")
DEFAULT_STD_FRACTION = 0.5
AXES = "XYZ"


def no_progress(items: Iterable, desc: str, total: int) -> Iterable:
    """The ``Progress`` that shows nothing: ``items`` as they are."""
    return items


@dataclass
class Cubes:
    """The experiment's data: C centres x S steps cubes, R repeats.

    names (C,); centres (C, 3) mm; steps (S,) mm; vertex_cmd (C, S, 8, 3);
    vertex_meas (C, S, 8, R, 3); test_target (C, S, 9, 3); test_meas (C, S, 9, R, 3) or None
    (None until simulated: a simulated test point is measured after its correction).
    """

    names: list[str]
    centres: np.ndarray
    steps: np.ndarray
    vertex_cmd: np.ndarray
    vertex_meas: np.ndarray
    test_target: np.ndarray
    test_meas: np.ndarray | None = None

    @property
    def repeats(self) -> int:
        return self.vertex_meas.shape[3]

    def models(self, progress: Progress = no_progress) -> list[GridModel]:
        """One GridModel per cube, in (centre, step) order (C*S,)."""
        n_c, n_s, _, n_r, _ = self.vertex_meas.shape
        cmd = np.repeat(self.vertex_cmd.reshape(n_c * n_s, 8, 1, 3), n_r, axis=2)
        meas = self.vertex_meas.reshape(n_c * n_s, 8, n_r, 3)
        return [
            GridModel.from_measurements((cmd[i].reshape(-1, 3), meas[i].reshape(-1, 3)))
            for i in progress(range(n_c * n_s), "cube models", n_c * n_s)
        ]


@dataclass
class Summary:
    """Max, min and standard deviation per axis (3,) mm of residuals."""

    max: np.ndarray
    min: np.ndarray
    std: np.ndarray


@dataclass
class Decision:
    """The chosen step (mm, None when no tested step qualifies) and the reasons, one per line."""

    step: float | None
    thresholds: np.ndarray  # (3,) mm per axis; inf: never crosses, -inf: fails at the first step
    reasons: list[str] = field(default_factory=list)


@dataclass
class StudyResult:
    """Table 4 (steps (S,), table (S,) Summaries), residuals (C, S, 9, R, 3), curves per axis
    (max and min Polynomials of the step), the decision and the settings that made it."""

    names: list[str]
    steps: np.ndarray
    table: list[Summary]
    residuals: np.ndarray
    max_curves: list[Polynomial]
    min_curves: list[Polynomial]
    decision: Decision
    tolerance_mm: float
    std_fraction: float
    repeat_rule: str


def summarize(residuals: np.ndarray, rule: str = "mean-of-extremes") -> Summary:
    """Statistics of residuals (K, R, 3) mm (K points, R repeat rounds) by a REPEAT_RULES rule."""
    res = np.asarray(residuals, dtype=float)
    if res.ndim != 3 or res.shape[2] != 3 or res.shape[0] == 0 or res.shape[1] == 0:
        raise ValueError(f"residuals must be (K, R, 3), got {res.shape}")
    if rule == "mean-of-extremes":
        flat = res.reshape(-1, 3)
        std = flat.std(axis=0, ddof=1) if len(flat) > 1 else np.zeros(3)
        return Summary(res.max(axis=0).mean(axis=0), res.min(axis=0).mean(axis=0), std)
    if rule == "mean-of-repeats":
        mean = res.mean(axis=1)
        std = mean.std(axis=0, ddof=1) if len(mean) > 1 else np.zeros(3)
        return Summary(mean.max(axis=0), mean.min(axis=0), std)
    raise InputError(f"unknown repeat rule '{rule}' (use {' or '.join(REPEAT_RULES)})")


def fit_curve(steps: np.ndarray, values: np.ndarray, degree: int = 3) -> Polynomial:
    """Least-squares polynomial of values (S,) against steps (S,) mm, degree min(degree, S-1)."""
    steps = np.asarray(steps, dtype=float)
    return Polynomial.fit(steps, np.asarray(values, dtype=float), min(degree, len(steps) - 1))


def crossing(curve: Polynomial, lo: float, hi: float, limit: float, above: bool) -> float:
    """Smallest step in lo..hi (mm) where curve goes beyond limit (above it when ``above``,
    below it otherwise): -inf when already beyond at lo, inf when it stays inside up to hi."""
    sign = 1.0 if above else -1.0
    beyond = lambda s: sign * (curve(s) - limit) > 0  # noqa: E731
    if beyond(lo):
        return -np.inf
    roots = (curve - limit).roots()
    roots = np.sort(roots[np.abs(roots.imag) < 1e-9].real)
    span = hi - lo
    for root in roots[(roots >= lo) & (roots <= hi)]:
        if beyond(min(root + 1e-6 * span, hi)):
            return float(root)
    return np.inf


def choose_step(
    steps: np.ndarray,
    table: list[Summary],
    max_curves: list[Polynomial],
    min_curves: list[Polynomial],
    tolerance_mm: float,
    std_fraction: float,
) -> Decision:
    """Seed Sec. 4.4 steps 3-4 (see module docstring), with the reason for every rejection."""
    steps = np.asarray(steps, dtype=float)
    lo, hi = float(steps.min()), float(steps.max())
    thresholds = np.array(
        [
            min(
                crossing(max_curves[a], lo, hi, tolerance_mm, above=True),
                crossing(min_curves[a], lo, hi, -tolerance_mm, above=False),
            )
            for a in range(3)
        ]
    )
    reasons = [
        f"threshold step {AXES[a]}: {_threshold_text(thresholds[a], lo, hi)}" for a in range(3)
    ]
    std_limit = std_fraction * tolerance_mm
    chosen = None
    for i in np.argsort(steps)[::-1]:
        s, row = steps[i], table[i]
        why = []
        over = [AXES[a] for a in range(3) if s > thresholds[a]]
        if over:
            why.append(f"beyond the threshold in {','.join(over)}")
        out = [AXES[a] for a in range(3) if row.max[a] > tolerance_mm or row.min[a] < -tolerance_mm]
        if out:
            why.append(f"measured max/min outside +-{tolerance_mm:g} mm in {','.join(out)}")
        wide = [AXES[a] for a in range(3) if row.std[a] > std_limit]
        if wide:
            why.append(f"std above {std_limit:.3f} mm in {','.join(wide)}")
        if why:
            reasons.append(f"step {s:g} mm rejected: {'; '.join(why)}")
            continue
        chosen = float(s)
        reasons.append(
            f"step {s:g} mm chosen: the largest tested step within the thresholds, with max/min "
            f"inside +-{tolerance_mm:g} mm and std <= {std_fraction:g} x tolerance "
            f"= {std_limit:.3f} mm (std {_fmt3(row.std)} mm)"
        )
        break
    if chosen is None:
        reasons.append(f"no tested step meets +-{tolerance_mm:g} mm: measure a finer grid")
    return Decision(chosen, thresholds, reasons)


def _threshold_text(value: float, lo: float, hi: float) -> str:
    if value == np.inf:
        return f"none up to {hi:g} mm (the curves stay inside the band)"
    if value == -np.inf:
        return f"below {lo:g} mm (outside the band already at the smallest step)"
    return f"{value:.1f} mm"


def _fmt3(v: np.ndarray) -> str:
    return "/".join(f"{x:.3f}" for x in v)


def analyse(
    cubes: Cubes,
    residuals: np.ndarray,
    tolerance_mm: float = DEFAULT_TOLERANCE_MM,
    std_fraction: float = DEFAULT_STD_FRACTION,
    repeat_rule: str = "mean-of-extremes",
) -> StudyResult:
    """Table 4, the curves and the decision from residuals (C, S, 9, R, 3) mm."""
    if not tolerance_mm > 0 or not std_fraction > 0:
        raise InputError("tolerance and std fraction must be > 0")
    steps = cubes.steps
    n_c, n_s, n_t, n_r, _ = residuals.shape
    per_step = np.moveaxis(residuals, 1, 0).reshape(n_s, n_c * n_t, n_r, 3)
    table = [summarize(per_step[i], repeat_rule) for i in range(n_s)]
    maxima = np.array([row.max for row in table])
    minima = np.array([row.min for row in table])
    max_curves = [fit_curve(steps, maxima[:, a]) for a in range(3)]
    min_curves = [fit_curve(steps, minima[:, a]) for a in range(3)]
    decision = choose_step(steps, table, max_curves, min_curves, tolerance_mm, std_fraction)
    return StudyResult(
        list(cubes.names),
        steps,
        table,
        residuals,
        max_curves,
        min_curves,
        decision,
        tolerance_mm,
        std_fraction,
        repeat_rule,
    )


def design(names: list[str], centres: np.ndarray, steps: np.ndarray) -> Cubes:
    """Cubes of the experiment (no measurements yet: vertex_meas has R = 0)."""
    centres = np.asarray(centres, dtype=float).reshape(-1, 3)
    steps = np.asarray(steps, dtype=float).reshape(-1)
    if len(steps) < 2:
        raise InputError("the study needs at least two steps to fit an error-step curve")
    if len(np.unique(steps)) != len(steps):
        raise InputError("study steps must be distinct")
    n_c, n_s = len(centres), len(steps)
    cen = np.repeat(centres, n_s, axis=0)
    stp = np.tile(steps, n_c)
    vertices = cube_vertices(cen, stp).reshape(n_c, n_s, 8, 3)
    tests = cube_test_points(cen, stp).reshape(n_c, n_s, 9, 3)
    empty = np.zeros((n_c, n_s, 8, 0, 3))
    return Cubes(list(names), centres, steps, vertices, empty, tests)


def simulate_study(
    measure: Measure,
    names: list[str],
    centres: np.ndarray,
    steps: np.ndarray,
    repeats: int,
    progress: Progress = no_progress,
) -> tuple[Cubes, np.ndarray]:
    """Run the experiment on a simulated robot: measure the vertices, build the cube models,
    command the corrected test points and measure them. Returns the cubes and the residuals
    (C, S, 9, R, 3) mm = target - measured."""
    if int(repeats) != repeats or repeats < 1:
        raise InputError(f"repeats must be a whole number >= 1, got {repeats}")
    cubes = design(names, centres, steps)
    n_c, n_s = len(cubes.centres), len(cubes.steps)
    measured = measure(cubes.vertex_cmd.reshape(-1, 3), int(repeats), 0)
    cubes.vertex_meas = measured.reshape(n_c, n_s, 8, int(repeats), 3)
    models = cubes.models(progress)
    targets = cubes.test_target.reshape(n_c * n_s, 9, 3)
    commands = np.stack([m.correct(t) for m, t in zip(models, targets, strict=True)])
    reached = measure(commands.reshape(-1, 3), int(repeats), 1)
    cubes.test_meas = reached.reshape(n_c, n_s, 9, int(repeats), 3)
    residuals = cubes.test_target[:, :, :, None, :] - cubes.test_meas
    return cubes, residuals


def measured_residuals(cubes: Cubes, progress: Progress = no_progress) -> np.ndarray:
    """Residuals (C, S, 9, R, 3) mm of a measured experiment whose test points were measured
    without correction: (P - M) - e_pred(P), the first-order effect of commanding P + e_pred."""
    n_c, n_s = len(cubes.centres), len(cubes.steps)
    models = cubes.models(progress)
    targets = cubes.test_target.reshape(n_c * n_s, 9, 3)
    predicted = np.stack([m.predict(t) for m, t in zip(models, targets, strict=True)])
    predicted = predicted.reshape(n_c, n_s, 9, 1, 3)
    return cubes.test_target[:, :, :, None, :] - cubes.test_meas - predicted


def read_experiment(path: str | os.PathLike[str]) -> Cubes:
    """A filled-in experiment plan (``accugrid plan experiment``): columns x,y,z, centre, step,
    label (C1..C8, P1..P9), x_meas,y_meas,z_meas. Every cube of every centre and step must hold
    every label with the same number of repeats; InputError (file, line, column) otherwise."""
    table = read_table(path)
    table.require(["x", "y", "z", "centre", "step", "label", "x_meas", "y_meas", "z_meas"])
    if len(table) == 0:
        raise InputError("no measurements", table.path, 1)
    cmd = table.floats(["x", "y", "z"])
    meas = table.floats(["x_meas", "y_meas", "z_meas"])
    step_col = table.floats(["step"])[:, 0]
    centre_col = [c.strip() for c in table.text("centre")]
    label_col = [lab.strip().upper() for lab in table.text("label")]
    labels = list(VERTEX_LABELS + TEST_LABELS)
    for r, lab in enumerate(label_col):
        if lab not in labels:
            raise InputError(
                f"unknown label '{lab}' (use C1..C8, P1..P9)", *table.where(r, "label")
            )
    names = list(dict.fromkeys(centre_col))
    steps = np.unique(step_col)
    groups: dict[tuple[str, float, str], list[int]] = {}
    for r, key in enumerate(zip(centre_col, step_col, label_col, strict=True)):
        groups.setdefault(key, []).append(r)
    counts = {k: len(v) for k, v in groups.items()}
    n_r = max(counts.values())
    for name in names:
        for s in steps:
            for lab in labels:
                rows = groups.get((name, s, lab))
                if rows is None:
                    raise InputError(
                        f"centre {name} step {s:g} mm has no row for {lab} "
                        "(every centre needs every step, vertex and test point)",
                        table.path,
                    )
                if len(rows) != n_r:
                    raise InputError(
                        f"unequal repeats: centre {name} step {s:g} mm {lab} has {len(rows)} "
                        f"rows, other points have {n_r}",
                        *table.where(rows[0], "label"),
                    )
    idx = np.array(
        [[[groups[(n, s, lab)] for lab in labels] for s in steps] for n in names]
    )  # (C, S, 17, R)
    commanded = cmd[idx]
    spread = np.abs(commanded - commanded[..., :1, :]).max(axis=(-1, -2))
    bad = np.argwhere(spread > 1e-3)
    if bad.size:
        c, s, k = bad[0]
        raise InputError(
            f"repeats of centre {names[c]} step {steps[s]:g} mm {labels[k]} are commanded at "
            "different positions",
            *table.where(int(idx[c, s, k, 1 if n_r > 1 else 0]), "x"),
        )
    commanded = commanded[..., 0, :]  # (C, S, 17, 3)
    measured = meas[idx]  # (C, S, 17, R, 3)
    centres = commanded[:, 0, 8, :]  # P1 of the first step
    expected = design(names, centres, steps)
    diff = np.abs(np.concatenate([expected.vertex_cmd, expected.test_target], axis=2) - commanded)
    bad = np.argwhere(diff.max(axis=-1) > 1e-3)
    if bad.size:
        c, s, k = bad[0]
        raise InputError(
            f"{labels[k]} of centre {names[c]} step {steps[s]:g} mm is not where the plan puts "
            f"it for the cube around P1 {mm_text(centres[c])}",
            *table.where(int(idx[c, s, k, 0]), "x"),
        )
    expected.vertex_meas = measured[:, :, :8]
    expected.test_meas = measured[:, :, 8:]
    return expected


@dataclass
class Validation:
    """Table 5: residuals before and after correction (N, R, 3) mm at random points (N, 3) mm
    of the region, with the grid model at the chosen step."""

    step_mm: float
    points: np.ndarray
    before: np.ndarray
    after: np.ndarray
    model: GridModel

    def table(self, rule: str = "mean-of-extremes") -> tuple[Summary, Summary]:
        return summarize(self.before, rule), summarize(self.after, rule)


def random_points(lo, hi, n: int, seed: int = 0) -> np.ndarray:
    """n uniform random points (n, 3) mm in the box lo..hi, reproducible by seed."""
    if int(n) != n or n < 1:
        raise InputError(f"number of validation points must be >= 1, got {n}")
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    return lo + rng.random((int(n), 3)) * (hi - lo)


def simulate_validation(
    measure: Measure, lo, hi, step_mm: float, repeats: int, n_points: int, seed: int = 0
) -> Validation:
    """Seed Table 5 in simulation: measure the grid at step_mm over lo..hi (an axis whose side is
    not a whole number of steps gets the next smaller step that is, see grid_axes), then measure
    random points commanded without and with the correction."""
    axes = grid_axes(lo, hi, step_mm)
    vertices = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    measured = measure(vertices, repeats, 2)
    model = GridModel.from_measurements((np.repeat(vertices, repeats, axis=0), measured))
    points = random_points(lo, hi, n_points, seed)
    before = points[:, None, :] - measure(points, repeats, 3).reshape(-1, repeats, 3)
    command = model.correct(points)
    after = points[:, None, :] - measure(command, repeats, 4).reshape(-1, repeats, 3)
    return Validation(step_mm, points, before, after, model)


def simulated_measure(
    robot: RobotModel,
    abc: np.ndarray,
    status: int | None,
    seed: int,
    noise_tracker_mm: float,
    noise_repeat_mm: float,
) -> Measure:
    """measure(points, repeats, stream): the measured rows of
    ``kinematics.simulation.simulate_measurements`` seeded ``seed * 1000 + stream``, every point
    in the one KUKA ``status`` (the IK default would flip the wrist inside a cube near A5 = 0 and
    make the simulated error field jump there)."""
    noise = (noise_tracker_mm, noise_repeat_mm)

    def measure(points: np.ndarray, repeats: int, stream: int) -> np.ndarray:
        stream_seed = seed * 1000 + stream
        return simulate_measurements(robot, points, abc, repeats, *noise, stream_seed, status)[1]

    return measure


def check_reach(robot: RobotModel, names, centres, steps, abc, status) -> int:
    """The KUKA Status of the whole study (``status``, or the IK default at the first centre)
    after checking that every cube point is reachable in it; InputError naming the first cube
    point that is not."""
    cubes = design(names, centres, steps)
    points = np.concatenate([cubes.vertex_cmd, cubes.test_target], axis=2)  # (C, S, 17, 3)
    first = commanded_poses(np.asarray(centres[:1], dtype=float), abc)[0]
    sol, status = solve_in_one_status(
        robot, commanded_poses(points.reshape(-1, 3), abc), status, first
    )
    if sol.ok.all():
        return int(status)
    i = int(np.flatnonzero(~sol.ok)[0])
    c, s, k = np.unravel_index(i, points.shape[:3])
    label = f"C{k + 1}" if k < 8 else f"P{k - 7}"
    x, y, z = points[c, s, k]
    raise InputError(
        f"cube of centre {names[c]} at step {steps[s]:g} mm is outside the reach of "
        f"{robot.name}: {label} X {x:.3f} Y {y:.3f} Z {z:.3f} ({sol.reason[i]}"
        f"{'' if status is None else f', Status {status}'}); move the centre or drop the step"
    )


def measured_validation(grid_path: str, points_path: str) -> Validation:
    """Table 5 from measurements: errors before (P - M) and after (P - M - e_pred(P))."""
    model = GridModel.from_measurements(grid_path)
    table = read_table(points_path)
    table.require(["x", "y", "z", "x_meas", "y_meas", "z_meas"])
    if not len(table):
        raise InputError("no validation points", table.path, 1)
    points = table.floats(["x", "y", "z"])
    measured = table.floats(["x_meas", "y_meas", "z_meas"])
    outside = np.flatnonzero(~model.contains(points))
    if outside.size:
        raise InputError(
            f"{outside.size} validation points lie outside the grid", *table.where(int(outside[0]))
        )
    before = (points - measured)[:, None, :]
    after = before - model.predict(points)[:, None, :]
    return Validation(float(model.step.max()), points, before, after, model)
