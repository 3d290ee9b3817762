"""The correction policy: the one place that decides, for every position of every command
(``correct``, ``krl``, ``gcode``, ``rewrite``, the Python API), whether it is corrected, how, and
why not.

``Policy.build`` takes a job's inputs once: the grid (the measured error grid, or the residual
grid after a calibrated model), the calibrated model, the tools and the limits. ``Policy.decide``
gives for N robot-frame targets a ``Verdict``: the command of each (P' where corrected, the
target itself where not), a reason code (N,) (``CORRECTED`` or why not, ``REASONS``) and flags
(N,) (corrected, but worth a look, ``FLAGS``), with the numbers the words need. The words come
from these two tables only, so the same input gets the same verdict and the same words in every
command. ``Verdict.enforce`` is the job rule: a correction beyond the safety limit refuses the
job; any other position not corrected refuses it too unless the job allows a partial result.

What is decided, in this order:

- the grid box: outside it a position is not corrected (``settings.outside == "clamp"``: the
  nearest cell's error is used and the position flagged);
- orientation against the grid's measured a,b,c (``GRID_ORIENTATION_TOL_DEG`` flags,
  ``ORIENTATION_LIMIT_DEG`` refuses unless ``allow_orientation``; with a model the residual grid
  is only flagged: the model holds at any orientation);
- Status against the grid's (``grid_status``: the measurement's column s, else the IK Status at
  the grid origin, said by ``grid_status_source``): a grid, error or residual, holds only in the
  Status it was measured in;
- with a model: an orientation is needed; the nominal controller with ``controller_tool`` must
  reach the command in the position's own Status, and the calibrated arm carrying ``arm_tool``
  must land it within 0.001 mm (``model_correction``); the command's joints are checked against
  the wrist singularity (|A5| below ``singular_a5_deg``, flagged) and the model's validated poses
  (``kinematics.validity``: flagged with the distance, refused with ``strict``) and the model's
  support among them (``kinematics.support``: a target whose prediction leverage exceeds every
  calibration pose's leave-one-out leverage is flagged and corrected by the DH-only fit of the
  same poses without the residual grid, refused with ``strict``);
- the safety limit ``settings.max_correction_mm`` on |P' - P|.

Tools: a calibrated model is the arm; its identified TCP is the SMR it was measured with.
Programs are corrected with the cell's tool (the drill as taught) as both ``controller_tool``
and ``arm_tool``; ``accugrid correct`` without ``--tool`` lands the SMR (the file's
``identification.controller_tool`` on the controller, the identified TCP on the arm).

Several tools (``decide_tool``): a position of another tool than the job's (``tool``, the one
the grid was measured with) is corrected by a model with that tool's own TCP. A grid holds the
position error of one TCP: at another TCP of the same flange pose the error differs by the
arm's orientation error times the distance between the TCPs, which no grid measures. So a grid
(or a residual grid) corrects another tool's positions only when its TCP is within
``settings.tool_distance_mm`` of the grid's tool's (its orientation, for the grid's orientation
check, is that of the grid's tool at the same flange pose); beyond it the grid alone refuses
them (``OTHER_TOOL``) and a model corrects them without the residual grid (flagged ``F_TOOL``).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from accugrid.compensation.budget import Budget, ModelBudget
from accugrid.compensation.grid import GridModel
from accugrid.compensation.model_correction import model_correct, residual_grid
from accugrid.compensation.settings import CorrectionSettings
from accugrid.infra.errors import InputError

if TYPE_CHECKING:  # a grid-only correction never loads the robot modules
    from accugrid.kinematics.robot import Robot
    from accugrid.kinematics.validity import Validity

__all__ = [
    "CORRECTED",
    "FIXES",
    "FLAGS",
    "F_BUDGET",
    "F_CLAMPED",
    "F_ORIENTATION",
    "F_REGION",
    "F_SINGULAR",
    "F_SUPPORT",
    "F_TOOL",
    "GRID_ORIENTATION_TOL_DEG",
    "NO_CONVERGENCE",
    "NO_ORIENTATION",
    "NO_SUPPORT",
    "NOT_PLACED",
    "NO_STATUS",
    "ORIENTATION",
    "OTHER_TOOL",
    "ORIENTATION_LIMIT_DEG",
    "OUTSIDE_GRID",
    "OUTSIDE_MODEL",
    "REASONS",
    "SINGULAR_A5_DEG",
    "STATUS",
    "TOO_LONG",
    "UNREACHABLE",
    "Policy",
    "PolicyRequest",
    "Verdict",
    "singular_a5_deg",
]

GRID_ORIENTATION_TOL_DEG = 5.0  # a grid's errors hold near the orientation it was measured at
ORIENTATION_LIMIT_DEG = 15.0  # ... and not at all this far from it
SINGULAR_A5_DEG = 5.0  # |A5| below this: near the wrist singularity

# reason codes: why a position is not corrected (0: it is)
CORRECTED, OUTSIDE_GRID, ORIENTATION, STATUS, NO_ORIENTATION = 0, 1, 2, 3, 4
UNREACHABLE, NO_CONVERGENCE, OUTSIDE_MODEL, TOO_LONG = 5, 6, 7, 8
# a position a program commands that cannot be placed in the robot frame (unknown base, a
# variable, an offset, an unknown start): never given to ``decide``, it lands off by the robot's
# error all the same, so it counts in the job rule like any position not corrected
NOT_PLACED = 9
OTHER_TOOL = 10  # a grid's positions of a tool whose TCP is far from the grid's tool's
NO_STATUS = 11  # a model's position with no Status of its own, and the job has none
NO_SUPPORT = 12  # --strict: the model extrapolates there (``kinematics.support``)
# code -> (short words for counts, the reason's words; fields: see ``Verdict.reason``)
REASONS = {
    OUTSIDE_GRID: ("outside the grid", "outside the {grid} box by {value:.3f} mm"),
    ORIENTATION: (
        "orientation beyond the limit",
        "orientation {value:.1f} deg from the {grid}'s {grid_abc} deg, beyond the limit of "
        "{limit:g} deg: the grid does not hold there",
    ),
    STATUS: (
        "another Status than the grid's",
        "in KUKA Status {value:.0f}: the {grid} holds only in Status {grid_status}, the one it "
        "was measured in",
    ),
    NO_ORIENTATION: ("no orientation", "no orientation (A, B, C) here: the model needs one"),
    UNREACHABLE: ("not reachable", "not reachable in KUKA Status {value:.0f}: {why}"),
    NO_CONVERGENCE: ("no convergence", "the model does not converge: {why}"),
    OUTSIDE_MODEL: (
        "outside the model's poses",
        "outside the poses the model was identified from ({region}; --strict refuses)",
    ),
    NO_SUPPORT: (
        "without the model's support",
        "without support in the poses the model was identified from: {value:.2f} x the largest "
        "prediction leverage or joint-space distance among them (--strict refuses)",
    ),
    TOO_LONG: (
        "beyond the safety limit",
        "correction of {value:.3f} mm exceeds the safety limit of {max:g} mm",
    ),
    NOT_PLACED: ("not placed in the robot frame", "not placed in the robot frame: {why}"),
    OTHER_TOOL: (
        "another tool than the grid's",
        "tool {tool:.0f}: its TCP is {value:.3f} mm from that of the tool the {grid} was "
        "measured with, beyond correction.tool_distance ({tool_distance:g} mm): a grid holds the "
        "error of its own TCP only (a calibrated model, --model, corrects each tool)",
    ),
    NO_STATUS: (
        "no KUKA Status",
        "no KUKA Status: the position has no S, none is written before it and the cell sets "
        "no configuration.status; the model corrects a position in the Status the robot runs "
        "it in",
    ),
}
# what fixes a job refused for a reason, where --allow-partial (uncorrected) is not the answer
FIXES = {NO_STATUS: "set configuration.status in the cell file: the Status the robot runs in"}
# flags (bits): corrected, but worth a look
F_ORIENTATION, F_CLAMPED, F_REGION, F_SINGULAR, F_TOOL, F_SUPPORT = 1, 2, 4, 8, 16, 32
F_BUDGET = 64  # its 95 % bound (``compensation.budget``) beyond --max-u95
FLAGS = {
    F_ORIENTATION: "orientation {angle:.1f} deg from the {grid}'s",
    F_CLAMPED: "outside the {grid} box by {clamp:.3f} mm: the nearest cell's error used",
    F_REGION: "outside the poses the model was identified from ({region})",
    F_SINGULAR: "|A5| {a5:.1f} deg, within {singular:g} deg of the wrist singularity",
    F_TOOL: (
        "tool {tool:.0f}: corrected by the model alone, its TCP {tool_mm:.3f} mm from that of "
        "the tool the residual grid was measured with (beyond correction.tool_distance)"
    ),
    F_SUPPORT: (
        "without support in the poses the model was identified from ({support:.2f} x the "
        "largest prediction leverage or joint-space distance among them): corrected by the "
        "DH-only fit of the same poses"
    ),
    F_BUDGET: "95 % bound {u95:.4f} mm beyond --max-u95 {max_u95:g} mm",
}
_LISTED = 5


def singular_a5_deg(q: np.ndarray) -> np.ndarray:
    """|A5| (...) deg of joint vectors q (..., 6) rad: the distance from the wrist singularity,
    compared with ``SINGULAR_A5_DEG`` (or the cell's ``configuration.singular_a5``)."""
    return np.degrees(np.abs(np.asarray(q)[..., 4]))


@dataclass(frozen=True)
class PolicyRequest:
    """What a command asks of the policy, the same options in every command (``correct``,
    ``krl``, ``gcode``, ``rapid``, ``rewrite``): positions outside the grid box (``outside``, the
    ``CorrectionSettings.outside`` word), the orientation against the grid's (flagged beyond
    ``orientation_tol_deg``, refused beyond ``orientation_limit_deg`` unless
    ``allow_orientation``; deg), ``strict`` (a model's positions outside its poses refused, not
    flagged), the largest 95 % bound of a position (``max_u95_mm``, mm; None: any; beyond it
    flagged, the job refused unless ``allow_partial``) and the job rule (``allow_partial``:
    ``Verdict.enforce``)."""

    outside: str = "error"
    orientation_tol_deg: float = GRID_ORIENTATION_TOL_DEG
    orientation_limit_deg: float = ORIENTATION_LIMIT_DEG
    allow_orientation: bool = False
    strict: bool = False
    allow_partial: bool = False
    max_u95_mm: float | None = None

    def check(self) -> None:
        """InputError unless 0 <= orientation_tol_deg <= orientation_limit_deg and
        max_u95_mm, when given, is a positive number."""
        if not 0 <= self.orientation_tol_deg <= self.orientation_limit_deg:
            raise InputError("need 0 <= --orientation-tol <= --orientation-limit (deg)")
        if self.max_u95_mm is not None and not (0 < self.max_u95_mm < np.inf):
            raise InputError(f"--max-u95 {self.max_u95_mm:g}: must be a positive length, mm")

    def limits(self) -> dict:
        """The fields of ``Policy`` it sets (``Policy.build``'s ``limits``)."""
        return {
            "orientation_tol_deg": self.orientation_tol_deg,
            "orientation_limit_deg": self.orientation_limit_deg,
            "allow_orientation": self.allow_orientation,
            "strict": self.strict,
            "max_u95_mm": self.max_u95_mm,
        }


@dataclass(frozen=True)
class Policy:
    """How targets are corrected and which are not (module docstring). ``grid``: the error grid
    (no model) or the residual grid after ``calibrated`` (None: none); ``status``: the job's KUKA
    Status (positions without their own); ``grid_status``: the Status the grid holds in (None:
    unknown, not checked); ``controller_tool``/``arm_tool`` (4, 4) mm (None: the calibrated TCP);
    ``validity``: where the model holds (None: no record); ``tool``: the job's tool, the one the
    grid was measured with (flange_T_tool (4, 4) mm, None: not given); ``budget``: each
    corrected position's error budget (``compensation.budget``), flagged beyond ``max_u95_mm``."""

    settings: CorrectionSettings
    grid: GridModel | None
    calibrated: Robot | None = None
    status: int | None = None
    grid_status: int | None = None
    grid_status_source: str = ""
    controller_tool: np.ndarray | None = None
    arm_tool: np.ndarray | None = None
    validity: Validity | None = None
    orientation_tol_deg: float = GRID_ORIENTATION_TOL_DEG
    orientation_limit_deg: float = ORIENTATION_LIMIT_DEG
    allow_orientation: bool = False
    strict: bool = False
    singular_deg: float = SINGULAR_A5_DEG
    tool: np.ndarray | None = None
    budget: Budget = Budget()
    max_u95_mm: float | None = None

    @classmethod
    def build(
        cls,
        settings: CorrectionSettings,
        grid: str | os.PathLike[str] | GridModel | None,
        calibrated: Robot | None = None,
        status: int | None = None,
        tools: tuple[np.ndarray | None, np.ndarray | None] = (None, None),
        repeat_tol_mm: float | None = None,
        points: np.ndarray | None = None,
        abc_deg: np.ndarray | None = None,
        turn: int | None = None,
        nominal: Robot | None = None,
        validity: Validity | None = None,
        budget: Budget | None = None,
        **limits,
    ) -> Policy:
        """The policy of one job. ``grid``: a measurement CSV path, a measured GridModel or
        None; ``tools``: (controller, arm) flange_T_tool (4, 4) mm of a model job;
        ``status``: the job's configuration code (None: the grid's, else the IK default at the
        first of ``points`` (N, 3) mm at ``abc_deg`` (N, 3) deg with ``turn``); ``nominal``: the
        controller's robot, with the tool the grid was measured with, which finds the Status of
        a grid that does not record it; ``budget``: the model's and frames' terms of the error
        budget (None: none known); ``limits``: the orientation, strictness and bound fields.
        InputError for a bad grid, a residual grid the model cannot reach or measured with
        another set-up."""
        measured = grid
        if grid is not None and not isinstance(grid, GridModel):
            kwargs = {} if repeat_tol_mm is None else {"repeat_tol_mm": repeat_tol_mm}
            measured = GridModel.from_measurements(grid, **kwargs)
        controller_tool, arm_tool = tools
        solver = nominal
        if calibrated is not None:
            solver = (
                calibrated if controller_tool is None else calibrated.with_tool(controller_tool)
            )
        grid_status, source = _grid_status(measured, solver)
        limits["budget"] = replace(budget or Budget(), modelled=calibrated is not None)
        if calibrated is None:
            return cls(
                settings,
                measured,
                None,
                status,
                grid_status,
                source,
                validity=validity,
                tool=controller_tool,
                **limits,
            )
        if measured is not None and grid_status is None and measured.orientation_abc is not None:
            raise InputError(  # a residual grid is computed in its own Status only
                "the grid does not record its KUKA Status (column s) and the model reaches no "
                "Status at its origin: the residual cannot be computed",
                measured.source_path,
            )
        if status is None:
            status = (
                grid_status
                if measured is not None
                else _first_status(solver, points, abc_deg, turn)
            )
        if measured is not None:
            measured = residual_grid(
                calibrated,
                measured,
                grid_status,
                controller_tool=controller_tool,
                arm_tool=arm_tool,
            )
        return cls(
            settings,
            measured,
            calibrated,
            status,
            grid_status,
            source,
            controller_tool,
            arm_tool,
            validity,
            tool=controller_tool,
            **limits,
        )

    @property
    def grid_name(self) -> str:
        return "residual grid" if self.calibrated is not None else "grid"

    def describe_status(self) -> str:
        """One line: the Status the grid holds in and where it comes from ("" without one)."""
        if self.grid_status is None:
            return ""
        return (
            f"{self.grid_name} holds in KUKA Status {self.grid_status} ({self.grid_status_source})"
        )

    def decide(
        self,
        points: np.ndarray,
        rotations: np.ndarray | None = None,
        axes: np.ndarray | None = None,
        status: int | np.ndarray | None = None,
    ) -> Verdict:
        """The verdict for targets P (N, 3) mm, robot frame, with their rotations (N, 3, 3)
        (NaN rows: none) or drill axes (N, 3), and their configuration codes (int or (N,) ints,
        -1: none; None: the job's; ``kinematics.configuration``). Vectorized over N."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        n = len(points)
        v = Verdict(self, points, points.copy(), np.zeros(n, np.int8), np.zeros(n))
        own = self._statuses(status, n)
        if self.grid is not None and n:
            found = self.grid.check(points, self.settings, rotations=rotations, axes=axes)
            if found.outside.size:
                gap = np.maximum(self.grid.origin - points[found.outside], 0.0)
                gap += np.maximum(points[found.outside] - self.grid.upper, 0.0)
                distance = np.linalg.norm(gap, axis=1)
                if self.settings.outside == "clamp":
                    v.flag(found.outside, F_CLAMPED, "clamp", distance)
                else:
                    v.refuse(found.outside, OUTSIDE_GRID, distance)
            if found.angle is not None:
                angle = np.nan_to_num(found.angle)
                beyond = angle > self.orientation_limit_deg
                if self.calibrated is None and not self.allow_orientation:
                    v.refuse(np.flatnonzero(beyond), ORIENTATION, angle[beyond])
                far = np.flatnonzero(angle > self.orientation_tol_deg)
                v.flag(far, F_ORIENTATION, "angle", angle[far])
            if self.grid_status is not None and own is not None:
                other = np.flatnonzero((own >= 0) & (own != self.grid_status))
                v.refuse(other, STATUS, own[other].astype(float))
            if self.calibrated is None:
                v.command[:] = found.command
        if self.calibrated is not None and n:
            self._by_model(v, rotations, own)
        length = np.linalg.norm(v.command - points, axis=1)
        limit = self.settings.max_correction_mm
        if limit is not None:
            over = np.flatnonzero((v.code == CORRECTED) & (length > limit))
            v.refuse(over, TOO_LONG, length[over])
        v.command[v.code != CORRECTED] = points[v.code != CORRECTED]
        v.length = np.where(v.code == CORRECTED, length, 0.0)
        self._assess(v)
        return v

    def _assess(self, v: Verdict) -> None:
        """The error budget of the corrected positions (``compensation.budget``): the model's
        (and the grid's) where the model corrected, the DH-only fallback's own where it did;
        those beyond ``max_u95_mm`` flagged."""
        at = np.flatnonzero(v.code == CORRECTED)
        by_fallback = (v.flags[at] & F_SUPPORT) != 0
        own, fallback = at[~by_fallback], at[by_fallback]
        model = None
        if self.budget.model is not None and v.joints is not None:
            model = self.budget.model.covariance(v.joints[own])
        self.budget.assess(v.numbers, len(v), own, v.points[own], self.grid, model)
        if fallback.size:
            own_term = ModelBudget.of_fallback(self.validity.support)
            term = None if own_term is None else own_term.covariance(v.joints[fallback])
            self.budget.assess(v.numbers, len(v), fallback, v.points[fallback], None, term)
        if self.max_u95_mm is not None:
            u95 = v.numbers["u95"][at]
            over = np.flatnonzero(u95 > self.max_u95_mm)
            v.flag(at[over], F_BUDGET, "u95", u95[over])

    def decide_tool(
        self,
        number: int,
        flange_T_tool: np.ndarray,
        points: np.ndarray,
        rotations: np.ndarray | None = None,
        status: int | np.ndarray | None = None,
    ) -> Verdict:
        """``decide`` for targets P (N, 3) mm robot frame of tool ``number`` (TCP
        ``flange_T_tool`` (4, 4) mm), their rotations (N, 3, 3) that tool's frame (NaN rows:
        none) and Status; the module docstring says when another tool than ``tool`` is
        corrected."""
        own = self.tool if self.tool is not None else self.controller_tool
        tool = np.asarray(flange_T_tool, dtype=float)
        if own is not None and np.array_equal(tool, own):
            return self.decide(points, rotations, status=status)
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        n = len(points)
        distance = np.inf if own is None else float(np.linalg.norm(tool[:3, 3] - own[:3, 3]))
        near = distance <= self.settings.tool_distance_mm
        if self.calibrated is not None:
            grid = self.grid if near else None
            mine = replace(self, grid=grid, controller_tool=tool, arm_tool=tool, tool=tool)
            verdict = mine.decide(points, rotations, status=status)
            if grid is None and self.grid is not None:
                verdict.flag(np.flatnonzero(verdict.corrected), F_TOOL, "tool_mm", distance)
        elif near:  # the grid's tool at the same flange pose: its orientation for the check
            if rotations is not None and own is not None:
                rotations = rotations @ (tool[:3, :3].T @ own[:3, :3])
            verdict = self.decide(points, rotations, status=status)
        else:
            verdict = Verdict(self, points, points.copy(), np.zeros(n, np.int8), np.zeros(n))
            verdict.refuse(np.arange(n), OTHER_TOOL, np.full(n, distance))
        verdict.numbers["tool"] = np.full(n, float(number))
        return verdict

    def _statuses(self, status, n: int) -> np.ndarray | None:
        """Each position's Status (N,) (-1: none), or None when neither it nor the job has one."""
        if status is None and self.status is None:
            return None
        own = np.full(n, -1 if status is None else 0, np.int64)
        if status is not None:
            own[:] = np.broadcast_to(np.asarray(status, dtype=np.int64), (n,))
        if self.status is not None:
            own[own < 0] = self.status
        return own

    def _commands(self, v: Verdict, model, grid, rows: np.ndarray, rotations, own):
        """``model``'s commands (with ``grid``, its residual grid, or None) for the positions
        ``rows`` (k,) at their ``rotations`` and Status ``own``: set where it lands them, refused
        as not reachable or not converging where not; the ``model_correct`` result (k rows)."""
        from accugrid.kinematics.frames import matrix_to_abc  # model jobs only

        status = None if own is None else own[rows]
        abc = matrix_to_abc(rotations[rows]).reshape(-1, 3)
        result = model_correct(
            model,
            v.points[rows],
            abc,
            status,
            grid,
            self.settings,
            controller_tool=self.controller_tool,
            arm_tool=self.arm_tool,
        )
        v.numbers.setdefault("miss", np.full(len(v.points), np.nan))[rows] = result.miss_mm
        failed = result.failed
        if failed.size:
            converging = np.char.startswith(result.reason[failed].astype(str), "no convergence")
            code = np.where(converging, NO_CONVERGENCE, UNREACHABLE)
            for c in (UNREACHABLE, NO_CONVERGENCE):
                at = failed[code == c]
                got = -1.0 if status is None else status[at].astype(float)
                v.refuse(rows[at], c, np.broadcast_to(got, at.shape).astype(float))
                v.why[rows[at]] = result.reason[at]
        v.command[rows[result.ok]] = result.command[result.ok]
        return result

    def _by_model(self, v: Verdict, rotations: np.ndarray | None, own: np.ndarray | None) -> None:
        """The model's commands for the positions still corrected, the joints' flags."""
        n = len(v.points)
        if rotations is None:
            rotations = np.full((n, 3, 3), np.nan)
        oriented = np.isfinite(rotations.reshape(n, 9)).all(axis=1)
        v.refuse(np.flatnonzero(~oriented), NO_ORIENTATION, np.zeros((~oriented).sum()))
        if own is not None:  # never a Status the robot may not be in
            unknown = np.flatnonzero(own < 0)
            v.refuse(unknown, NO_STATUS, np.full(unknown.size, -1.0))
        todo = np.flatnonzero(v.code == CORRECTED)
        if not todo.size:
            return
        result = self._commands(v, self.calibrated, self.grid, todo, rotations, own)
        done = todo[result.ok]
        q = result.q[result.ok]  # the controller's joints at the final commands
        v.joints = np.full((n, 6), np.nan)
        v.joints[done] = q
        a5 = singular_a5_deg(q)
        near = np.flatnonzero(a5 < self.singular_deg)
        v.flag(done[near], F_SINGULAR, "a5", a5[near])
        if self.validity is not None:
            box, tilt, joint, axis = self.validity.excess(v.points[done], rotations[done], q)
            out = np.flatnonzero((box > 0) | (tilt > 0) | (joint > 0))
            for key, values in (("box", box), ("tilt", tilt), ("joint", joint), ("axis", axis)):
                v.numbers.setdefault(key, np.zeros(n))[done] = values
            if self.strict:
                v.refuse(done[out], OUTSIDE_MODEL, box[out])
            else:
                v.flag(done[out], F_REGION, "box", box[out])
            if self.validity.support is not None:
                self._by_fallback(v, done, q, rotations, own)

    def _by_fallback(self, v: Verdict, done, q, rotations, own) -> None:
        """Positions ``done`` (k,) corrected by the model at the controller's joints q (k, 6)
        rad: those without its support flagged and corrected by its DH-only fallback (the
        residual grid, the full model's, not added), or refused with ``strict``."""
        support = self.validity.support
        ratio = support.ratio(q)
        v.numbers.setdefault("support", np.zeros(len(v.points)))[done] = ratio
        out = done[ratio > 1.0]
        if self.strict:
            v.refuse(out, NO_SUPPORT, ratio[ratio > 1.0])
            return
        out = out[v.code[out] == CORRECTED]
        if not out.size:
            return
        result = self._commands(v, support.fallback, None, out, rotations, own)
        v.joints[out[result.ok]] = result.q[result.ok]
        v.flag(out[result.ok], F_SUPPORT, "support", v.numbers["support"][out[result.ok]])


@dataclass
class Verdict:
    """``Policy.decide`` for N targets: points and commands (N, 3) mm robot frame (the target
    where not corrected), code (N,) int8 (``CORRECTED`` or a ``REASONS`` key), value (N,) the
    number of the code's words, flags (N,) uint8 (``FLAGS`` bits), why (N,) object (the IK's
    words), length (N,) |P' - P| mm (0 where not corrected), the flags' numbers by name
    (N,) each (the error budget's too: ``sigma_x``, ``sigma_y``, ``sigma_z``, ``u95`` mm) and
    the controller's joints (N, 6) rad where a model corrected (None: no model; NaN rows)."""

    policy: Policy
    points: np.ndarray
    command: np.ndarray
    code: np.ndarray
    value: np.ndarray
    flags: np.ndarray = field(default=None)
    why: np.ndarray = field(default=None)
    length: np.ndarray = field(default=None)
    numbers: dict[str, np.ndarray] = field(default_factory=dict)
    joints: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = len(self.code)
        self.flags = np.zeros(n, np.uint8) if self.flags is None else self.flags
        self.why = np.full(n, "", dtype=object) if self.why is None else self.why
        self.length = np.zeros(n) if self.length is None else self.length

    def __len__(self) -> int:
        return len(self.code)

    def refuse(self, at: np.ndarray, code: int, value: np.ndarray) -> None:
        """Positions ``at`` (k,) not corrected for ``code`` (the first reason found stays)."""
        at = np.asarray(at, dtype=np.int64)
        fresh = self.code[at] == CORRECTED
        self.code[at[fresh]] = code
        self.value[at[fresh]] = np.asarray(value, dtype=float)[fresh]

    def flag(self, at: np.ndarray, bit: int, name: str, values: np.ndarray) -> None:
        """Positions ``at`` (k,) flagged with ``bit``, their number ``values`` (k,) as ``name``."""
        at = np.asarray(at, dtype=np.int64)
        self.flags[at] |= bit
        self.numbers.setdefault(name, np.zeros(len(self.code)))[at] = values

    @property
    def corrected(self) -> np.ndarray:
        """(N,) bool."""
        return self.code == CORRECTED

    @property
    def refused(self) -> np.ndarray:
        """Indices (M,) of the positions not corrected."""
        return np.flatnonzero(self.code != CORRECTED)

    def reason(self, i: int, bits: int = 0xFF) -> str:
        """The words of position i: why it is not corrected, else its flags among ``bits``
        ("" for none)."""
        words = self._words()
        words["value"], words["why"] = float(self.value[i]), self.why[i]
        for k, a in self.numbers.items():
            words[k] = float(a[i])
        code = int(self.code[i])
        if code == OUTSIDE_MODEL or (code == CORRECTED and self.flags[i] & bits & F_REGION):
            words["region"] = self._region(i)
        if code != CORRECTED:
            return REASONS[code][1].format_map(words)
        flags = int(self.flags[i]) & bits
        return "; ".join(t.format_map(words) for bit, t in FLAGS.items() if flags & bit)

    def _words(self) -> dict:
        """The words every position shares (made once per verdict), a fresh copy."""
        if "_shared" not in self.__dict__:
            p = self.policy
            abc = None if p.grid is None else p.grid.orientation_abc
            self.__dict__["_shared"] = {
                "grid": p.grid_name,
                "grid_abc": "" if abc is None else ", ".join(f"{a:.3f}" for a in abc),
                "grid_status": p.grid_status,
                "limit": p.orientation_limit_deg,
                "max": p.settings.max_correction_mm or 0.0,
                "singular": p.singular_deg,
                "tool_distance": p.settings.tool_distance_mm,
                "max_u95": p.max_u95_mm or 0.0,
                "region": "",
            }
        return dict(self.__dict__["_shared"])

    def flag_lines(self, label, what: str = "position") -> list[str]:
        """One line per kind of flag among the corrected positions: how many, and the words
        of the first (``label(i)`` names it)."""
        out = []
        for bit in FLAGS:
            at = np.flatnonzero(((self.flags & bit) != 0) & (self.code == CORRECTED))
            if at.size:
                i = int(at[0])
                out.append(f"{at.size} {what}(s) flagged, first {label(i)}: {self.reason(i, bit)}")
        return out

    def _region(self, i: int) -> str:
        parts = []
        box, tilt, joint = (self.numbers.get(k) for k in ("box", "tilt", "joint"))
        if box is not None and box[i] > 0:
            parts.append(f"{box[i]:.1f} mm from their region")
        if tilt is not None and tilt[i] > 0:
            parts.append(f"tool tilt {tilt[i]:.1f} deg beyond theirs")
        if joint is not None and joint[i] > 0:
            parts.append(f"A{int(self.numbers['axis'][i])} {joint[i]:.1f} deg beyond its range")
        return ", ".join(parts)

    def reasons(self) -> list[str]:
        """The words of every position (N), "" where there are none."""
        out = [""] * len(self)
        for i in np.flatnonzero((self.code != CORRECTED) | (self.flags != 0)).tolist():
            out[i] = self.reason(i)
        return out

    def counts(self) -> str:
        """The refused positions counted by reason: "19 outside the grid, 2 not reachable"."""
        codes, count = np.unique(self.code[self.code != CORRECTED], return_counts=True)
        return ", ".join(
            f"{c} {REASONS[int(k)][0]}" for k, c in zip(codes.tolist(), count.tolist(), strict=True)
        )

    def enforce(self, label, where, allow_partial: bool, what: str = "position") -> list[str]:
        """The job rule. InputError (at ``where(i)``, naming ``label(i)``) for a correction
        beyond the safety limit (always: the whole job is suspect) and, unless
        ``allow_partial``, for any position not corrected, with the counts by reason; else the
        lines to print on stderr about the positions left uncorrected (none: [])."""
        over = np.flatnonzero(self.code == TOO_LONG)
        if over.size:
            i = int(over[np.argmax(self.value[over])])
            raise InputError(
                f"{label(i)}: {self.reason(i)}; refusing the whole job (check the grid, the "
                "model, the tool and the base frame)",
                *where(i),
            )
        over = np.flatnonzero(((self.flags & F_BUDGET) != 0) & (self.code == CORRECTED))
        if over.size and not allow_partial:
            i = int(over[np.nanargmax(self.numbers["u95"][over])])
            raise InputError(
                f"{over.size} {what}(s) beyond the largest 95 % bound; the worst {label(i)}: "
                f"{self.reason(i, F_BUDGET)} (--allow-partial writes them corrected and flagged)",
                *where(i),
            )
        refused = self.refused
        if not refused.size:
            return []
        i = int(refused[0])
        text = f"{refused.size} {what}(s) cannot be corrected ({self.counts()})"
        if not allow_partial:
            fix = FIXES.get(
                int(self.code[i]), "--allow-partial writes the job with them uncorrected and marked"
            )
            raise InputError(f"{text}; first {label(i)}: {self.reason(i)} ({fix})", *where(i))
        lines = [f"{text}: written uncorrected (--allow-partial)"]
        lines += [f"  {label(int(k))}: {self.reason(int(k))}" for k in refused[:_LISTED]]
        if refused.size > _LISTED:
            lines.append(f"  ... and {refused.size - _LISTED} more")
        return lines


def _grid_status(grid: GridModel | None, solver: Robot | None) -> tuple[int | None, str]:
    """The Status a grid holds in and where it comes from: its column s; else the IK Status at
    its origin and a,b,c by ``solver`` (a robot with the tool it was measured with); else None
    (not checked)."""
    if grid is None:
        return None, ""
    if grid.status is not None:
        return grid.status, "recorded in its measurement, column s"
    if solver is None or grid.orientation_abc is None:
        return None, ""
    from accugrid.kinematics.simulation import grid_status  # model jobs only

    try:
        found = grid_status(solver, grid.origin, grid.orientation_abc)
    except InputError:  # the origin unreachable: no Status to check against
        found = None
    if found is None:
        return None, ""
    return found, "not recorded in its measurement: the IK Status at its origin"


def _first_status(solver: Robot, points, abc_deg, turn) -> int | None:
    """The IK default Status at the first of ``points`` (None if none or unreachable)."""
    if points is None or not len(points):
        return None
    from accugrid.kinematics.simulation import commanded_poses  # model jobs only

    abc = np.asarray(abc_deg, dtype=float).reshape(-1, 3)
    first = solver.ik(commanded_poses(np.asarray(points)[:1], abc[0]), turn=turn)
    return int(first.status[0]) if first.ok[0] else None
