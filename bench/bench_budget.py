"""The error budget of every corrected hole (``compensation.budget``) against held-out holes, on
robots nobody has described (``kinematics.robot_family``).

Per robot: 60 poses of `plan identify` tilted up to 30 deg, 3 repeats, tracker noise 0.02 mm and
repeatability 0.03 mm per axis, written as a tracker file and calibrated by the ``identify`` job
as the command runs it (joint-error terms chosen from the data, 5 folds); the calibrated file is
read back as every command reads it. Then 200 held-out holes at random joints in the same
region, tilted up to 25 deg, never seen by identification: each hole's model term of the budget
(its 95 % bound u95 on the error's length) against

- measured: the tracker's reading of where the arm put the hole, minus the model's prediction
  (repeatability and tracker noise included, what ``validate`` compares);
- landing: where the arm put the hole (repeatability, no tracker noise), minus the prediction.

Columns: the scale k chosen on identify's held-out folds; the share of holes within their bound
(the budget is calibrated when it holds 90-98 %); the actual 95th percentile of |e|, the median
u95 and their ratio (at most 2 asked).

Run: .venv/bin/python bench/bench_budget.py [--seeds N]
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from accugrid.app.jobs.identify import IdentifyOptions, calibrate  # noqa: E402
from accugrid.codegen.correction import read_model  # noqa: E402
from accugrid.compensation.budget import COVERAGE_RANGE, coverage  # noqa: E402
from accugrid.compensation.plans import SEED_REGION, identification_plan  # noqa: E402
from accugrid.infra.bounds import length_bound_95  # noqa: E402
from accugrid.kinematics.frames import pose_from_xyzabc  # noqa: E402
from accugrid.kinematics.robot_family import (  # noqa: E402
    NOISE_REPEAT_MM,
    NOISE_TRACKER_MM,
    random_robot,
)
from bench.bench_structure import tilted_joints  # noqa: E402
from bench.timing import table  # noqa: E402

LO, HI = np.array(SEED_REGION[0]), np.array(SEED_REGION[1])
DRILL = (0.0, 90.0, 0.0)
POSES, REPEATS, HOLES = 60, 3, 200


def tracker_file(path: Path, s) -> None:
    """A session (``FamilyRobot.session``) as the tracker file ``identify`` reads."""
    head = "id,x,y,z,a,b,c,a1,a2,a3,a4,a5,a6,x_meas,y_meas,z_meas"
    rows = np.column_stack([s.commanded, s.abc_deg, s.joints_deg, s.measured])
    lines = [head] + [
        f"P{i // REPEATS}," + ",".join(f"{v:.4f}" for v in r) for i, r in enumerate(rows)
    ]
    path.write_text("\n".join(lines) + "\n")


def one_robot(seed: int, folder: Path) -> tuple[tuple, np.ndarray]:
    family = random_robot(seed)
    nominal = family.nominal
    status = int(nominal.ik(pose_from_xyzabc([*(LO + HI) / 2, *DRILL])).status[0])
    plan = identification_plan(nominal, LO, HI, POSES, 30.0, DRILL, status)[0]
    q = nominal.ik(pose_from_xyzabc(np.column_stack([plan.points, plan.abc_rows()])), status).q
    measurements = folder / f"ident_{seed}.csv"
    tracker_file(measurements, family.session(q, REPEATS, seed))
    output = folder / f"calibrated_{seed}.yaml"
    done = calibrate(measurements, nominal, IdentifyOptions(), str(output))
    output.write_text(done.files[str(output)])
    model = read_model(output)
    holes = tilted_joints(nominal, status, HOLES, 25.0, seed + 1000)
    predicted = model.robot.true_robot().fk(holes)[:, :3, 3]
    rng = np.random.default_rng([33, seed])
    landing = family.true_robot().fk(holes)[:, :3, 3]
    landing = landing + rng.normal(0.0, NOISE_REPEAT_MM, landing.shape)
    measured = landing + rng.normal(0.0, NOISE_TRACKER_MM, landing.shape)
    u95 = length_bound_95(model.budget.covariance(holes))
    cells = [f"family-{seed}", f"{_scale(output):.3f}"]
    shares = []
    for error in (measured - predicted, landing - predicted):
        share, _ = coverage(error, u95)
        p95 = float(np.percentile(np.linalg.norm(error, axis=1), 95))
        median = float(np.median(u95))
        shares.append(share)
        cells += [f"{100 * share:.1f}", f"{p95:.4f}", f"{median:.4f}", f"{median / p95:.2f}"]
    return tuple(cells), np.array(shares)


def _scale(path: Path) -> float:
    from accugrid.infra.yamlfile import load_yaml

    return load_yaml(path).number("identification", "budget", "scale")


def main(seeds: int) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        results = [one_robot(seed, Path(tmp)) for seed in range(seeds)]
    rows = [r for r, _ in results]
    shares = np.array([s for _, s in results])
    print(
        f"{POSES} poses x {REPEATS} repeats, {HOLES} held-out holes tilted up to 25 deg per "
        f"robot; noise: tracker {NOISE_TRACKER_MM} mm, repeatability {NOISE_REPEAT_MM} mm; "
        "coverage in %, lengths in mm"
    )
    print(
        table(
            rows,
            (
                "robot",
                "k",
                "measured: in u95",
                "p95 |e|",
                "median u95",
                "u95/p95",
                "landing: in u95",
                "p95 |e|",
                "median u95",
                "u95/p95",
            ),
        )
    )
    lo, hi = COVERAGE_RANGE
    for name, column in (("measured", 0), ("landing", 1)):
        share = shares[:, column]
        print(
            f"{name}: coverage median {100 * np.median(share):.1f} %, range "
            f"{100 * share.min():.1f}-{100 * share.max():.1f} % "
            f"({int(np.sum((share >= lo) & (share <= hi)))} of {len(share)} robots in "
            f"{100 * lo:.0f}-{100 * hi:.0f} %)"
        )


if __name__ == "__main__":
    main(int(sys.argv[sys.argv.index("--seeds") + 1]) if "--seeds" in sys.argv else 8)
