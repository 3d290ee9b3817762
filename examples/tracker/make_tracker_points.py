"""Write the synthetic example tracker files of this folder from a known frame.

Run from the repository root: .venv/bin/python examples/tracker/make_tracker_points.py
The output is deterministic (fixed seed); the committed CSVs are exactly what it writes.
Geometry: kinematics/tracker_sim.py (KR 210 at mechanical zero, ISO 9409-1-160 flange).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from accugrid.kinematics.frames import pose_from_xyzabc, transform_points
from accugrid.kinematics.tracker_sim import simulate_tracker_points

HERE = Path(__file__).resolve().parent
TRUE_XYZABC = np.array([-2850.0, 1960.0, -1210.0, -37.5, 0.3, -0.2])
"""The known tracker_T_robot (mm, KUKA ABC deg): the tracker 3.5 m from A1, 1.2 m above the
floor, roughly levelled, its X axis turned 37.5° from the robot's."""
NOISE_MM = 0.02
SEED = 9409


def _csv(rows: np.ndarray, note: str, ids: list[str]) -> str:
    lines = [f"# {note}", "# synthetic: examples/tracker/make_tracker_points.py", "id,x,y,z"]
    lines += [f"{i},{p[0]:.4f},{p[1]:.4f},{p[2]:.4f}" for i, p in zip(ids, rows, strict=True)]
    return "\n".join(lines) + "\n"


def measurement_csv(tracker_T_robot: np.ndarray, rng: np.random.Generator) -> str:
    """A 2x2x2 grid measurement: commanded x,y,z in the robot frame, measured x_meas,y_meas,z_meas
    in the tracker frame (an invented smooth TCP error of a few tenths of a mm, plus noise)."""
    axes = [np.array([1400.0, 1600.0]), np.array([-100.0, 100.0]), np.array([800.0, 1000.0])]
    cmd = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    error = np.column_stack(
        [
            0.3 + 2e-4 * (cmd[:, 0] - 1500.0),
            -0.2 + 1e-3 * cmd[:, 1],
            0.4 - 1e-3 * (cmd[:, 2] - 900.0),
        ]
    )
    reached = cmd - error
    meas = transform_points(tracker_T_robot, reached) + rng.normal(0.0, NOISE_MM, cmd.shape)
    lines = [
        "# 2x2x2 grid: commanded x,y,z in the robot frame, measured x_meas,y_meas,z_meas in the",
        "# tracker frame; map them with: accugrid transform --triples meas",
        "# synthetic: examples/tracker/make_tracker_points.py",
        "id,x,y,z,a,b,c,x_meas,y_meas,z_meas",
    ]
    for i, (c, m) in enumerate(zip(cmd, meas, strict=True)):
        lines.append(
            f"G{i + 1},{c[0]:.4f},{c[1]:.4f},{c[2]:.4f},0.0000,90.0000,0.0000,"
            f"{m[0]:.4f},{m[1]:.4f},{m[2]:.4f}"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    pose = pose_from_xyzabc(TRUE_XYZABC)
    pts = simulate_tracker_points(pose, NOISE_MM, seed=SEED, surface_tilt_deg=0.05)
    files = {
        "base_plane.csv": _csv(
            pts.base_plane,
            "SMR (38.1 mm) scanned over the robot's mounting surface, tracker frame, mm",
            [f"B{i + 1}" for i in range(len(pts.base_plane))],
        ),
        "a1_circle.csv": _csv(
            pts.a1_circle,
            "SMR in flange hole 1 while only A1 turns from -60 to +60 deg, tracker frame, mm",
            [f"A{i + 1}" for i in range(len(pts.a1_circle))],
        ),
        "flange_holes.csv": _csv(
            pts.flange_holes,
            "SMR seated on the 6 flange holes at mechanical zero, tracker frame, mm",
            [f"H{i + 1}" for i in range(len(pts.flange_holes))],
        ),
        "meas_tracker.csv": measurement_csv(pose, np.random.default_rng(SEED + 1)),
    }
    for name, text in files.items():
        (HERE / name).write_text(text, encoding="utf-8")
        print(f"wrote {HERE / name}")


if __name__ == "__main__":
    main()
