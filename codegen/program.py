"""The neutral drilling program: corrected, reachable poses per hole, independent of the dialect.

Per hole, four positions on the drill axis (tool Z, pointing into the part), in the BASE frame:

- ``APP`` approach: ``drilling.approach`` mm before the hole; travel (PTP or LIN) ends here;
- ``CLR`` clearance: ``drilling.clearance`` mm before the hole; approach speed from APP to here;
- ``BOT`` bottom: ``depth`` mm into the part; drilling feed from CLR to here, then the dwell;
- ``RET`` retract: ``drilling.retract`` mm before the hole, at approach speed.

Correction (docs/formats.md): the hole point is mapped to the robot frame (robot_T_base), corrected
with the grid (P' = P + e(P)), and the same vector e is added to all four positions of the hole.
Correcting each position by its own e would bend the drill axis by the difference, and that is
not small: the error changes over the 30-40 mm between approach and bottom, and inverse-distance
weighting over the 8 vertices of a cell jumps where the positions straddle a cell face (0.22 mm at
the example grid's Y = 0 plane). One vector per hole keeps the axis straight and the hole where
the grid says. Orientation is not corrected.

The grid and the model are the cell's (``grid``, ``correction.model``) unless the call names
others (``None``: none), as the command line reads them (``codegen.correction``); a program
corrected by neither says so in its header (``Program.header``). With a calibrated model the
vector is P' - P of the correction policy (``compensation.policy``, built by
``codegen.correction.policy_for``) at the hole point and its own orientation (the
controller's IK with the cell's tool in the program's Status, the calibrated arm carrying the
cell's tool), plus the grid as the residual after the model when one is given. The policy also
decides which holes are not corrected (outside the grid, orientation, Status, ...): the job is
refused unless ``allow_partial``, then those holes keep e = 0 and are listed in the header.

Every corrected pose goes through IK: unreachable or out-of-limit poses are InputErrors naming
the hole; |A5| below ``configuration.singular_a5`` is a warning. The configuration code is the
cell's; else, with a grid or a model, the one it corrected in (the grid's measurement Status, or
the first hole's IK default); else the first pose's IK solution; it stays the same for the whole
program unless ``configuration.allow_change`` lets a hole that cannot reach it take its own (an
uncorrected hole only: a correction holds in the Status it was made for). The jobs run this
check on a background thread (``build_program(..., background=True)``) while they write what
needs only the positions; ``Program.wait`` joins it, ``Program.configuration_of`` hands out the
configuration (``kinematics.configuration``) of holes its IK blocks have reached, which each
dialect writes in its own words. The joint angles of every pose (the IK
solution each pose is written with) are kept when a dialect asks (``keep_joints``:
``Program.joints``): ABB confdata comes from them.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np

from accugrid.codegen.cell_record import Cell
from accugrid.codegen.correction import (
    FROM_CELL,
    ModelFile,
    cell_grid,
    cell_model,
    policy_for,
)
from accugrid.codegen.points import Points
from accugrid.compensation.grid import GridModel
from accugrid.compensation.policy import PolicyRequest, Verdict, singular_a5_deg
from accugrid.infra.blocks import run_blocks
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import fixed_texts
from accugrid.kinematics.configuration import Configuration, quarters
from accugrid.kinematics.frames import (
    MAX_TILT_DEG,
    abc_to_matrix,
    invert,
    matrix_to_abc,
    orient_along_axes,
    rows_times,
    times_stack,
    too_tilted,
    transform_points,
)
from accugrid.kinematics.model import RobotModel
from accugrid.kinematics.robot import Robot

__all__ = [
    "IK_BLOCK",
    "MAX_AXIS_JUMP_DEG",
    "NOT_CORRECTED",
    "IKCheck",
    "STAGES",
    "Program",
    "build_program",
]

STAGES = ("APP", "CLR", "BOT", "RET")
_LISTED = 5  # holes named in one message
IK_BLOCK = 16384  # poses per IK call
MAX_AXIS_JUMP_DEG = 180.0  # a larger joint move between consecutive poses: a wrist flip or wrap
NOT_CORRECTED = "grid none, model none: positions are not corrected"  # a header line


@dataclass
class Program:
    """A corrected drilling job. N holes; positions (N, 4, 3) mm in the BASE frame, stage order
    ``STAGES``; rotations (N, 3, 3) tool orientation in the BASE frame."""

    cell: Cell
    points: Points
    positions: np.ndarray  # (N, 4, 3) mm, BASE frame, corrected
    rotations: np.ndarray  # (N, 3, 3)
    correction: np.ndarray  # (N, 3) mm, robot frame, e added to every stage of the hole
    feed_mm_s: np.ndarray  # (N,)
    depth_mm: np.ndarray  # (N,)
    configuration: Configuration | None  # (N, 4) per pose, stage order STAGES; None until
    # ``wait`` when the IK check runs in the background (``build_program(background=True)``)
    warnings: list[str]
    corrected: bool
    checking: IKCheck | None = field(default=None, repr=False, compare=False)
    joints: np.ndarray | None = field(default=None, repr=False)  # (N, S, 6) rad, robot axes of
    # each pose, S = 4 stages, or 3 when RET is the APP position; set by ``wait`` when built
    # with ``keep_joints``
    uncorrected: list[str] = field(default_factory=list)  # header lines: holes left as they are
    verdict: Verdict | None = field(default=None, repr=False)  # the policy's, robot frame

    def __len__(self) -> int:
        return len(self.positions)

    @property
    def nominal(self) -> np.ndarray:
        """(N, 4, 3) mm, BASE frame: the positions before correction, made when asked (a
        million-hole job keeps no second copy of its positions)."""
        return _nominal(self.cell, self.points.xyz, self.rotations[:, :, 2], self.depth_mm)

    def configuration_of(self, lo: int, hi: int) -> Configuration:
        """The configuration (hi - lo, 4) of holes lo..hi-1, stage order ``STAGES``. With the IK
        check in the background, as soon as its blocks have reached these holes (what the
        check keeps, see ``IKCheck.early``); else after ``wait``."""
        if self.checking is not None:
            early = self.checking.early(lo, hi)
            if early is not None:
                return early
        return self.wait().configuration[lo:hi]

    def wait(self) -> Program:
        """This program with its IK check done: waits for a check running in the background,
        then ``configuration`` is set and its warnings follow the correction's; raises the
        check's InputError (an unreachable hole, a branch jump)."""
        if self.checking is not None:
            configuration, warnings, joints = self.checking.result()  # raises again if waited
            self.configuration, self.joints, self.checking = configuration, joints, None
            self.warnings = self.warnings + warnings
        return self

    def joint_angles(self, lo: int = 0, hi: int | None = None) -> np.ndarray:
        """Joint angles (hi - lo, 4, 6) rad of holes lo..hi-1, stage order ``STAGES``: the IK
        solution each pose is written with (a program built with ``keep_joints``)."""
        joints = self.wait().joints
        if joints is None:
            raise ValueError("the program was built without keep_joints")
        q = joints[lo:hi]
        return q if q.shape[1] == 4 else np.concatenate([q, q[:, :1]], axis=1)

    def header(self, lines: list[str]) -> list[str]:
        """The header of a program file: ``lines`` (the caller's), then what the program says of
        itself that they do not: that nothing is corrected (``NOT_CORRECTED``), the holes left
        uncorrected (``uncorrected``)."""
        own = self.uncorrected if self.corrected else [NOT_CORRECTED]
        given = set(lines)
        return [*lines, *(line for line in own if line not in given)]

    def largest_correction(self) -> tuple[float, int | None]:
        """(length mm, hole index) of the largest correction; (0, None) for no holes."""
        if not len(self):
            return 0.0, None
        length = np.linalg.norm(self.correction, axis=1)
        i = int(np.argmax(length))
        return float(length[i]), i

    def labels(self, lo: int = 0, hi: int | None = None) -> list[str]:
        """Comment text of holes lo..hi-1: id, depth and diameter (templates sanitize it)."""
        hi = len(self) if hi is None else hi
        ids = self.points.ids[lo:hi]
        depth = fixed_texts(self.depth_mm[lo:hi], 3, distinct=True).tolist()
        dia = self.points.diameter[lo:hi]
        given = ~np.isnan(dia)
        if given.all():
            texts = fixed_texts(dia, 3, distinct=True).tolist()
            return [f"{i} depth {d} dia {t}" for i, d, t in zip(ids, depth, texts, strict=True)]
        if not given.any():
            return [f"{i} depth {d}" for i, d in zip(ids, depth, strict=True)]
        texts = np.full(len(dia), "", dtype=object)
        texts[given] = [f" dia {t}" for t in fixed_texts(dia[given], 3, distinct=True).tolist()]
        return [f"{i} depth {d}{t}" for i, d, t in zip(ids, depth, texts.tolist(), strict=True)]

    def in_frame(
        self, robot_T_frame: np.ndarray, lo: int = 0, hi: int | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Positions (n, 4, 3) mm and KUKA A,B,C (n, 3) deg of holes lo..hi-1 in another frame
        given in the robot frame (e.g. ``cell.dialects["gcode"].robot_T_program`` for G-code)."""
        frame_T_base = invert(robot_T_frame) @ self.cell.robot_T_base
        rot = frame_T_base[:3, :3]
        pos = rows_times(self.positions[lo:hi].reshape(-1, 3), rot.T).reshape(-1, 4, 3)
        pos += frame_T_base[:3, 3]  # one product of all rows, not one per hole
        rotations = self.rotations[lo:hi]
        abc = matrix_to_abc(times_stack(rot, rotations)) if len(rotations) else np.zeros((0, 3))
        return pos, abc


class IKCheck:
    """A program's IK check (``_configuration``) on a background thread: ``result()`` waits for
    it, (Configuration, warnings, joint angles) or its exception raised in the caller's thread;
    ``early`` hands out the configuration of holes its blocks have reached."""

    def __init__(self, check: Callable[[_Progress], tuple]) -> None:
        self._outcome: tuple | BaseException | None = None
        self._progress = _Progress()
        self._thread = threading.Thread(target=self._run, args=(check,), name="accugrid-ik")
        self._thread.start()

    def _run(self, check) -> None:
        try:
            self._outcome = check(self._progress)
        except BaseException as exc:  # raised again by result(), in the waiting thread
            self._outcome = exc
        finally:
            self._progress.close()

    def result(self) -> tuple[Configuration, list[str], np.ndarray | None]:
        self._thread.join()
        if isinstance(self._outcome, BaseException):
            raise self._outcome
        return self._outcome

    def early(self, lo: int, hi: int) -> Configuration | None:
        """The configuration (hi - lo, 4) of holes lo..hi-1 once the IK blocks have reached
        them, before the check ends: the numbers the check keeps, since it changes only holes
        with a failing pose (``allow_change``); None when one of these holes has one or the
        check ended first (then ``result()`` tells)."""
        return self._progress.early(lo, hi)


class _Progress:
    """How far the IK blocks of a check have come: the first pass's ``ok``, ``status`` and ``q``
    per pose (holes * stages, hole-major; each block writes its rows once and the
    check never changes them after) and the holes done so far."""

    def __init__(self) -> None:
        self._changed = threading.Condition()
        self._holes, self._closed = 0, False
        self._sol: SimpleNamespace | None = None
        self._stages = 0

    def start(self, sol: SimpleNamespace, stages: int) -> None:
        with self._changed:
            self._sol, self._stages = sol, stages

    def advance(self, holes: int) -> None:
        with self._changed:
            self._holes = holes
            self._changed.notify_all()

    def _reached(self, hi: int) -> bool:
        return self._sol is not None and self._holes >= hi

    def close(self) -> None:
        with self._changed:
            self._closed = True
            self._changed.notify_all()

    def early(self, lo: int, hi: int) -> Configuration | None:
        with self._changed:
            self._changed.wait_for(lambda: self._reached(hi) or self._closed)
            if not self._reached(hi):
                return None
            sol, k = self._sol, self._stages
        rows = slice(lo * k, hi * k)
        if not sol.ok[rows].all():
            return None
        return _stage_configuration(sol.status[rows].reshape(-1, k), sol.q[rows].reshape(-1, k, 6))


def build_program(
    points: Points,
    cell: Cell,
    robot: RobotModel,
    grid: GridModel | None = FROM_CELL,
    model: Robot | ModelFile | None = FROM_CELL,
    background: bool = False,
    validity=None,
    request: PolicyRequest | None = None,
    keep_joints: bool = False,
) -> Program:
    """Corrected, IK-checked program for ``points`` in ``cell``, corrected as the command line
    corrects it: ``grid`` the measured grid and ``model`` the calibrated model (a Robot, with
    ``validity`` where it holds, ``kinematics.validity``; or a ``ModelFile``), each by default
    the cell's (``grid``, ``correction.model``), None for none; with a model the grid holds its
    residual. ``robot``: the controller's, with the cell's tool. ``request``: the policy's
    options and job rule (``compensation.policy``; None: the defaults). ``background``: the
    IK check (configuration, reach, limits, branch jumps, the wrist singularity) runs on a
    background thread while the caller goes on with what needs only the positions (a G-code
    program, the .src of a KRL job); ``Program.wait()`` joins it. ``keep_joints``: keep the
    joint angles of every pose (``Program.joints``, 144 bytes a hole: only for a dialect whose
    configuration words need more than the configuration, e.g. ABB confdata)."""
    request = PolicyRequest() if request is None else request
    if grid is FROM_CELL:
        grid = cell_grid(cell)
    if model is FROM_CELL:
        model = cell_model(cell)
    elif model is not None and not isinstance(model, ModelFile):
        model = ModelFile(getattr(model, "source", None) or model.name, model, validity, None)
    n = len(points)
    if n == 0:
        raise InputError("no drilling points in the file", points.path)
    if points.axis is None:
        raise InputError(
            "the points have no orientation: add columns a,b,c or i,j,k", points.path, 1
        )
    rotations = _rotations(points, cell)
    axis = rotations[:, :, 2]
    depth = np.where(np.isnan(points.depth), cell.drilling.depth_mm, points.depth)
    feed = np.where(np.isnan(points.feed), cell.drilling.feed_mm_s, points.feed)
    base_rot = cell.robot_T_base[:3, :3]
    holes_robot = transform_points(cell.robot_T_base, points.xyz)
    warnings: list[str] = []
    marks: list[str] = []
    status = cell.configuration.status
    verdict = None
    if model is None and grid is None:
        correction = np.zeros((n, 3))
    else:  # the robot-frame rotations whole only here: freed before the IK
        correction, warnings, status, marks, verdict = _correct(
            points,
            cell,
            robot,
            grid,
            model,
            holes_robot,
            times_stack(base_rot, rotations),
            request,
        )
    positions = _nominal(cell, points.xyz, axis, depth)
    positions += rows_times(correction, base_rot)[:, None, :]  # e in the BASE frame

    corrected_in = status if model is not None or grid is not None else None

    def check(progress: _Progress | None = None) -> tuple:
        configuration, ik_warnings, q = _configuration(
            points, cell, robot, positions, rotations, status, progress, corrected_in, correction
        )
        return configuration, ik_warnings, q if keep_joints else None

    program = Program(
        cell=cell,
        points=points,
        positions=positions,
        rotations=rotations,
        correction=correction,
        feed_mm_s=feed,
        depth_mm=depth,
        configuration=None,
        warnings=warnings,
        corrected=grid is not None or model is not None,
        checking=IKCheck(check) if background else None,
        uncorrected=marks,
        verdict=verdict,
    )
    if not background:
        program.configuration, ik_warnings, program.joints = check()
        program.warnings = warnings + ik_warnings
    return program


def _nominal(cell: Cell, xyz: np.ndarray, axis: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Uncorrected positions (N, 4, 3) mm, BASE frame, stage order ``STAGES``: the hole points
    xyz (N, 3) mm moved along their drill axes (N, 3) by the cell's distances and the depths
    (N,) mm."""
    drilling = cell.drilling
    offsets = np.empty((len(xyz), 4))
    offsets[:, 0], offsets[:, 1] = -drilling.approach_mm, -drilling.clearance_mm
    offsets[:, 2], offsets[:, 3] = depth, -drilling.retract_mm
    out = np.multiply(offsets[:, :, None], axis[:, None, :])
    out += xyz[:, None, :]  # = xyz + offset * axis, without a second (N, 4, 3)
    return out


def _rotations(points: Points, cell: Cell) -> np.ndarray:
    """Tool rotations (N, 3, 3) in the BASE frame, from a,b,c or by the i,j,k rule of
    ``orient_along_axes`` around the cell's reference orientation (a robot-frame A,B,C), in
    blocks on the block threads. The robot-frame rotations are made where they are used (whole
    for the correction, block by block in the IK): a million-hole job never holds both."""
    n = len(points)
    base_rot = cell.robot_T_base[:3, :3]
    if points.abc is not None:

        def rule(rows: slice) -> np.ndarray:
            return abc_to_matrix(points.abc[rows]).reshape(-1, 3, 3)

    else:
        reference = base_rot.T @ abc_to_matrix(np.array(cell.configuration.reference_abc))
        bad = np.flatnonzero(too_tilted(points.axis, reference))
        if bad.size:
            raise InputError(
                f"{points.name(int(bad[0]))}: the drill axis i,j,k is more than "
                f"{MAX_TILT_DEG:g} deg from the reference tool axis (configuration.reference); "
                "give a,b,c for this hole or turn the reference",
                *points.table.where(int(bad[0]), "i"),
            )

        def rule(rows: slice) -> np.ndarray:
            return orient_along_axes(points.axis[rows], reference)

    out = np.empty((n, 3, 3))

    def block(i: int) -> None:  # in blocks: the rule's (N, 3, 3) temporaries stay small
        rows = slice(i, i + IK_BLOCK)
        out[rows] = rule(rows)

    run_blocks(block, range(0, n, IK_BLOCK))
    return out


def _correct(
    points: Points,
    cell: Cell,
    robot: RobotModel,
    grid: GridModel | None,
    model: ModelFile | None,
    holes_robot: np.ndarray,
    rotations: np.ndarray,
    request: PolicyRequest,
) -> tuple[np.ndarray, list[str], int | None, list[str], Verdict]:
    """The correction policy (``compensation.policy``, ``codegen.correction.policy_for``) at every
    hole point (N, 3) mm with its rotation (N, 3, 3), robot frame: e = P' - P (N, 3) (0 for holes
    left uncorrected), the warnings, the configuration code the program runs in (the cell's; else
    the one the model corrected in, or the grid's), the header lines marking each hole left
    uncorrected and the verdict (for the report). InputError (the policy's job rule) unless every
    hole is corrected or ``request.allow_partial``."""
    status = cell.configuration.status
    targets = None
    if model is not None:  # the A,B,C only for the model's Status rule
        targets = (holes_robot, matrix_to_abc(rotations))
    policy = policy_for(cell, grid, model, request, robot, targets)
    if status is None:
        status = policy.status if model is not None else policy.grid_status
    verdict = policy.decide(holes_robot, rotations, status=status)
    warnings = verdict.enforce(points.label, points.table.where, request.allow_partial, "hole")
    warnings += verdict.flag_lines(points.label, "hole")
    if policy.grid is not None and policy.grid.status is None and policy.grid_status is not None:
        warnings.append(f"the grid does not record its Status: {policy.describe_status()}")
    marks = [
        f"not corrected: hole {points.ids[i]}: {verdict.reason(i)}"
        for i in verdict.refused.tolist()
    ]
    return verdict.command - holes_robot, warnings, status, marks, verdict


def _configuration(
    points: Points,
    cell: Cell,
    robot: RobotModel,
    positions: np.ndarray,
    rotations: np.ndarray,
    status: int | None,
    progress: _Progress | None = None,
    corrected_in: int | None = None,
    correction: np.ndarray | None = None,
) -> tuple[Configuration, list[str], np.ndarray]:
    """IK of every pose (positions (N, 4, 3) mm and rotations (N, 3, 3), BASE frame) in the
    configuration code ``status`` (None: the first pose's IK default): the configuration
    (N, 4) per pose, the warnings and the joint angles (N, S, 6) rad (S: the stages solved, 3
    when RET is APP).
    ``progress``: told of the IK blocks as they are done. ``corrected_in``: the Status the
    corrections (N, 3) mm ``correction`` hold in (the policy's): a corrected hole that takes
    another one (allow_change) is an InputError."""
    n = len(points)
    if n == 0:
        q = np.zeros((0, 4, 6))
        return _stage_configuration(np.zeros((0, 4), int), q), [], q
    stages = len(STAGES) - (1 if cell.drilling.retract_mm == cell.drilling.approach_mm else 0)

    def poses(holes) -> np.ndarray:
        """Robot-frame TCP poses (len(holes), stages, 4, 4) of some holes (index or slice)."""
        return _poses(cell, positions[holes, :stages], rotations[holes])

    if status is None:
        first = robot.ik(poses(slice(0, 1))[0, :1], turn=cell.configuration.turn)
        if not first.ok[0]:
            _fail(points, 0, 0, first.reason[0], cell)
        status = int(first.status[0])
    sol = _ik_blocks(robot, poses, n, stages, status, cell.configuration.turn, progress)
    ok = sol.ok.reshape(n, stages).copy()  # the retry changes this, never the blocks' own
    q = sol.q.reshape(n, stages, 6)
    pose_status = sol.status.reshape(n, stages).astype(int)
    warnings: list[str] = []
    failed = np.flatnonzero(~ok.all(axis=1))
    if failed.size and cell.configuration.allow_change:
        # a failing hole takes the default configuration of its approach pose for all its poses
        failed_poses = poses(failed)
        own = robot.ik(failed_poses[:, 0])
        retry = robot.ik(
            failed_poses.reshape(-1, 4, 4),
            status=np.repeat(np.where(own.ok, own.status, 0), stages),
        )
        ok[failed] = retry.ok.reshape(-1, stages) & own.ok[:, None]
        q[failed] = retry.q.reshape(-1, stages, 6)
        pose_status[failed] = retry.status.reshape(-1, stages)
        changed = failed[ok[failed].all(axis=1)]
        moved = changed[np.any(correction[changed] != 0, axis=1)] if correction is not None else []
        if corrected_in is not None and len(moved):
            hole = int(moved[0])
            raise InputError(
                f"{points.name(hole)}: takes KUKA Status {int(pose_status[hole, 0])} "
                f"(configuration.allow_change), but its correction holds only in Status "
                f"{corrected_in}, the one it was corrected in; {len(moved)} such hole(s): give "
                "them a program of their own",
                *points.table.where(hole),
            )
        if changed.size:
            warnings.append(
                f"{changed.size} hole(s) take another Status than {status} "
                f"(configuration.allow_change), first {points.label(int(changed[0]))}"
            )
    failed = np.flatnonzero(~ok.all(axis=1))
    if failed.size:
        hole = int(failed[0])
        stage = int(np.flatnonzero(~ok[hole])[0])
        reason = sol.reason.reshape(n, stages)[hole, stage] or "no solution"
        _fail(points, hole, stage, reason, cell, failed.size, status, cell.configuration.turn)
    warnings += _branch_jumps(points, cell, q)
    a5 = singular_a5_deg(q[:, 0])
    for stage in range(1, stages):  # stage by stage: a reduction over a short axis is slow
        np.minimum(a5, singular_a5_deg(q[:, stage]), out=a5)
    near = np.flatnonzero(a5 < cell.configuration.singular_a5_deg)
    if near.size:
        named = ", ".join(f"{points.label(int(i))} |A5| {a5[i]:.1f} deg" for i in near[:_LISTED])
        more = f" and {near.size - _LISTED} more" if near.size > _LISTED else ""
        warnings.append(
            f"{near.size} hole(s) within {cell.configuration.singular_a5_deg:g} deg of the wrist "
            f"singularity (A5 = 0): {named}{more}"
        )
    return _stage_configuration(pose_status, q), warnings, q


def _stage_configuration(code: np.ndarray, q: np.ndarray) -> Configuration:
    """The configuration (H, 4) of holes whose S stages' poses have configuration codes (H, S)
    and joint angles (H, S, 6) rad; S = 3: RET is the APP position."""
    quarter = quarters(q)
    if code.shape[1] == 3:
        code, quarter = (np.concatenate([a, a[:, :1]], axis=1) for a in (code, quarter))
    return Configuration.of_code(code, quarter)


def _poses(cell: Cell, positions: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """Robot-frame TCP poses (H, S, 4, 4) of positions (H, S, 3) mm and rotations (H, 3, 3) in
    the BASE frame."""
    base_rot, base_org = cell.robot_T_base[:3, :3], cell.robot_T_base[:3, 3]
    out = np.empty((*positions.shape[:2], 4, 4))
    out[:, :, :3, :3] = times_stack(base_rot, rotations)[:, None]
    rows = rows_times(positions.reshape(-1, 3), base_rot.T) + base_org  # not one per hole
    out[:, :, :3, 3] = rows.reshape(positions.shape)
    out[:, :, 3] = (0.0, 0.0, 0.0, 1.0)
    return out


def _ik_blocks(
    robot: RobotModel, poses, holes: int, stages: int, status, turn, progress=None
) -> SimpleNamespace:
    """``robot.ik`` of the poses (holes * stages, 4, 4) that ``poses(slice)`` makes, in blocks of
    about ``IK_BLOCK`` poses on a few threads (``infra.blocks``): the same result as one
    call, with the poses and the IK's (M, 8, ...) temporaries bounded in memory. ``progress``
    (a ``_Progress``) is handed the result arrays and told the holes done, block by block."""
    per = max(IK_BLOCK // stages, 1)
    m = holes * stages
    out = SimpleNamespace(
        q=np.empty((m, 6)),
        ok=np.empty(m, bool),
        reason=np.empty(m, object),
        status=np.empty(m, np.int16),  # -1..7
    )

    def block(i: int) -> None:  # holes i .. i + per - 1, written into their rows of out
        sol = robot.ik(poses(slice(i, i + per)).reshape(-1, 4, 4), status=status, turn=turn)
        at = slice(i * stages, i * stages + len(sol.ok))
        for name, values in vars(out).items():
            values[at] = getattr(sol, name)

    follow = _WristFollower(robot, out) if turn is None else None

    def done(i: int) -> None:  # in hole order, once holes ..i + per - 1 are solved
        end = min(i + per, holes)
        if follow is not None:
            follow(slice(i * stages, end * stages))
        if progress is not None:
            progress.advance(end)

    if progress is not None:
        progress.start(out, stages)
    run_blocks(block, range(0, holes, per), done=done)
    return out


class _WristFollower:
    """A4 and A6 along the program (Turn free): the Status fixes the arm and the wrist, not the
    turn of A4 and A6, so each solved pose takes the angle closest to the pose before it (a
    full turn more or less than the IK's (-180, 180] deg one: 181 deg, not -179 deg, after 178
    deg) where that stays within the joint limits.
    Called on the rows of each block in program order (``run_blocks``' ``done``), before the
    block is published to an early reader."""

    def __init__(self, robot: RobotModel, sol: SimpleNamespace) -> None:
        self._sol = sol
        self._limits = np.radians(robot.joint_limits_deg)
        self._last: dict[int, float] = {}  # axis -> its angle at the last solved pose, rad

    def __call__(self, rows: slice) -> None:
        q, solved = self._sol.q[rows], np.flatnonzero(self._sol.ok[rows])
        if not solved.size:
            return
        for axis in (3, 5):
            angles = q[solved, axis]
            start = self._last.get(axis, angles[0])
            path = np.unwrap(np.concatenate([[start], angles]))[1:]
            lo, hi = self._limits[axis]
            path[path > hi] -= 2 * np.pi  # beyond a limit: back by a turn (a jump: reported)
            path[path < lo] += 2 * np.pi
            outside = (path < lo) | (path > hi)
            path[outside] = angles[outside]
            q[solved, axis] = path
            self._last[axis] = float(path[-1])


def _branch_jumps(points: Points, cell: Cell, q: np.ndarray) -> list[str]:
    """An axis turning more than ``MAX_AXIS_JUMP_DEG`` between consecutive poses (a wrist flip or
    a change of branch): InputError naming the hole, or a warning with allow_change."""
    seq = q.reshape(-1, 6)
    jump = np.abs(seq[1:, 0] - seq[:-1, 0])
    for axis in range(1, 6):  # axis by axis: no (M, 6) temporaries
        np.maximum(jump, np.abs(seq[1:, axis] - seq[:-1, axis]), out=jump)
    np.degrees(jump, out=jump)
    bad = np.flatnonzero(jump > MAX_AXIS_JUMP_DEG)
    if not bad.size:
        return []
    hole = int((bad[0] + 1) // q.shape[1])
    before, after = np.degrees(seq[bad[0]]), np.degrees(seq[bad[0] + 1])
    axis = int(np.argmax(np.abs(after - before)))
    message = (
        f"{points.name(hole)}: A{axis + 1} turns {jump[bad[0]]:.0f} deg from the previous pose "
        f"({before[axis]:.1f} to {after[axis]:.1f} deg; more than {MAX_AXIS_JUMP_DEG:g} deg: the "
        "robot changes configuration on the way)"
    )
    if not cell.configuration.allow_change:
        raise InputError(
            message + "; reorder the holes or set configuration.allow_change",
            *points.table.where(hole),
        )
    return [message + f"; {bad.size} such move(s) in the program"]


def _fail(points, hole, stage, reason, cell, count=1, status=None, turn=None) -> None:
    config = "" if status is None else f" with Status {status}"
    config += "" if turn is None else f" Turn {turn}"
    hint = (
        ""
        if status is None or cell.configuration.allow_change
        else " (configuration.allow_change lets a hole take another Status)"
    )
    more = f"; {count - 1} more hole(s) fail" if count > 1 else ""
    raise InputError(
        f"{points.name(hole)}: the {STAGES[stage]} pose is not reachable{config}: {reason}"
        f"{more}{hint}",
        *points.table.where(hole),
    )
