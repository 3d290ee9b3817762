"""The full seed study in simulation (issue 4, "Speed"): 5 centres x 9 steps x (8 vertices + 9
test points) x 5 repeats on kr210-paper, then Table 5 with 200 validation points, as
`accugrid study --robot kr210-paper` runs it (without plots). Peer: the same experiment with
the default per-point IK configuration of kinematics.simulation.simulate_measurements.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from accugrid.compensation.plans import SEED_ABC, SEED_CENTRES, SEED_REGION, SEED_STEPS  # noqa: E402
from accugrid.compensation.study import (  # noqa: E402  # noqa: E402
    analyse,
    check_reach,
    simulate_study,
    simulate_validation,
    simulated_measure,
)
from accugrid.kinematics.robot import load_robot  # noqa: E402
from accugrid.kinematics.simulation import simulate_measurements  # noqa: E402
from bench.timing import measure, table  # noqa: E402


def main_bench() -> None:
    robot = load_robot("kr210-paper")
    abc = np.array(SEED_ABC)
    names, xyz = list(SEED_CENTRES), np.array(list(SEED_CENTRES.values()))
    steps = np.array(SEED_STEPS)
    args = argparse.Namespace(noise_tracker=0.02, noise_repeat=0.03, seed=0)

    def study(measure):
        def job():
            cubes, residuals = simulate_study(measure, names, xyz, steps, 5)
            result = analyse(cubes, residuals)
            simulate_validation(measure, *SEED_REGION, result.decision.step, 5, 200)

        return job

    status = check_reach(robot, names, xyz, steps, abc, None)
    fixed = simulated_measure(robot, abc, status, args.seed, args.noise_tracker, args.noise_repeat)

    def per_point(points, repeats, stream):
        return simulate_measurements(robot, points, abc, repeats, 0.02, 0.03, stream)[1]

    rows = []
    for label, measure_fn in (("fixed Status (accugrid study)", fixed), ("IK default", per_point)):
        best, peak = measure(study(measure_fn))
        rows.append((label, f"{best:.3f}", f"{peak:.1f}"))
    print(table(rows, ("full seed study (sim)", "best s", "peak MiB")))


if __name__ == "__main__":
    main_bench()
