"""Issue 13's numbers: grid-only vs model-only vs model + residual grid on kr210-realistic.

The "real" arm is kr210-realistic's true robot (seed Table 1 DH errors, compliance under gravity,
reducer harmonics) carrying a 250 mm drill whose true TCP is off by (0.4, -0.3, 0.6) mm from the
nominal one the controller uses. Every measurement: nominal IK in KUKA Status 6, the real arm's
FK, repeatability 0.03 mm and tracker noise 0.02 mm (sigma per axis), as ``accugrid simulate``.

- grid only: the seed's 200 mm grid (X 1200-2200, Y -600-600, Z 1100-2100 mm, A 0 B 90 C 0,
  252 vertices x 5 repeats), IDW (seed Eq. 12-14) and trilinear, P' = P + e(P).
- model only: 60 poses chosen D-optimally (``identification.select_poses``) from 1500 candidates
  in the region at orientations tilted up to 25 deg, 3 repeats each; ``identify`` with A2/A3
  compliance; ``model_correct`` of each target at its own orientation.
- model + residual grid: the model above plus a 27-vertex (3 x 3 x 3) grid over the region at
  A 0 B 90 C 0, 3 repeats, of what the model leaves (``residual_grid``), trilinear.
- model + harmonics: as "model only" (its own 60 D-optimal poses x 3) with the reducer harmonics
  identified too, at the orders kr210-realistic's reducers have (``identify --harmonics``: the
  orders are known from the reducers' data sheets; amplitudes and phases are fitted), alone and
  with the same 27-vertex residual grid.
- model, structure from the data: plain ``identify`` (``kinematics.structure``: the joint-error
  terms chosen by cross-validation; nominal kr210, no masses, no orders), from its own 60 poses
  D-optimal for DH + TCP, x 3 (orders beyond the library offered by the periodogram screen);
  and the same with the library up to every order the poses resolve (``--max-order`` at the
  highest axis's limit, 124 here).

Held out: 200 random targets inside the region (50 mm margin) at A 0 B 90 C 0, and 200 at
orientations tilted 0-25 deg. The table shows where the real arm lands when commanded P'
(noise-free, the correction's own error): max |P - M| and std per axis, mm. Not timed tests:
run ``.venv/bin/python bench/calibration_accuracy.py``.
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from accugrid.compensation.comparison import tilted_abc  # noqa: E402
from accugrid.compensation.grid import GridModel  # noqa: E402
from accugrid.compensation.model_correction import model_correct, residual_grid  # noqa: E402
from accugrid.compensation.settings import CorrectionSettings  # noqa: E402
from accugrid.kinematics.frames import abc_to_matrix, pose_from_xyzabc  # noqa: E402
from accugrid.kinematics.identification import identify, pose_set, select_poses  # noqa: E402
from accugrid.kinematics.joint_errors import JointErrors  # noqa: E402
from accugrid.kinematics.robot import load_robot  # noqa: E402
from accugrid.kinematics.structure import identify_structure, max_order_of  # noqa: E402

STATUS = 6
SEED_ABC = np.array([0.0, 90.0, 0.0])
LO, HI = np.array([1200.0, -600.0, 1100.0]), np.array([2200.0, 600.0, 2100.0])
NOISE_REPEAT, NOISE_TRACKER = 0.03, 0.02
TOOL = [0.0, 0.0, 250.0, 0.0, 0.0, 0.0]
TOOL_ERROR = np.array([0.4, -0.3, 0.6])
TILT_DEG = 25.0
POSES, POSE_REPEATS, CANDIDATES = 60, 3, 1500
TARGETS = 200


HARMONICS = tuple((h.axis, h.order) for h in load_robot("kr210-realistic").joint_errors.harmonics)


class Cell:
    """The simulated cell: the controller (nominal model, nominal tool) and the real arm."""

    def __init__(self) -> None:
        realistic = load_robot("kr210-realistic")
        self.controller = realistic.with_tool(pose_from_xyzabc(TOOL))
        real_tool = self.controller.flange_T_tool.copy()
        real_tool[:3, 3] += TOOL_ERROR
        self.real = realistic.with_tool(real_tool).true_robot()
        masses = realistic.joint_errors.masses
        nominal = load_robot("kr210").with_tool(pose_from_xyzabc(TOOL))
        self.nominal = replace(
            nominal, joint_errors=JointErrors.from_compliance(np.zeros(6), masses)
        )

    def joints(self, points: np.ndarray, abc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nominal IK (N, 6) rad in Status 6 of commands (N, 3) mm at A B C (N, 3) deg, and ok."""
        poses = np.tile(np.eye(4), (len(points), 1, 1))
        poses[:, :3, :3] = abc_to_matrix(np.broadcast_to(abc, points.shape))
        poses[:, :3, 3] = points
        sol = self.controller.ik(poses, status=STATUS)
        return sol.q, sol.ok

    def land(self, commands: np.ndarray, abc: np.ndarray) -> np.ndarray:
        """Where the real arm's TCP goes (N, 3) mm, noise-free."""
        q, ok = self.joints(commands, abc)
        assert ok.all(), "a corrected command left the Status or the limits"
        return self.real.fk(q)[:, :3, 3]

    def measure(self, points, abc, repeats, rng) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A tracker session: (commanded, measured, abc) with ``repeats`` consecutive rows."""
        reached = np.repeat(self.land(points, abc), repeats, axis=0)
        reached += rng.normal(0.0, NOISE_REPEAT, reached.shape)
        reached += rng.normal(0.0, NOISE_TRACKER, reached.shape)
        abc_rows = np.repeat(np.broadcast_to(abc, points.shape), repeats, axis=0)
        return np.repeat(points, repeats, axis=0), reached, abc_rows


def lattice(lo: np.ndarray, hi: np.ndarray, counts: tuple[int, int, int]) -> np.ndarray:
    axes = [np.linspace(lo[a], hi[a], counts[a]) for a in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)


def reachable_targets(cell: Cell, rng, tilt: bool) -> tuple[np.ndarray, np.ndarray]:
    """TARGETS random positions inside the region (50 mm margin) and orientations, all
    reachable in Status 6 (with the correction's few millimetres of slack)."""
    points, abc = np.zeros((0, 3)), np.zeros((0, 3))
    while len(points) < TARGETS:
        p = rng.uniform(LO + 50.0, HI - 50.0, (TARGETS, 3))
        a = (
            tilted_abc(rng, TARGETS, SEED_ABC, TILT_DEG)
            if tilt
            else np.tile(SEED_ABC, (TARGETS, 1))
        )
        ok = np.ones(TARGETS, bool)
        for shift in ([0, 0, 0], [5, 5, 5], [-5, -5, -5]):
            ok &= cell.joints(p + np.array(shift, float), a)[1]
        points, abc = np.vstack([points, p[ok]]), np.vstack([abc, a[ok]])
    return points[:TARGETS], abc[:TARGETS]


def row(name: str, measured: int, residual: np.ndarray) -> str:
    peak = np.abs(residual).max(axis=0)
    std = residual.std(axis=0)
    cells = [f"{v:.3f}" for v in (*peak, *std)]
    return f"| {name} | {measured} | " + " | ".join(cells) + " |"


def main_bench() -> None:
    rng = np.random.default_rng(13)
    cell = Cell()

    # grid only: the seed's 200 mm grid, 5 repeats
    vertices = lattice(LO, HI, (6, 7, 6))
    grid = GridModel.from_measurements(cell.measure(vertices, SEED_ABC, 5, rng))

    # model: D-optimal poses from tilted candidates, 3 repeats, identified with compliance
    cand_p = rng.uniform(LO, HI, (CANDIDATES, 3))
    cand_abc = tilted_abc(rng, CANDIDATES, SEED_ABC, TILT_DEG)
    q, ok = cell.joints(cand_p, cand_abc)
    cand_p, cand_abc, q = cand_p[ok], cand_abc[ok], q[ok]
    residual_vertices = lattice(LO, HI, (3, 3, 3))
    tool = cell.controller.flange_T_tool  # the controller's TOOL_DATA: the nominal drill
    residual_session = cell.measure(residual_vertices, SEED_ABC, 3, rng)
    models = {}
    plain = load_robot("kr210").with_tool(pose_from_xyzabc(TOOL))
    for name, harmonics in (
        ("model", ()),
        ("model + harmonics", HARMONICS),
        ("model, structure from the data", None),
        ("model, structure from the data, orders up to what the poses resolve", 0),
    ):
        auto = harmonics is None or isinstance(harmonics, int)
        if auto:
            chosen, o1 = select_poses(plain, q, POSES)
        else:
            chosen, o1 = select_poses(cell.nominal, q, POSES, compliance=True, harmonics=harmonics)
        commanded, measured, abc_rows = cell.measure(
            cand_p[chosen], cand_abc[chosen], POSE_REPEATS, rng
        )
        started = time.perf_counter()
        if auto:
            data = pose_set(plain, commanded, measured, abc_deg=abc_rows, status=STATUS)
            first = np.unique(data.group, return_index=True)[1]
            top = int(max_order_of(data.q[first]).max()) if harmonics == 0 else None
            result, selection = identify_structure(plain, data, max_order=top)
            cv = selection.nested
            print(f"{name}: chose {', '.join(selection.chosen)}")
        else:
            data = pose_set(cell.nominal, commanded, measured, abc_deg=abc_rows, status=STATUS)
            result = identify(cell.nominal, data, compliance=True, folds=5, harmonics=harmonics)
            cv = result.cross_validation
        identify_s = time.perf_counter() - started
        residual = residual_grid(result.robot, residual_session, STATUS, controller_tool=tool)
        models[name] = (result.robot, residual)
        print(
            f"{name}: {POSES} poses x {POSE_REPEATS} (O1 {o1:.3g}), rank {result.rank} of "
            f"{len(result.x)}, condition {result.condition_number:.3g}, "
            f"{'search + nested CV' if auto else 'identify + 5-fold CV'} "
            f"{identify_s:.2f} s; residual RMS {', '.join(f'{v:.3f}' for v in result.rms_mm)} "
            f"mm; {'nested ' if auto else ''}cross-validation RMS "
            f"{', '.join(f'{v:.3f}' for v in cv.rms_mm)}, max "
            f"{', '.join(f'{v:.3f}' for v in cv.max_mm)} mm"
        )
    print()
    header = "| targets, method | measured points | max X | max Y | max Z | std X | std Y | std Z |"
    print(header)
    print("|---|---|---|---|---|---|---|---|")
    n_grid, n_model = len(vertices) * 5, POSES * POSE_REPEATS
    n_both = n_model + len(residual_vertices) * 3
    for tilt in (False, True):
        points, abc = reachable_targets(cell, rng, tilt)
        label = "tilted 0-25 deg" if tilt else "A 0 B 90 C 0"
        print(row(f"{label}: before", 0, points - cell.land(points, abc)))
        for method in ("idw", "trilinear"):
            command = grid.correct(points, method=method)
            name = f"{label}: 200 mm grid, {method}"
            print(row(name, n_grid, points - cell.land(command, abc)))
        trilinear = CorrectionSettings(method="trilinear")
        for name, (calibrated, residual) in models.items():
            only = model_correct(calibrated, points, abc, STATUS, controller_tool=tool)
            print(row(f"{label}: {name}", n_model, points - cell.land(only.command, abc)))
            both = model_correct(
                calibrated, points, abc, STATUS, residual, trilinear, controller_tool=tool
            )
            name = f"{label}: {name} + 27-vertex residual grid"
            print(row(name, n_both, points - cell.land(both.command, abc)))


if __name__ == "__main__":
    main_bench()
