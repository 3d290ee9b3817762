"""The grid-step study job (``accugrid study``, ``study_files``) and its tables as text: Tables 4
and 5 of the seed for the terminal (aligned columns), CSV and the Markdown report, with Fig. 12
and the Table 5 histograms. Errors in mm with 3 decimals."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accugrid.app.reports.plots import fig12_png, hist_png
from accugrid.compensation.plans import SEED_REGION, SEED_REPEATS
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM
from accugrid.compensation.study import (
    AXES,
    DEFAULT_STD_FRACTION,
    REPEAT_RULES,
    Progress,
    StudyResult,
    Summary,
    analyse,
    check_reach,
    measured_residuals,
    measured_validation,
    no_progress,
    read_experiment,
    simulate_study,
    simulate_validation,
    simulated_measure,
)
from accugrid.infra.atomic import JobFiles
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import fixed
from accugrid.kinematics.robot import Robot

__all__ = [
    "OUTPUTS",
    "STAT_HEADER",
    "StudyRequest",
    "csv_text",
    "md_table",
    "study_files",
    "table4",
    "table5",
    "text_table",
]

OUTPUTS = ("table4.csv", "table5.csv", "fig12.png", "table5_hist.png", "report.md")


def text_table(header: list[str], rows: list[list[str]]) -> str:
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(header)]
    line = lambda cells: "  ".join(c.rjust(w) for c, w in zip(cells, widths, strict=True))  # noqa: E731
    return "\n".join([line(header), line(["-" * w for w in widths])] + [line(r) for r in rows])


STAT_HEADER = [f"{k} {a}" for k in ("max", "min", "std") for a in AXES]


def _stat_cells(row: Summary) -> list[str]:
    return [fixed(v, 3) for v in (*row.max, *row.min, *row.std)]


def table4(result: StudyResult) -> tuple[list[str], list[list[str]]]:
    rows = [[f"{s:g}", *_stat_cells(r)] for s, r in zip(result.steps, result.table, strict=True)]
    return ["step mm", *STAT_HEADER], rows


def table5(before: Summary, after: Summary) -> tuple[list[str], list[list[str]]]:
    return ["", *STAT_HEADER], [["before", *_stat_cells(before)], ["after", *_stat_cells(after)]]


def csv_text(header: list[str], rows: list[list[str]]) -> str:
    names = [h.replace(" mm", "_mm").replace(" ", "_").lower() or "calibration" for h in header]
    return "\n".join([",".join(names)] + [",".join(r) for r in rows]) + "\n"


def md_table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])


@dataclass(frozen=True)
class StudyRequest:
    """One grid-step study: simulated on ``robot`` (its tool included) at ``abc`` (KUKA deg) in
    one KUKA ``status`` (None: the IK default at the first centre) with Gaussian noise (sigma
    per axis, mm) and ``seed``, over the cubes at ``centres`` (name -> (3,) mm) and ``steps``
    (mm); or (``robot`` None) from the filled-in experiment plan ``measured``. ``repeats``
    measurements per point, ``tolerance_mm``, ``std_fraction`` and ``repeat_rule`` of the
    decision (seed Sec. 4.4). Table 5: ``validation_points`` random points in ``region``
    (xmin..zmax mm) at the chosen step (``validation_step_mm`` overrides it, simulation only),
    or from the measured ``validate`` (grid CSV, points CSV)."""

    robot: Robot | None = None
    measured: str | None = None
    centres: dict[str, tuple[float, float, float]] | None = None
    steps: np.ndarray | None = None
    repeats: int = SEED_REPEATS
    abc: tuple[float, float, float] = (0.0, 90.0, 0.0)
    status: int | None = None
    noise_tracker_mm: float = 0.02
    noise_repeat_mm: float = 0.03
    seed: int = 0
    region: tuple[float, ...] = tuple(np.ravel(np.transpose(SEED_REGION)).tolist())
    tolerance_mm: float = DEFAULT_TOLERANCE_MM
    std_fraction: float = DEFAULT_STD_FRACTION
    repeat_rule: str = REPEAT_RULES[0]
    validation_points: int = 200
    validation_step_mm: float | None = None
    validate: tuple[str, str] | None = None


def study_files(
    r: StudyRequest,
    output: str | Path,
    progress: Progress = no_progress,
) -> JobFiles:
    """The study's files in folder ``output`` (``OUTPUTS``: Table 4 and 5 CSVs, Fig. 12, the
    Table 5 histograms, the Markdown report) and the lines to print (the tables, the decision,
    the time); ``progress`` wraps the long loops (e.g. ``app.progress.progress``).
    InputError on bad settings, files or an unreachable cube point."""
    output = Path(output)
    if r.validate and not r.measured:
        raise InputError("--validate goes with --measured (simulation validates by itself)")
    box = r.region
    lo, hi = np.array([box[0], box[2], box[4]]), np.array([box[1], box[3], box[5]])
    started = time.perf_counter()
    settings: list[str] = []
    if r.robot is not None:
        robot = r.robot
        abc = np.array(r.abc, dtype=float)
        names, xyz = list(r.centres), np.array(list(r.centres.values()), dtype=float)
        steps = r.steps
        status = check_reach(robot, names, xyz, steps, abc, r.status)
        measure = simulated_measure(
            robot, abc, status, r.seed, r.noise_tracker_mm, r.noise_repeat_mm
        )
        cubes, residuals = simulate_study(measure, names, xyz, steps, r.repeats, progress)
        settings += [
            f"simulated robot {robot.name}, A B C {' '.join(f'{v:g}' for v in abc)} deg, "
            f"KUKA Status {status} throughout",
            f"noise: tracker {r.noise_tracker_mm:g} mm, repeatability {r.noise_repeat_mm:g} mm "
            f"(sigma per axis), seed {r.seed}",
        ]
    else:
        cubes = read_experiment(r.measured)
        residuals = measured_residuals(cubes, progress)
        settings.append(f"measured plan {Path(r.measured).name} (test points uncorrected)")
    result = analyse(cubes, residuals, r.tolerance_mm, r.std_fraction, r.repeat_rule)
    settings += [
        "centres "
        + ", ".join(
            f"{n} ({', '.join(f'{v:g}' for v in c)})"
            for n, c in zip(cubes.names, cubes.centres, strict=True)
        ),
        f"steps {', '.join(f'{s:g}' for s in cubes.steps)} mm, {cubes.repeats} repeats, "
        f"tolerance +-{r.tolerance_mm:g} mm, std fraction {r.std_fraction:g}, "
        f"repeat rule {r.repeat_rule}",
    ]
    validation = None
    step = result.decision.step
    if r.validation_step_mm is not None:
        if r.robot is None:
            raise InputError("--validation-step goes with a simulated study, not --measured")
        if not r.validation_step_mm > 0:
            raise InputError(f"--validation-step must be > 0 mm, got {r.validation_step_mm:g}")
        step = r.validation_step_mm
    if step is not None and r.robot is not None:
        validation = simulate_validation(
            measure, lo, hi, step, r.repeats, r.validation_points, seed=r.seed
        )
    elif step is not None and r.validate:
        validation = measured_validation(*r.validate)
    elapsed = time.perf_counter() - started

    h4, r4 = table4(result)
    lines = ["Table 4: remaining error after compensation per cube step (mm)", text_table(h4, r4)]
    lines += ["", *result.decision.reasons]
    files: dict[Path, str | bytes] = {output / "table4.csv": csv_text(h4, r4)}
    files[output / "fig12.png"] = fig12_png(result)
    report = [
        "# Grid-step study (accugrid study)",
        "",
        *[f"- {s}" for s in settings],
        f"- validation region X {lo[0]:g}..{hi[0]:g}, Y {lo[1]:g}..{hi[1]:g}, "
        f"Z {lo[2]:g}..{hi[2]:g} mm",
        f"- study time {elapsed:.2f} s",
        "",
        "## Table 4: remaining error after compensation (mm)",
        "",
        md_table(h4, r4),
        "",
        "## Decision (seed Sec. 4.4)",
        "",
        *[f"- {reason}" for reason in result.decision.reasons],
        "",
        "![Fig. 12: error-step curves](fig12.png)",
        "",
        "## Table 5: validation at the chosen step (mm)",
        "",
    ]
    if validation is not None:
        before, after = validation.table(r.repeat_rule)
        h5, r5 = table5(before, after)
        steps_used = " x ".join(f"{s:.3f}" for s in validation.model.step)
        chosen = "" if step == result.decision.step else " (--validation-step, not the chosen)"
        lines += [
            "",
            f"Table 5: {len(validation.points)} random points, grid step {steps_used} mm{chosen} "
            f"({int(np.prod(validation.model.counts))} vertices)",
            text_table(h5, r5),
        ]
        files[output / "table5.csv"] = csv_text(h5, r5)
        files[output / "table5_hist.png"] = hist_png(validation, result.tolerance_mm)
        report += [
            f"{len(validation.points)} random points; grid step {steps_used} mm{chosen}, "
            f"{int(np.prod(validation.model.counts))} vertices.",
            "",
            md_table(h5, r5),
            "",
            "![Table 5 histograms](table5_hist.png)",
        ]
    else:
        why = "no step chosen" if step is None else "no --validate files given"
        lines.append(f"\nTable 5: not computed ({why})")
        files[output / "table5.csv"] = "calibration\n"
        report.append(f"Not computed ({why}).")
        files.pop(output / "table5_hist.png", None)
    files[output / "report.md"] = "\n".join(report) + "\n"
    lines.append(f"\nstudy time {elapsed:.2f} s; wrote {', '.join(str(p) for p in files)}")
    return JobFiles(files, [r.measured, *(r.validate or ())], lines)
