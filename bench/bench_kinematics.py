"""Kinematics on 100,000 poses of the kr210-paper robot (tool 250 mm along the flange Z): batched
FK, closed-form IK (all 8 candidates, Status/Turn selection, limits), the error-field simulation
(IK in one Status + true FK + noise), and the error Jacobian of seed Eq. 3-7. The peer is
Pinocchio's FK one pose at a time in a Python loop (10,000 poses, scaled to 100,000).
Targets: FK and IK under 0.5 s each.

Run: .venv/bin/python bench/bench_kinematics.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from accugrid.kinematics.error_model import error_jacobian  # noqa: E402
from accugrid.kinematics.frames import pose_from_xyzabc  # noqa: E402
from accugrid.kinematics.robot import load_robot  # noqa: E402
from accugrid.kinematics.simulation import simulate_measurements  # noqa: E402
from bench.timing import measure, table  # noqa: E402

N = 100_000
N_PEER = 10_000
REPEATS = 3


def main_bench() -> None:
    import pinocchio as pin

    robot = load_robot("kr210-paper").with_tool(pose_from_xyzabc([0, 0, 250, 0, 0, 0]))
    rng = np.random.default_rng(0)
    lo, hi = np.radians(robot.joint_limits_deg).T
    q = lo + rng.random((N, 6)) * (hi - lo)
    poses = robot.fk(q)
    points = rng.uniform([1200, -600, 1100], [2200, 600, 2100], size=(N, 3))

    model, frame = robot.pinocchio_model()
    data = model.createData()
    q_pin = q[:N_PEER] * robot.dh.sign

    def peer() -> None:
        for qk in q_pin:
            pin.framesForwardKinematics(model, data, qk)
            data.oMf[frame].homogeneous  # noqa: B018 - the 4x4 as numpy, as fk returns

    rows = []
    fk_time, fk_mem = measure(lambda: robot.fk(q), REPEATS)
    rows.append(("FK (batched numpy)", f"{N:,}", f"{fk_time:.3f}", f"{fk_mem:.0f}"))
    # FK's numpy floor: the 6 batched (N, 4, 4) products it cannot avoid (5 links + the tool)
    frames = np.tile(np.eye(4), (N, 1, 1))
    link = frames.copy()
    floor_time, _ = measure(lambda: [np.matmul(frames, link, out=frames) for _ in range(6)])
    rows.append(("floor: 6 batched 4x4 products", f"{N:,}", f"{floor_time:.3f}", "-"))
    ik_time, ik_mem = measure(lambda: robot.ik(poses), REPEATS)
    rows.append(("IK (closed form, default Status)", f"{N:,}", f"{ik_time:.3f}", f"{ik_mem:.0f}"))
    ik6_time, ik6_mem = measure(lambda: robot.ik(poses, status=6), REPEATS)
    rows.append(("IK (closed form, Status 6)", f"{N:,}", f"{ik6_time:.3f}", f"{ik6_mem:.0f}"))
    sim_time, sim_mem = measure(
        lambda: simulate_measurements(robot, points, [0, 90, 0], 1, 0.02, 0.03), REPEATS
    )
    rows.append(
        ("simulation (IK + true FK + noise)", f"{N:,}", f"{sim_time:.3f}", f"{sim_mem:.0f}")
    )
    jac_time, jac_mem = measure(lambda: error_jacobian(robot, q), 1)
    rows.append(("error Jacobian 6x24 (Eq. 3-7)", f"{N:,}", f"{jac_time:.3f}", f"{jac_mem:.0f}"))
    peer_time, _ = measure(peer, 1)
    scaled = peer_time * N / N_PEER
    rows.append(("peer: Pinocchio FK, Python loop", f"{N:,} (10k x 10)", f"{scaled:.3f}", "-"))
    print(table(rows, ("kinematics", "poses", "best s", "peak MiB")))
    print(f"FK speed-up over the Pinocchio per-pose loop: {scaled / fk_time:.1f}x")
    print(
        f"FK / floor {fk_time / floor_time:.2f}; IK default Status / FK {ik_time / fk_time:.2f}, "
        f"IK Status 6 / FK {ik6_time / fk_time:.2f}"
    )


if __name__ == "__main__":
    main_bench()
