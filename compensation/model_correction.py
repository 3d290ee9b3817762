"""Correction with a calibrated kinematic model, optionally plus a residual grid (issue 13 item 5).

The robot's controller keeps its nominal model: commanded a TCP pose (position P', orientation R)
in one KUKA Status it runs the nominal IK, and the real arm, which the calibrated model stands for
(``calibrated.true_robot()``: identified DH errors, TCP, joint errors), reaches
reach(P') = FK_cal(IK_nom(P', R, Status)). ``model_correct`` finds per target P (robot frame, mm)
the command P' with reach(P') = P by the fixed-point iteration P'_(k+1) = P'_k + (P - reach(P'_k)),
P'_0 = P. reach differs from the identity by millimetres over metres, so every step gains about
three orders of magnitude; it stops when |P - reach(P')| < ``tol_mm``.

With a residual grid (``residual_grid``: at every vertex the measured error minus the model's, so
r = reach_model - M, mm) the arm is taken to reach reach(P') - r, and the iteration solves
reach(P') = P + r(P). r is interpolated at the target, not at the moving command: the two differ
by the correction (millimetres), over which r changes by micrometres, and IDW, which jumps across
cell faces, would otherwise keep the iteration from settling next to a face. The orientation R
stays as commanded: only positions are corrected.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from accugrid.compensation.grid import GridModel
from accugrid.compensation.settings import CorrectionSettings
from accugrid.infra.blocks import run_blocks
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix

if TYPE_CHECKING:  # a grid-only rewrite or correct never loads the robot modules
    from accugrid.kinematics.robot import Robot

__all__ = [
    "BLOCK",
    "MAX_ITERATIONS",
    "SETUP_FACTOR",
    "SETUP_FLOOR_MM",
    "TOL_MM",
    "ModelCorrection",
    "model_correct",
    "reached_by_model",
    "residual_grid",
]

BLOCK = 16384  # targets iterated together, blocks on the threads of infra.blocks
TOL_MM = 1e-3  # default: |P - reach(P')| below 0.001 mm
MAX_ITERATIONS = 12
SETUP_FACTOR = 2.0  # a residual grid's mean offset beyond this x the validated max: refused
SETUP_FLOOR_MM = 0.2  # ... and beyond this, mm


@dataclass(frozen=True)
class ModelCorrection:
    """Result of ``model_correct`` for N targets."""

    command: np.ndarray  # (N, 3) mm, P'; the target itself where not ok
    ok: np.ndarray  # (N,) bool
    reason: np.ndarray  # (N,) object: "" when ok, else why not
    miss_mm: np.ndarray  # (N,) |P + r(P) - reach(P')| at the returned command, mm (NaN if none)
    iterations: (
        int  # passes over the points (each one nominal IK + calibrated FK), most of any block
    )
    q: np.ndarray | None = None  # (N, 6) rad: the controller's joints at the command (NaN: none)

    @property
    def failed(self) -> np.ndarray:
        """Indices (M,) of the targets that are unreachable or did not converge."""
        return np.flatnonzero(~self.ok)


def reached_by_model(
    calibrated: Robot,
    commands: np.ndarray,
    rotations: np.ndarray,
    status: int | np.ndarray | None,
    controller_tool: np.ndarray | None = None,
    arm_tool: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where the calibrated arm puts the tool tip for commands (N, 3) mm at rotations (N, 3, 3)
    under the nominal controller in KUKA ``status`` (int, or (N,) ints: each command's own):
    (positions (N, 3) mm, NaN where the nominal IK fails; ok (N,); reason (N,)). The controller
    solves with ``controller_tool`` (flange_T_tool (4, 4) mm, its TOOL_DATA), the arm carries
    ``arm_tool`` (the tool whose tip lands; for a program both are the cell's tool, the drill
    as taught); either defaults to the calibrated TCP (the SMR the model was measured with)."""
    return _reach(calibrated, commands, rotations, status, controller_tool, arm_tool)[:3]


def _reach(calibrated, commands, rotations, status, controller_tool, arm_tool):
    """``reached_by_model`` and the controller's joints (N, 6) rad (NaN rows: none)."""
    poses = np.zeros((len(commands), 4, 4))
    poses[:, :3, :3] = rotations
    poses[:, :3, 3] = commands
    poses[:, 3, 3] = 1.0
    controller = calibrated if controller_tool is None else calibrated.with_tool(controller_tool)
    sol = controller.ik(poses, status=status)
    true = calibrated.true_robot() or calibrated
    if arm_tool is not None:
        true = true.with_tool(arm_tool)
    out = np.full((len(commands), 3), np.nan)
    if sol.ok.any():
        out[sol.ok] = true.fk(sol.q[sol.ok])[:, :3, 3]
    return out, sol.ok, sol.reason, sol.q


def model_correct(
    calibrated: Robot,
    points: np.ndarray,
    abc_deg: np.ndarray,
    status: int | np.ndarray | None,
    grid: GridModel | None = None,
    settings: CorrectionSettings | None = None,
    tol_mm: float = TOL_MM,
    max_iterations: int = MAX_ITERATIONS,
    controller_tool: np.ndarray | None = None,
    arm_tool: np.ndarray | None = None,
) -> ModelCorrection:
    """Commands P' (N, 3) mm for targets P (N, 3) mm (robot frame) at KUKA A, B, C ``abc_deg``
    ((N, 3) or (3,) deg) in KUKA ``status`` (one int, (N,) ints: each target's own, or None:
    the IK default per point).

    ``grid``: a residual grid (``residual_grid``) added as r(P), interpolated with ``settings``
    (method, power, outside rule; default ``CorrectionSettings()``). Unreachable targets and
    targets that do not converge within ``max_iterations`` are ``ok = False`` with the reason,
    vectorized over N. ``controller_tool``, ``arm_tool``: as ``reached_by_model``.
    """
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    n = len(points)
    rotations = np.broadcast_to(abc_to_matrix(np.asarray(abc_deg, dtype=float)), (n, 3, 3))
    if not tol_mm > 0 or int(max_iterations) < 1:
        raise InputError("tolerance must be > 0 mm and iterations >= 1")
    settings = settings or CorrectionSettings()
    per_point = status is not None and np.ndim(status) > 0
    if per_point:
        status = np.broadcast_to(np.asarray(status, dtype=np.int64), (n,))
    goals = points
    if grid is not None:
        goals = points + grid.predict(points, settings.method, settings.power, settings.outside)
    command = points.copy()
    ok = np.zeros(n, bool)
    miss_mm = np.full(n, np.nan)
    joints = np.full((n, 6), np.nan)
    reason = np.full(n, "", dtype=object)
    passes = np.zeros(-(-n // BLOCK), int)

    def block(start: int) -> None:
        """The iteration for targets start..start+BLOCK-1 (each target's own: blocks are
        independent), written into their rows."""
        active = np.arange(start, min(start + BLOCK, n))
        while active.size and passes[start // BLOCK] < max_iterations:
            passes[start // BLOCK] += 1
            reach, reached, why, q = _reach(
                calibrated,
                command[active],
                rotations[active],
                status[active] if per_point else status,
                controller_tool,
                arm_tool,
            )
            reason[active[~reached]] = why[~reached]
            active, reach, q = active[reached], reach[reached], q[reached]
            miss = goals[active] - reach
            length = np.linalg.norm(miss, axis=1)
            miss_mm[active] = length
            done = length < tol_mm
            joints[active[done]] = q[done]  # the command is final: its joints are these
            ok[active[done]] = True
            command[active[~done]] += miss[~done]
            active = active[~done]
        reason[active] = f"no convergence to {tol_mm:g} mm in {max_iterations} iterations"

    run_blocks(block, range(0, n, BLOCK))
    command[~ok] = points[~ok]
    return ModelCorrection(command, ok, reason, miss_mm, int(passes.max(initial=0)), joints)


def residual_grid(
    calibrated: Robot,
    measurements: str | os.PathLike[str] | tuple | GridModel,
    status: int | None,
    abc_deg: np.ndarray | None = None,
    repeat_tol_mm: float | None = None,
    controller_tool: np.ndarray | None = None,
    arm_tool: np.ndarray | None = None,
) -> GridModel:
    """The grid of what the calibrated model leaves: at each vertex P_v the measured error
    P_v - M minus the model's P_v - reach(P_v), i.e. r = reach(P_v) - M (mm).

    ``measurements``: a measurement CSV path or (commanded, measured[, abc]) arrays, as for
    ``GridModel.from_measurements``, or the measured GridModel itself; the vertices are reached
    at the measurement's a,b,c (``abc_deg`` when it has none) in KUKA ``status`` (the grid's
    own) with ``controller_tool`` and ``arm_tool`` (as ``reached_by_model``). InputError naming
    the first vertex the nominal controller cannot reach, and for a grid whose mean residual is
    beyond what the model's identification validated (``Robot.validated_max_mm``; without one,
    ``SETUP_FLOOR_MM``): measured with another tool or base than the model.
    """
    if isinstance(measurements, GridModel):
        measured = measurements
    else:
        kwargs = {} if repeat_tol_mm is None else {"repeat_tol_mm": repeat_tol_mm}
        measured = GridModel.from_measurements(measurements, **kwargs)
    abc = measured.orientation_abc if measured.orientation_abc is not None else abc_deg
    if abc is None:
        raise InputError(
            "a residual grid needs the orientation of its measurement (a,b,c columns)",
            measured.source_path,
        )
    vertices = measured.vertices().reshape(-1, 3)
    rotations = np.broadcast_to(abc_to_matrix(np.asarray(abc, dtype=float)), (len(vertices), 3, 3))
    reach, ok, why = reached_by_model(
        calibrated, vertices, rotations, status, controller_tool, arm_tool
    )
    if not ok.all():
        i = int(np.flatnonzero(~ok)[0])
        x, y, z = vertices[i]
        raise InputError(
            f"{(~ok).sum()} grid vertices cannot be reached by {calibrated.name}; first X {x:g} "
            f"Y {y:g} Z {z:g} ({why[i]})",
            measured.source_path,
        )
    model_error = (vertices - reach).reshape(measured.errors.shape)
    _check_same_set_up(calibrated, measured.errors - model_error, measured.source_path)
    return GridModel(
        measured.origin,
        measured.step,
        measured.errors - model_error,
        orientation_abc=np.asarray(abc, dtype=float),
        status=measured.status,
        source_sha256=measured.source_sha256,
        source_path=measured.source_path,
        repeats=measured.repeats,
        spread_mm=measured.spread_mm,
        noise_mm=measured.noise_mm,
    )


def _check_same_set_up(calibrated: Robot, residual: np.ndarray, path: str | None) -> None:
    """InputError when the residual grid (..., 3) mm is offset on average by more than
    ``SETUP_FACTOR`` x the model's validated max error (at least ``SETUP_FLOOR_MM``; a model
    that makes no claim, e.g. a file without ``identification:``, gets the floor) on an axis: a
    common offset is what another tool or base frame puts into every vertex."""
    offset = residual.reshape(-1, 3).mean(axis=0)
    claimed = calibrated.validated_max_mm
    limit = np.maximum(SETUP_FACTOR * (0.0 if claimed is None else claimed), SETUP_FLOOR_MM)
    if np.any(np.abs(offset) > limit):
        said = (
            "the floor of a model without a validated error"
            if claimed is None
            else f"{SETUP_FACTOR:g} x the error its identification validated "
            f"({', '.join(f'{v:.3f}' for v in claimed)} mm)"
        )
        raise InputError(
            "the residual grid is offset from the model by "
            f"({', '.join(f'{v:.3f}' for v in offset)}) mm on average, beyond {said}, "
            f"{', '.join(f'{v:.3f}' for v in np.broadcast_to(limit, 3))} mm: was it measured "
            "with another tool or base than the model's measurements?",
            path,
        )
