"""A drill's TCP measured on the calibrated arm (``accugrid identify-tool``), on robots nobody
has described (``kinematics.robot_family``).

Per robot: the arm is calibrated by ``identify`` from 60 poses x 3 repeats of `plan identify`
(the SMR on the declared tool, joint terms told, as ``--harmonics`` pins them), tracker noise
0.02 mm and repeatability 0.03 mm per axis. A drill is taught at (10, -5, 320) mm (``--drill-z``:
another length; the SMR sits at 250 mm), A B C 0; the
real drill sits up to 1 mm and 0.5 deg off that (random per robot). `plan tool` chooses 8
orientations about one point; the tip and a point 60 mm back on the drill axis are measured 3
times each (in the arm's calibrated Status and joint ranges); ``fit_tool`` gives the drill.

Columns: the TCP's distance from the truth (the real drill in the calibrated flange's frame: the
last link's errors moved into the tool, as identification splits them) and its predicted 1
sigma; the axis' angle from the truth; at 200 holes tilted up to 25 deg, the largest error of
the model (calibrated arm + tool - real arm + real drill) with the taught tool, with the
measured tool and with the true drill (arm only), and the measured/arm-only ratio.

Run: .venv/bin/python bench/bench_tool.py [--seeds N] [--drill-z MM]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from accugrid.compensation.plans import SEED_REGION, identification_plan  # noqa: E402
from accugrid.kinematics.candidates import gravity_terms  # noqa: E402
from accugrid.kinematics.frames import pose_from_xyzabc, rotation_angle_deg  # noqa: E402
from accugrid.kinematics.identification import identify, pose_set  # noqa: E402
from accugrid.kinematics.robot_family import (  # noqa: E402
    NOISE_REPEAT_MM,
    NOISE_TRACKER_MM,
    random_robot,
)
from accugrid.kinematics.tool_calibration import (  # noqa: E402
    fit_tool,
    flange_poses_of,
    plan_tool_poses,
)
from accugrid.kinematics.validity import Validity  # noqa: E402
from bench.bench_structure import tilted_joints  # noqa: E402
from bench.timing import table  # noqa: E402

LO, HI = np.array(SEED_REGION[0]), np.array(SEED_REGION[1])
DRILL = (0.0, 90.0, 0.0)
POSES, REPEATS, HOLES = 60, 3, 200
DRILL_Z = float(sys.argv[sys.argv.index("--drill-z") + 1]) if "--drill-z" in sys.argv else 320.0
TAUGHT = (10.0, -5.0, DRILL_Z, 0.0, 0.0, 0.0)
ORIENTATIONS, AXIS_BACK_MM = 8, 60.0
OFFSET_MM, OFFSET_DEG = 1.0, 0.5


def real_drill(seed: int) -> np.ndarray:
    """flange_T_tool (4, 4) of the real drill: the taught one moved by up to OFFSET_MM and turned
    by up to OFFSET_DEG about a random axis."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng([31, seed])
    move = rng.normal(size=3)
    turn = rng.normal(size=3)
    tool = pose_from_xyzabc(TAUGHT)
    tool[:3, 3] += move / np.linalg.norm(move) * rng.uniform(0.0, OFFSET_MM)
    angle = np.radians(rng.uniform(0.0, OFFSET_DEG))
    tool[:3, :3] = (
        Rotation.from_rotvec(turn / np.linalg.norm(turn) * angle).as_matrix() @ tool[:3, :3]
    )
    return tool


def in_model_flange(calibrated, real_arm, drill: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The real drill (4, 4) in the calibrated flange's frame: the mean over poses q of
    model_flange^-1 real_flange drill (exact for the last link's errors; the rest averaged)."""
    model = flange_poses_of(calibrated, q)
    real = real_arm.fk(q)
    rel = np.linalg.inv(model) @ real @ drill
    out = np.eye(4)
    out[:3, 3] = rel[:, :3, 3].mean(axis=0)
    u, _, vt = np.linalg.svd(rel[:, :3, :3].mean(axis=0))
    out[:3, :3] = u @ vt
    return out


def one_robot(seed: int) -> tuple:
    family = random_robot(seed)
    nominal = family.nominal
    status = int(nominal.ik(pose_from_xyzabc([*(LO + HI) / 2, *DRILL])).status[0])
    plan = identification_plan(nominal, LO, HI, POSES, 30.0, DRILL, status)[0]
    poses = pose_from_xyzabc(np.column_stack([plan.points, plan.abc_rows()]))
    q = nominal.ik(poses, status=status).q
    s = family.session(q, REPEATS, seed)
    data = pose_set(nominal, s.commanded, s.measured, s.abc_deg, s.joints_deg)
    harmonics = family.harmonics
    gravity = gravity_terms(nominal)
    calibrated = identify(nominal, data, harmonics=harmonics, gravity=gravity, selected=True).robot
    # the drill on the real arm; its tip and axis point measured at planned orientations
    drill = real_drill(seed)
    taught = pose_from_xyzabc(TAUGHT)
    real_arm = family.robot.with_tool(np.eye(4)).true_robot()
    centre = (LO + HI) / 2
    ranges = Validity.of_poses(data.commanded, data.rotations, data.q).joints_deg
    _, qt = plan_tool_poses(
        calibrated, taught, centre, ORIENTATIONS, status=status, joints_deg=ranges
    )
    qt = np.repeat(qt, REPEATS, axis=0)
    points = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -AXIS_BACK_MM]])  # tip, axis in drill frame
    real = real_arm.fk(qt) @ drill
    rng = np.random.default_rng([32, seed])
    measured = np.vstack([real[:, :3, :3] @ p + real[:, :3, 3] for p in points])
    measured += rng.normal(0.0, np.hypot(NOISE_REPEAT_MM, NOISE_TRACKER_MM), measured.shape)
    is_axis = np.repeat([False, True], len(qt))
    fit = fit_tool(calibrated, np.vstack([qt, qt]), measured, is_axis, taught[:3, :3])
    holes = tilted_joints(nominal, status, HOLES, 25.0, seed + 1000)
    truth = in_model_flange(calibrated, real_arm, drill, holes)
    tcp_error = float(np.linalg.norm(fit.flange_T_tool[:3, 3] - truth[:3, 3]))
    axis_error = float(
        np.degrees(np.arccos(np.clip(fit.flange_T_tool[:3, 2] @ truth[:3, 2], -1, 1)))
    )
    real_holes = (real_arm.fk(holes) @ drill)[:, :3, 3]
    model_flange = flange_poses_of(calibrated, holes)

    def worst(tool: np.ndarray) -> float:
        return float(np.linalg.norm((model_flange @ tool)[:, :3, 3] - real_holes, axis=1).max())

    taught_max, measured_max, arm_max = worst(taught), worst(fit.flange_T_tool), worst(truth)
    spin = float(rotation_angle_deg(fit.flange_T_tool[None, :3, :3], truth[:3, :3])[0])
    return (
        f"family-{seed}",
        f"{np.linalg.norm(drill[:3, 3] - taught[:3, 3]):.3f}",
        f"{tcp_error:.4f}",
        f"{fit.tip.sigma_mm[0]:.4f}",
        f"{axis_error:.4f}",
        f"{spin:.3f}",
        f"{taught_max:.3f}",
        f"{measured_max:.4f}",
        f"{arm_max:.4f}",
        f"{measured_max / arm_max:.2f}",
    )


def main(seeds: int) -> None:
    rows = [one_robot(seed) for seed in range(seeds)]
    print(
        f"drill at {DRILL_Z:g} mm, the SMR at 250 mm; "
        f"{ORIENTATIONS} orientations x {REPEATS} repeats of the tip and of an axis point "
        f"{AXIS_BACK_MM:g} mm back; {HOLES} holes tilted up to 25 deg; mm and deg"
    )
    print(
        table(
            rows,
            (
                "robot",
                "taught off",
                "TCP error",
                "TCP 1 sigma",
                "axis error deg",
                "rotation deg",
                "max taught",
                "max measured",
                "max arm only",
                "ratio",
            ),
        )
    )
    ratios = np.array([float(r[-1]) for r in rows])
    tcp = np.array([float(r[2]) for r in rows])
    print(
        f"TCP error: median {np.median(tcp):.4f} mm, max {tcp.max():.4f} mm; measured/arm-only "
        f"max hole error: median {np.median(ratios):.2f}, max {ratios.max():.2f}"
    )


if __name__ == "__main__":
    count = int(sys.argv[sys.argv.index("--seeds") + 1]) if "--seeds" in sys.argv else 8
    main(count)
