"""Accuracy study of the grid model on the simulated kr210-paper (seed Table 5 layout).

The demo's measurement (kr210-paper with the seed's Table 1 errors, tool 250 mm along the flange Z,
A 0 B 90 C 0, region X 1200..2200, Y -600..600, Z 1100..2100 mm, step 200 mm, 5 repeats, tracker
noise 0.02 mm, repeatability 0.03 mm) builds the grid; 200 random targets P in the region are
commanded uncorrected and corrected, and "measured" once each with the same noise. The residual
is P - M per axis (mm), e = P - M as in docs/formats.md. Also: the largest jump of IDW across a cell
face of that grid (trilinear has none).

Run: .venv/bin/python bench/accuracy_grid.py [--targets 200] [--seed 7] [--no-noise]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from accugrid.compensation import GridModel  # noqa: E402
from accugrid.kinematics.frames import pose_from_xyzabc  # noqa: E402
from accugrid.kinematics.robot import load_robot  # noqa: E402
from accugrid.kinematics.simulation import commanded_joints, grid_status  # noqa: E402
from bench.timing import table  # noqa: E402

ABC = np.array([0.0, 90.0, 0.0])
LOW, HIGH = np.array([1200.0, -600.0, 1100.0]), np.array([2200.0, 600.0, 2100.0])
STEP = 200.0
TRACKER_MM, REPEAT_MM = 0.02, 0.03
CASES = [("idw", 1), ("idw", 3), ("trilinear", 1), ("trilinear", 3)]


def demo_robot():
    return load_robot("kr210-paper").with_tool(pose_from_xyzabc([0, 0, 250, 0, 0, 0]))


def reach(robot, commands: np.ndarray, status: int) -> tuple[np.ndarray, np.ndarray]:
    """True TCP positions (N, 3) mm and nominal A5 (N,) deg for commands (N, 3) at ABC: the
    controller's IK in one KUKA Status (as a LIN program keeps it), then the true FK."""
    q = commanded_joints(robot, commands, ABC, status)
    return robot.true_robot().fk(q)[:, :3, 3], np.degrees(q[:, 4])


def noisy(positions: np.ndarray, rng: np.random.Generator, noise: bool) -> np.ndarray:
    """Repeatability then tracker noise (the order of kinematics.simulate_measurements)."""
    if not noise:
        return positions
    positions = positions + rng.normal(0.0, REPEAT_MM, positions.shape)
    return positions + rng.normal(0.0, TRACKER_MM, positions.shape)


def grid_model(robot, status: int, noise: bool, repeats: int = 5, seed: int = 1):
    """The simulated tracker measurement of the study region at STEP (5 repeats) as a GridModel."""
    axes = [np.arange(LOW[a], HIGH[a] + STEP / 2, STEP) for a in range(3)]
    vertices = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    commanded = np.repeat(vertices, repeats, axis=0)
    measured = noisy(
        np.repeat(reach(robot, vertices, status)[0], repeats, axis=0),
        np.random.default_rng(seed),
        noise,
    )
    return GridModel.from_measurements((commanded, measured, np.tile(ABC, (len(commanded), 1))))


def stats(residual: np.ndarray) -> list[str]:
    """Max X Y Z, Min X Y Z, Std X Y Z (mm, 3 decimals) of residuals (N, 3)."""
    values = [*residual.max(axis=0), *residual.min(axis=0), *residual.std(axis=0, ddof=1)]
    return [f"{v:.3f}" for v in values]


def face_jumps(model: GridModel, samples: int = 21) -> tuple[float, np.ndarray]:
    """Largest |e(face from above) - e(face from below)| (mm) of IDW over every interior face of
    the grid, on a samples x samples raster per face, and the point where it happens."""
    worst, where = 0.0, np.zeros(3)
    grid_t = np.linspace(0.0, 1.0, samples)
    for axis in range(3):
        others = [a for a in range(3) if a != axis]
        for level in range(1, int(model.counts[axis]) - 1):
            u, v = np.meshgrid(
                model.origin[others[0]] + grid_t * (model.upper - model.origin)[others[0]],
                model.origin[others[1]] + grid_t * (model.upper - model.origin)[others[1]],
            )
            points = np.empty((u.size, 3))
            points[:, others[0]], points[:, others[1]] = u.ravel(), v.ravel()
            points[:, axis] = model.origin[axis] + level * model.step[axis]
            below = points.copy()
            below[:, axis] -= 1e-6 * model.step[axis]  # in the lower cell (the face is the upper's)
            jump = np.linalg.norm(model.predict(points) - model.predict(below), axis=1)
            k = int(np.argmax(jump))
            if jump[k] > worst:
                worst, where = float(jump[k]), points[k]
    return worst, where


def study(robot, status: int, targets: np.ndarray, seed: int, noise: bool) -> GridModel:
    """Print the Table 5-style rows for one controller IK; returns the grid model."""
    model = grid_model(robot, status, noise)
    rng = np.random.default_rng(seed)
    reached, a5 = reach(robot, targets, status)
    clear = np.abs(a5) > 10.0
    residual = targets - noisy(reached, rng, noise)
    rows = [("Before", "-", *stats(residual))]
    clear_rows = [("Before", "-", *stats(np.abs(residual[clear]))[:3])]
    for method, iterations in CASES:
        command = model.correct(targets, iterations=iterations, method=method)
        residual = targets - noisy(reach(robot, command, status)[0], rng, noise)
        rows.append((f"After {method}", str(iterations), *stats(residual)))
        clear_rows.append((f"After {method}", str(iterations), *stats(np.abs(residual[clear]))[:3]))
    print(f"\n-- controller: IK in KUKA Status {status} for grid and targets --")
    print("residual P - M (mm); columns: Max X Y Z | Min X Y Z | Std X Y Z")
    head = ("", "iter", "max X", "Y", "Z", "min X", "Y", "Z", "std X", "Y", "Z")
    print(table(rows, head))
    print(f"largest |P - M| per axis (mm) of the {clear.sum()} targets with |A5| > 10 deg:")
    print(table(clear_rows, ("", "iter", "X", "Y", "Z")))
    return model


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--targets", type=int, default=200, help="random targets (default 200)")
    parser.add_argument("--seed", type=int, default=7, help="seed of the targets and noise")
    parser.add_argument("--no-noise", action="store_true", help="no tracker/repeat noise")
    args = parser.parse_args()
    noise = not args.no_noise
    robot = demo_robot()
    targets = np.random.default_rng(args.seed).uniform(LOW, HIGH, size=(args.targets, 3))
    print(
        f"kr210-paper, tool Z 250 mm, A B C 0 90 0, region {LOW.tolist()}..{HIGH.tolist()} mm, "
        f"step {STEP:g} mm, 5 repeats, noise tracker {TRACKER_MM if noise else 0} / repeat "
        f"{REPEAT_MM if noise else 0} mm; {args.targets} random targets (seed {args.seed})"
    )
    print()
    # The grid holds for the configuration it was measured in: grid and targets share one Status
    # (kinematics.simulation.grid_status: the IK default at the grid's first vertex).
    status = grid_status(robot, LOW[None], ABC)
    model = study(robot, status, targets, args.seed + 1, noise)
    jump, where = face_jumps(model)
    print(
        f"largest IDW jump across a cell face of this grid: {jump:.4f} mm at "
        f"({', '.join(f'{v:.0f}' for v in where)}) mm (trilinear: continuous)"
    )


if __name__ == "__main__":
    main()
