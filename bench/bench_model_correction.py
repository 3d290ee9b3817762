"""Model-based correction (compensation.model_correction) of 100,000 targets: the command P' that
the calibrated arm, driven by the nominal controller in one KUKA Status, takes to P.

Calibrated models: kr210-realistic itself (its true robot: seed Table 1 DH errors, compliance
under gravity, reducer harmonics; the steepest error field and the most expensive FK), the same
with compliance only (what ``accugrid identify --compliance`` writes), and kr210-paper (DH errors
only) with a 27-vertex residual grid of what it leaves of kr210-realistic. Targets: uniform in
the seed region X 1300-2100, Y -500-500, Z 1200-2000 mm, orientations A 0 B 90 C 0 tilted by up to
25 deg, Status 6. Floor: one pass (nominal IK + calibrated FK of all targets), what any
correction that checks its result must spend at least; on one thread, and in the correction's
blocks on the threads of ``infra.blocks`` (as the correction runs). Landing: the commands
driven through the nominal IK and the calibrated FK, largest distance from the target. Issue 13
target: < 1 s.

Run: .venv/bin/python bench/bench_model_correction.py
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from accugrid.compensation.comparison import tilted_abc  # noqa: E402
from accugrid.compensation.model_correction import (  # noqa: E402
    BLOCK,
    model_correct,
    reached_by_model,
    residual_grid,
)
from accugrid.infra.blocks import run_blocks, threads  # noqa: E402
from accugrid.kinematics.frames import abc_to_matrix  # noqa: E402
from accugrid.kinematics.joint_errors import JointErrors  # noqa: E402
from accugrid.kinematics.robot import load_robot  # noqa: E402
from bench.timing import measure, table  # noqa: E402

N = 100_000
STATUS = 6
REPEATS = 3
TILT_DEG = 25.0


def main_bench() -> None:
    robot = load_robot("kr210-realistic")
    paper = load_robot("kr210-paper")
    errors = robot.joint_errors
    compliant = replace(
        robot, joint_errors=JointErrors.from_compliance(errors.compliance, errors.masses)
    )
    rng = np.random.default_rng(0)
    points = rng.uniform([1300, -500, 1200], [2100, 500, 2000], size=(N, 3))
    abc = tilted_abc(rng, N, (0.0, 90.0, 0.0), TILT_DEG)
    rotations = abc_to_matrix(abc)
    seed_abc = np.array([0.0, 90.0, 0.0])
    axes = [np.linspace(1300, 2100, 3), np.linspace(-500, 500, 3), np.linspace(1200, 2000, 3)]
    vertices = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    reach, _, _ = reached_by_model(robot, vertices, abc_to_matrix(seed_abc)[None], STATUS)
    grid = residual_grid(paper, (vertices, reach, np.tile(seed_abc, (27, 1))), STATUS)

    rows = []
    floor, floor_mem = measure(lambda: reached_by_model(robot, points, rotations, STATUS), REPEATS)
    rows.append(("floor: one pass (nominal IK + calibrated FK)", "-", f"{floor:.3f}", "-", "-"))

    def one_pass_in_blocks():  # the same pass in the correction's blocks on its threads
        def block(start):
            part = slice(start, start + BLOCK)
            reached_by_model(robot, points[part], rotations[part], STATUS)

        run_blocks(block, range(0, N, BLOCK))

    threaded, _ = measure(one_pass_in_blocks, REPEATS)
    rows.append(
        (f"floor: one pass, blocks on {threads()} threads", "-", f"{threaded:.3f}", "-", "-")
    )
    cases = [
        ("model, tol 0.001 mm (default)", robot, None, 1e-3),
        ("model, tol 0.0001 mm", robot, None, 1e-4),
        ("model, tol 1e-7 mm", robot, None, 1e-7),
        ("DH + compliance model, tol 0.001 mm", compliant, None, 1e-3),
        ("model (paper) + 27-vertex residual grid, 0.001", paper, grid, 1e-3),
    ]
    for name, model, residual, tol in cases:
        result = None

        def run(model=model, residual=residual, tol=tol):
            nonlocal result
            result = model_correct(model, points, abc, STATUS, residual, tol_mm=tol)

        best, mem = measure(run, REPEATS)
        ok = result.ok
        landed, _, _ = reached_by_model(model, result.command[ok], rotations[ok], STATUS)
        goal = points[ok]
        if residual is not None:
            goal = goal + residual.predict(goal)
        miss = np.linalg.norm(landed - goal, axis=1).max()
        rows.append((name, f"{result.iterations}", f"{best:.3f}", f"{miss:.1e}", f"{(~ok).sum()}"))
    print(
        table(rows, ("model correction, 1e5 targets", "passes", "best s", "max miss mm", "failed"))
    )


if __name__ == "__main__":
    main_bench()
