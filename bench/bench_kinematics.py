"""Kinematics on 100,000 poses of the kr210-paper robot (tool 250 mm along the flange Z): batched
FK, closed-form IK (all 8 candidates, Status/Turn selection, limits), the error-field simulation
(IK in one Status + true FK + noise), and the error Jacobian of seed Eq. 3-7. The peer is
Pinocchio's FK one pose at a time in a Python loop (10,000 poses, scaled to 100,000). The IK in
blocks of 16,384 poses (as ``build_program`` runs it) on one thread and on the block threads of
``infra.blocks`` (the CPUs this process may use, at most 4): their ratio is the threads'
gain on this machine at this moment (a busy machine shares its cores).
Targets: FK and IK under 0.5 s each.

Run: .venv/bin/python bench/bench_kinematics.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from accugrid.infra.blocks import run_blocks, threads  # noqa: E402
from accugrid.kinematics.error_model import error_jacobian  # noqa: E402
from accugrid.kinematics.frames import pose_from_xyzabc  # noqa: E402
from accugrid.kinematics.robot import load_robot  # noqa: E402
from accugrid.kinematics.simulation import simulate_measurements  # noqa: E402
from bench.timing import measure, table  # noqa: E402

N = 100_000
N_PEER = 10_000
BLOCK = 16_384  # poses per IK call, as build_program's IK_BLOCK
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
    q6 = np.empty((N, 6))

    def ik_blocks(workers: int) -> None:
        def block(i: int) -> None:
            q6[i : i + BLOCK] = robot.ik(poses[i : i + BLOCK], status=6).q

        run_blocks(block, range(0, N, BLOCK), workers)

    one_time, one_mem = measure(lambda: ik_blocks(1), REPEATS)
    rows.append(("IK Status 6, blocks, 1 thread", f"{N:,}", f"{one_time:.3f}", f"{one_mem:.0f}"))
    n_threads = threads()
    many_time, many_mem = measure(lambda: ik_blocks(n_threads), REPEATS)
    label = f"IK Status 6, blocks, {n_threads} threads"
    rows.append((label, f"{N:,}", f"{many_time:.3f}", f"{many_mem:.0f}"))
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
    print(f"IK blocks: {n_threads} threads / 1 thread {many_time / one_time:.2f}")


if __name__ == "__main__":
    main_bench()
