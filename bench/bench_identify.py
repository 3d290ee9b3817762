"""Identification (`kinematics.identification`) on simulated tracker sessions, and what the
calibrated model predicts on held-out targets.

kr210-paper (seed Table 1 errors, tool 20/-10/250 mm whose real TCP is off by 0.3/-0.2/0.1 mm):
60 poses spread over the working range, tracker noise 0.02 mm per axis, the logged joints exact.
Timed: the fit of 27 parameters (+6 with the tracker frame), and with 5-fold cross-validation.
Accuracy: cross-validation's predicted held-out residual against 200 new poses measured the
same way, and the model's own prediction error (calibrated − true FK) at those poses.

kr210-realistic (Table 1 + compliance + reducer harmonics): 60 poses x 3 repeats in the seed's
region at orientations tilted up to 40 deg from A 0 B 90 C 0 (IK in one Status), identified with
--compliance and with --compliance --harmonics (kr210-realistic's reducer orders); the error
left on 200 targets tilted up to 25 deg (model prediction − true FK,
what a model correction leaves to first order) beside the uncorrected error.

Pose choice: 60 poses in the seed's region within 30 deg of A 0 B 90 C 0, chosen D-optimally
(`accugrid plan identify`, from 2000 candidates) against drawn at random, 3 repeats each; the
error left on the same 200 targets tilted up to 25 deg.

Run: .venv/bin/python bench/bench_identify.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from accugrid.kinematics.frames import matrix_to_abc, pose_from_xyzabc  # noqa: E402
from accugrid.kinematics.identification import identify, pose_set  # noqa: E402
from accugrid.kinematics.robot import Robot, load_robot  # noqa: E402
from bench.timing import measure, table  # noqa: E402

TOOL = pose_from_xyzabc([20.0, -10.0, 250.0, 0.0, 0.0, 0.0])
OFFSET = np.array([0.3, -0.2, 0.1])
LOW = np.radians([-60.0, -120.0, 20.0, -150.0, 20.0, -150.0])
HIGH = np.radians([60.0, -40.0, 120.0, 150.0, 110.0, 150.0])
NOISE_MM = 0.02
REGION = np.array([[1000.0, -500.0, 1300.0], [2000.0, 500.0, 2100.0]])
DRILL = np.array([0.0, 90.0, 0.0])


def true_of(robot: Robot) -> Robot:
    tool = TOOL.copy()
    tool[:3, 3] += OFFSET
    return robot.with_tool(tool).true_robot()


def session(nominal: Robot, true: Robot, q: np.ndarray, seed: int, repeats: int = 1):
    q = np.repeat(q, repeats, axis=0)
    commanded = nominal.fk(q)
    measured = true.fk(q)[:, :3, 3]
    measured = measured + np.random.default_rng(seed).normal(0.0, NOISE_MM, measured.shape)
    abc = matrix_to_abc(commanded[:, :3, :3])
    return pose_set(nominal, commanded[:, :3, 3], measured, abc, np.degrees(q)), measured


def per_axis(values: np.ndarray) -> str:
    return " ".join(f"{v:.4f}" for v in values)


def paper() -> None:
    nominal = load_robot("kr210").with_tool(TOOL)
    true = true_of(load_robot("kr210-paper"))
    rng = np.random.default_rng(0)
    q = LOW + rng.random((60, 6)) * (HIGH - LOW)
    data, _ = session(nominal, true, q, 1)
    rows = []
    for label, kwargs in (
        ("27 parameters", {}),
        ("33 parameters (tracker frame)", {"base_frame": True}),
        ("27 parameters + 5-fold CV", {"folds": 5}),
    ):
        seconds, peak = measure(lambda kwargs=kwargs: identify(nominal, data, **kwargs))
        rows.append((label, f"{seconds * 1000:.0f} ms", f"{peak:.1f} MiB"))
    print("kr210-paper, 60 poses, noise 0.02 mm per axis: identification time (best of 3)")
    print(table(rows, ("fit", "time", "peak")))
    result = identify(nominal, data, folds=5)
    q_new = LOW + rng.random((200, 6)) * (HIGH - LOW)
    held, measured = session(nominal, true, q_new, 2)
    predicted = result.robot.true_robot().fk(q_new)[:, :3, 3]
    residual = measured - predicted
    model_error = predicted - true.fk(q_new)[:, :3, 3]
    raw = nominal.fk(q_new)[:, :3, 3] - true.fk(q_new)[:, :3, 3]
    cv = result.cross_validation
    print(
        table(
            [
                (
                    "uncorrected (nominal - true)",
                    per_axis(np.abs(raw).max(0)),
                    per_axis(raw.std(0)),
                ),
                ("fit residual (60 poses)", per_axis(result.max_mm), per_axis(result.rms_mm)),
                ("5-fold CV predicted held-out", per_axis(cv.max_mm), per_axis(cv.rms_mm)),
                (
                    "200 held-out poses: measured - model",
                    per_axis(np.abs(residual).max(0)),
                    per_axis(np.sqrt(np.mean(residual**2, 0))),
                ),
                (
                    "200 held-out poses: model - true (no noise)",
                    per_axis(np.abs(model_error).max(0)),
                    per_axis(np.sqrt(np.mean(model_error**2, 0))),
                ),
            ],
            ("kr210-paper, mm", "max |.| X Y Z", "RMS X Y Z"),
        )
    )


def tilted_poses(nominal: Robot, n: int, tilt_deg: float, seed: int, status: int) -> np.ndarray:
    """Joints (n, 6) of random positions in REGION at orientations within tilt_deg of DRILL."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    out = []
    while sum(len(o) for o in out) < n:
        points = rng.uniform(REGION[0], REGION[1], (4 * n, 3))
        axis = rng.normal(size=(4 * n, 3))
        axis[:, 2] = 0.0  # tilt about a horizontal axis of the tool frame, any direction
        axis /= np.linalg.norm(axis, axis=1, keepdims=True)
        angle = np.radians(tilt_deg) * np.sqrt(rng.random(4 * n))
        drill = Rotation.from_euler("ZYX", DRILL, degrees=True)
        rot = drill * Rotation.from_rotvec(axis * angle[:, None])
        poses = np.tile(np.eye(4), (4 * n, 1, 1))
        poses[:, :3, :3], poses[:, :3, 3] = rot.as_matrix(), points
        sol = nominal.ik(poses, status=status)
        out.append(sol.q[sol.ok])
    return np.concatenate(out)[:n]


def realistic() -> None:
    robot = load_robot("kr210-realistic")
    nominal = robot.with_tool(TOOL)
    true = true_of(robot)
    status = int(nominal.ik(pose_from_xyzabc([1500.0, 0.0, 1700.0, *DRILL])).status[0])
    q = tilted_poses(nominal, 60, 40.0, 3, status)
    data, _ = session(nominal, true, q, 4, repeats=3)
    targets = tilted_poses(nominal, 200, 25.0, 5, status)
    reached = true.fk(targets)[:, :3, 3]
    raw = nominal.fk(targets)[:, :3, 3] - reached
    rows = [("uncorrected", per_axis(np.abs(raw).max(0)), per_axis(raw.std(0)), "", "")]
    harmonics = tuple((h.axis, h.order) for h in robot.joint_errors.harmonics)
    for label, kwargs in (
        ("geometric model", {}),
        ("geometric + compliance", {"compliance": True}),
        ("geometric + compliance + harmonics", {"compliance": True, "harmonics": harmonics}),
    ):
        seconds, _ = measure(lambda kwargs=kwargs: identify(nominal, data, **kwargs))
        result = identify(nominal, data, folds=5, **kwargs)
        left = result.robot.true_robot().fk(targets)[:, :3, 3] - reached
        count = f"{result.rank} of {len(result.x)}"
        time_ms = f"{seconds * 1000:.0f} ms"
        rows.append((label, per_axis(np.abs(left).max(0)), per_axis(left.std(0)), count, time_ms))
        cv = result.cross_validation
        cells = per_axis(cv.max_mm), per_axis(cv.rms_mm)
        rows.append(("  its 5-fold CV (with noise)", *cells, "", ""))
    print(
        f"\nkr210-realistic: 60 poses x 3 repeats tilted up to 40 deg (Status {status}), noise "
        "0.02 mm; error on 200 targets tilted up to 25 deg (model - true)"
    )
    columns = ("kr210-realistic, mm", "max |.| X Y Z", "std X Y Z", "parameters", "fit time")
    print(table(rows, columns))


def pose_choice() -> None:
    from accugrid.compensation.plans import identification_plan

    rows = []
    for name in ("kr210-paper", "kr210-realistic"):
        robot = load_robot(name)
        nominal, true = robot.with_tool(TOOL), true_of(robot)
        status = int(nominal.ik(pose_from_xyzabc([1500.0, 0.0, 1700.0, *DRILL])).status[0])
        targets = tilted_poses(nominal, 200, 25.0, 5, status)
        plan = identification_plan(nominal, *REGION, 60, 30.0, DRILL, status, design="dh")[0]
        planned = pose_from_xyzabc(np.column_stack([plan.points, plan.abc_rows()]))
        for label, q in (
            ("random", tilted_poses(nominal, 60, 30.0, 3, status)),
            ("D-optimal", nominal.ik(planned, status=status).q),
        ):
            result = identify(nominal, session(nominal, true, q, 4, repeats=3)[0])
            left = result.robot.true_robot().fk(targets)[:, :3, 3] - true.fk(targets)[:, :3, 3]
            rows.append(
                (
                    name,
                    label,
                    f"{result.o1:.3f}",
                    per_axis(np.abs(left).max(0)),
                    per_axis(left.std(0)),
                )
            )
    print("\n60 poses x 3 repeats within 30 deg, geometric model; error on 200 targets (25 deg)")
    print(table(rows, ("robot", "poses", "O1", "max |.| X Y Z", "std X Y Z")))


if __name__ == "__main__":
    paper()
    realistic()
    pose_choice()
