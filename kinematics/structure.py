"""Choosing the joint-error structure of a calibrated model from the measurements.

The candidates (``kinematics.candidates``) are groups of linear parameters: reducer harmonics (axis,
order 1..K) and the mass-free gravity parts of every axis gravity loads. By default (method "ard")
step 2-3 below is replaced by group sparse Bayesian learning over every candidate at once
(``kinematics.sparse_bayes``: each group's prior precision by maximum evidence, each group paying
log m of evidence for being the best of m; its curve adds the groups kept, largest effect first,
scored by the same cross-validation): near-alias orders share the evidence instead of a greedy step
committing to one. The groups it keeps are then **pruned by joint range** (``range_prune``): each
joint's range of the poses is cut in ``RANGE_BLOCKS`` contiguous blocks, each block held out in turn
and predicted from the rest (every joint in turn, pooled), and the group whose removal most lowers
that held-out error is dropped, while one does. Random folds test poses drawn like
the calibration poses; these test a term where one joint leaves the range it was fitted on: a
reducer harmonic or a gravity term is a function of the joints that holds there, a term that
only fits the poses' own joint combinations (on a real arm: effects no candidate describes)
misses there, often by far more than the DH-only fit. The chosen model is scored the same way
against the DH + TCP model (``Selection.carry_over``, reported). Method "search"
(``--structure search``):

1. Fit DH errors + TCP (+ the tracker frame, ``--compliance`` with masses and the pinned
   harmonics, which are always kept) with the full nonlinear model; linearise there: residuals y,
   the identifiable base columns X and every candidate's columns, computed once.
2. **Grouped forward selection by K-fold cross-validation over the distinct poses** (repeats in
   one fold): each step adds the group whose least-squares fit (X and the groups so far refitted
   in every fold, by QR updates) gives the smallest held-out sum of squares; a group whose
   columns lie within ``SEPARATE`` (a harmonic) or ``SEPARATE_GRAVITY`` (a gravity group) of the
   current model's span on the data (relative singular value) cannot be told apart by these
   poses and is skipped; the path stops when no group
   lowers the held-out error, at ``MAX_SHARE`` of a fold's equations in parameters or after
   ``MAX_STEPS`` steps.
3. **Keep steps while they beat their own uncertainty**: a step is kept when its held-out gain
   (paired per-pose differences of the sums of squares) exceeds its standard error times a bar
   that accounts for the step being the best of m candidate groups: the one-sided normal
   quantile of ``FALSE_STEP`` / m (Bonferroni; 3.3 for m = 100). A step that fails may be
   carried by the next 2..``LOOK_AHEAD`` steps together when their joint gain passes the same
   bar (terms that only help together, e.g. neighbouring orders on a narrow angle range). With a
   bar of one or two standard errors noise-only data gained terms: the best of ~100 candidates
   is always a little lucky.
   Then each kept harmonic is swapped for a neighbouring order of its axis (k ± 1, 2) where that
   lowers the held-out error: over a narrow angle range neighbouring orders differ by a fraction
   of a period and the greedy step may take the wrong one.
   **Second pass** (up to ``SECOND_PASSES`` rounds, after the screened orders below): drop the
   groups whose removal lowers the held-out error, exchange groups one for one (any offered
   group of the same size) while that lowers it, and continue the path from there (steps clear
   their bar again; dropped groups are not offered back). A forward path never steps back: an
   early group that later ones made redundant, or one order standing in for two true ones,
   stays without it.
4. **Nested cross-validation** for the accuracy to expect: in each outer fold the whole search
   (steps 2-3, on inner folds of the training poses) is repeated, the chosen groups are fitted
   on the training poses and the held-out poses are predicted; so the estimate is not the score
   the selection minimised. With repeated poses, the row noise (pooled scatter of the repeats)
   is removed from the held-out RMS to give the model's own error.
5. The chosen groups are fitted with the full nonlinear model (``identification.identify``).

K (the highest harmonic order of the library) defaults to ``DEFAULT_MAX_ORDER`` clamped to what
the poses resolve: an order's period 2π/k must span ``GAPS_PER_PERIOD`` median gaps between the
sorted angles of the distinct poses on every axis. Higher orders (reducer stages of 40..160) are
not excluded: irregular samples alias only approximately, so a few sparse high orders can be
identified. A **screen** before step 2 offers them: a greedy periodogram of the DH fit's
residuals (beyond DH, TCP and the gravity groups) over every (axis, order 1..π / the smallest
gap between the axis's angles, at most ``SCREEN_MAX_ORDER``), ``SCREEN_PICKS_PER_KEPT`` picks
per order kept, each deflating what it explains, keeps the first picks beyond K per axis (one
per ``POSES_PER_SCREENED`` distinct poses, at least ``SCREEN_KEEP``: ``screen_keep``) as
candidates. Such a candidate is the best of a pool of hundreds, so its step must pass the bar
of that whole pool (Bonferroni over library + pool). The library's search (steps 2-3) runs
first; then it continues from there with the screened orders offered too, and those it keeps
are swapped for a neighbouring order where that lowers the held-out error. The screen sees all
poses, also in the nested estimate (it only proposes; the choice is made in the folds).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np
from scipy.linalg import solve_triangular
from scipy.stats import norm

from accugrid.infra.blas import one_blas_thread
from accugrid.infra.errors import InputError
from accugrid.kinematics.candidates import GravityTerm, gravity_terms, harmonic_name
from accugrid.kinematics.identification import (
    Identification,
    PoseSet,
    Terms,
    identify,
    linearised,
    planned_columns,
    pose_folds,
)
from accugrid.kinematics.robot import Robot
from accugrid.kinematics.sparse_bayes import ard_choice

__all__ = [
    "DEFAULT_MAX_ORDER",
    "GAPS_PER_PERIOD",
    "MAX_SHARE",
    "FALSE_STEP",
    "LOOK_AHEAD",
    "MAX_STEPS",
    "SCREEN_KEEP",
    "POSES_PER_SCREENED",
    "SCREEN_PICKS_PER_KEPT",
    "SCREEN_MAX_ORDER",
    "SECOND_PASSES",
    "SEPARATE",
    "SEPARATE_GRAVITY",
    "STRUCTURE_WORD",
    "SELECTION",
    "ArdSelection",
    "ForwardSearch",
    "SelectionStrategy",
    "RANGE_BLOCKS",
    "CarryOver",
    "Nested",
    "Selection",
    "Step",
    "identify_structure",
    "max_order_of",
    "observability",
    "screen_keep",
    "screen_limit",
]

# each selection method of ``identify_structure`` and the ``--structure`` word that asks for it
# (the calibrated YAML's ``identification.structure.mode``)
STRUCTURE_WORD = {"ard": "auto", "search": "search"}

DEFAULT_MAX_ORDER = 16  # reducer output stages; a user may search further with --max-order
GAPS_PER_PERIOD = 4.0  # an order's period must span this many median gaps between pose angles
SEPARATE = 0.05  # a harmonic whose columns keep less than this share beyond the model: inseparable
SEPARATE_GRAVITY = 0.02  # the same for a gravity group (few, physical, large torques)
SECOND_PASSES = 3  # rounds of dropping, exchanging and continuing after the path
MAX_SHARE = 0.5  # parameters at most this share of a training fold's equations
MAX_STEPS = 40  # groups one search adds at most
FALSE_STEP = 0.05  # chance that a step on noise alone passes the bar (shared by the candidates)
LOOK_AHEAD = 4  # a step that fails may be carried by the next 2..LOOK_AHEAD steps together
SCREEN_MAX_ORDER = 200  # the highest order the periodogram screens (reducer stages up to ~160)
SCREEN_KEEP = 3  # orders beyond the library an axis's periodogram adds as candidates, at least
POSES_PER_SCREENED = 32  # and one per this many distinct poses where that is more
SCREEN_PICKS_PER_KEPT = 10  # picks of the greedy periodogram (low and high orders) per kept order
RANGE_BLOCKS = 5  # the carry-over check holds out each joint's range in this many blocks in turn
_NESTED_SEED = 1  # inner folds: another permutation of the training poses
_FIRST_ORDERS = tuple((axis, 1) for axis in range(1, 7))  # sin, cos give each joint's column


@dataclass(frozen=True)
class Step:
    """One point of the cross-validation curve: the group ``added`` ('' for the start), the
    linear parameters then fitted, held-out RMS and max |.| per axis (3,) mm and overall RMS."""

    added: str
    parameters: int
    rms_mm: np.ndarray
    max_mm: np.ndarray
    score_mm: float


@dataclass(frozen=True)
class Nested:
    """Nested cross-validation: held-out (measured − model) RMS and max per axis (3,) mm, the row
    noise sigma mm per axis from the repeats (None without repeats) and the model's own RMS (3,)
    mm with that noise removed (None without repeats); ``chosen``: the groups of each outer fold."""

    folds: int
    rms_mm: np.ndarray
    max_mm: np.ndarray
    noise_mm: float | None
    model_rms_mm: np.ndarray | None
    chosen: tuple[tuple[str, ...], ...]


@dataclass(frozen=True)
class CarryOver:
    """Held out by joint range: each moving joint's range in ``RANGE_BLOCKS`` contiguous blocks
    of the sorted angles, each block held out in turn (the poses of one part of that joint's range
    predicted from the others), pooled over the joints: RMS per axis (3,) mm of the chosen model
    and of the DH + TCP (+ pinned) model on the same folds. Random folds test poses drawn like the
    calibration poses; these test the model where its terms must extrapolate in one joint."""

    rms_mm: np.ndarray
    dh_rms_mm: np.ndarray

    @property
    def holds(self) -> bool:
        """The chosen model does no worse than DH + TCP held out by joint range."""
        return float(np.sum(self.rms_mm**2)) <= float(np.sum(self.dh_rms_mm**2))


@dataclass(frozen=True)
class Selection:
    """What the search chose: ``pinned`` group names (kept, not searched), ``chosen`` in the
    order added, the fitted ``harmonics`` (pinned + chosen) and ``gravity`` groups, the
    cross-validation ``curve`` (start, every step of the path; ``kept`` steps chosen), what was
    ``left_out`` ((name, reason) pairs), the highest order searched and why, the nested
    estimate and the ``carry_over`` check (``CarryOver``)."""

    pinned: tuple[str, ...]
    chosen: tuple[str, ...]
    harmonics: Terms
    gravity: tuple[GravityTerm, ...]
    curve: tuple[Step, ...]
    kept: int
    left_out: tuple[tuple[str, str], ...]
    max_order: int
    max_order_rule: str
    folds: int
    candidates: int
    nested: Nested | None
    method: str = "ard"  # how the groups were chosen: "ard" or "search" (``identify_structure``)
    carry_over: CarryOver | None = None  # the chosen model held out by joint range


def max_order_of(q: np.ndarray) -> np.ndarray:
    """The highest harmonic order (6,) the distinct poses' joints q (P, 6) rad resolve on each
    axis: an order's period must span ``GAPS_PER_PERIOD`` median gaps between the sorted angles
    on that axis (1 for an axis the poses do not move)."""
    return np.array(
        [
            max(int(2 * np.pi / (GAPS_PER_PERIOD * float(np.median(g)))), 1) if g.size else 1
            for g in _angle_gaps(q)
        ]
    )


def screen_limit(q: np.ndarray) -> np.ndarray:
    """The highest order (6,) the periodogram screens per axis for distinct poses' joints q (P, 6)
    rad: π over the smallest gap between the sorted angles (finer periods alias even on
    irregular samples), at most ``SCREEN_MAX_ORDER`` (0 for an axis the poses do not move)."""
    return np.array(
        [
            min(int(np.pi / float(g.min())), SCREEN_MAX_ORDER) if g.size else 0
            for g in _angle_gaps(q)
        ]
    )


def screen_keep(poses: int) -> int:
    """Orders beyond the library the periodogram offers per axis for ``poses`` distinct poses:
    one per ``POSES_PER_SCREENED`` poses, at least ``SCREEN_KEEP`` (the screened orders' 2 × 6
    parameters per ``POSES_PER_SCREENED`` poses stay an eighth of their 3 equations each)."""
    return max(SCREEN_KEEP, poses // POSES_PER_SCREENED)


def range_folds(q: np.ndarray, blocks: int = RANGE_BLOCKS) -> list[np.ndarray]:
    """Per joint that the distinct poses' joints q (P, 6) rad move, the fold (P,) of each pose:
    its joint's range in ``blocks`` contiguous blocks of the sorted angles (equal counts)."""
    out = []
    for axis in range(q.shape[1]):
        if np.ptp(q[:, axis]) <= 1e-9:
            continue
        rank = np.argsort(np.argsort(q[:, axis], kind="stable"), kind="stable")
        out.append(rank * blocks // len(q))
    return out


def _angle_gaps(q: np.ndarray) -> list[np.ndarray]:
    """Per axis the gaps (rad) > 0 between the sorted angles of joints q (P, 6) rad."""
    gaps = np.diff(np.sort(q, axis=0), axis=0)
    return [gaps[:, axis][gaps[:, axis] > 1e-9] for axis in range(6)]


def _screen(y, base, joint, angle, caps, last, keep: int) -> list[tuple[int, int]]:
    """Harmonics beyond the library (orders caps[axis]+1..last[axis] (6,)) that a greedy
    periodogram of the residuals y (M,) mm picks: beyond the columns ``base`` (M, r) (DH, TCP,
    gravity), each pick is the (axis, order) of orders 1..last whose two columns, on the joint's
    column joint (M, 6) mm/rad at the rows' angles (M, 6) rad, remove most of what is left; picks
    are deflated, so a low order taken first no longer leaks into the high ones and a peak's
    neighbours lose what it explained; ``SCREEN_PICKS_PER_KEPT`` × ``keep`` picks. The first
    ``keep`` high orders per axis, sorted."""
    q_, _ = np.linalg.qr(base)
    terms = [(a + 1, k) for a in range(6) for k in range(1, int(last[a]) + 1)]
    if not terms:
        return []
    axis = np.array([t[0] - 1 for t in terms])
    order = np.array([t[1] for t in terms], dtype=float)
    phase = angle[:, axis] * order  # (M, G)
    rest = joint[:, axis, None] * np.stack([np.sin(phase), np.cos(phase)], axis=2)  # (M, G, 2)
    rest /= np.sqrt(np.mean(rest**2, axis=0)) + 1e-300
    own = np.einsum("mgi,mgi->gi", rest, rest)  # each column's size before the base takes its share
    flat = rest.reshape(len(y), -1)  # (M, 2G)
    flat = flat - q_ @ (q_.T @ flat)
    rest = flat.reshape(rest.shape)
    left = y - q_ @ (q_.T @ y)
    # each pick deflates every pair by its two directions u: the Gram matrices and right-hand
    # sides are downdated by uᵀ·rest (u is orthogonal to the picks before, so uᵀ of the columns
    # as first projected is uᵀ of the deflated ones); only the pick's own pair is deflated fully
    gram = np.einsum("mgi,mgj->gij", rest, rest)
    rhs = (flat.T @ left).reshape(-1, 2)
    taken = np.zeros((len(y), 0))
    picked: list[tuple[int, int]] = []
    found = np.zeros(6, dtype=int)
    for _ in range(SCREEN_PICKS_PER_KEPT * keep):
        # a pair whose columns keep less than SEPARATE of their own size beyond the base and the
        # picks has nothing left to give (what is left of it is rounding, which BLAS kernels and
        # thread counts do differently)
        alive = np.linalg.eigvalsh(gram)[:, 0] > SEPARATE**2 * own.max(axis=1)
        safe = np.where(alive[:, None, None], gram, np.eye(2))
        gain = np.einsum("gi,gi->g", rhs, np.linalg.solve(safe, rhs[:, :, None])[:, :, 0])
        gain[~alive] = -np.inf
        best = int(np.argmax(gain))
        if not np.isfinite(gain[best]):
            break
        v = rest[:, best] - taken @ (taken.T @ rest[:, best])
        u, _ = np.linalg.qr(v - taken @ (taken.T @ v))  # (M, 2): twice, or u drifts off ⊥ taken
        cut = (u.T @ flat).reshape(2, -1, 2)  # (2, G, 2)
        along = u.T @ left
        gram -= np.einsum("jgi,jgk->gik", cut, cut)
        rhs -= np.einsum("jgi,j->gi", cut, along)
        left -= u @ along
        taken = np.column_stack([taken, u])
        a, k = terms[best]
        if k > caps[a - 1] and found[a - 1] < keep:
            picked.append((a, k))
            found[a - 1] += 1
    return sorted(picked)


def observability(robot: Robot, q: np.ndarray) -> tuple[np.ndarray, list[tuple[str, str]]]:
    """Before measuring: the highest order (6,) joints q (P, 6) rad resolve per axis, and the
    candidate groups (orders up to ``DEFAULT_MAX_ORDER`` clamped to those, the gravity groups)
    these poses cannot tell from the DH errors and TCP: (name, reason)."""
    caps = np.minimum(max_order_of(q), DEFAULT_MAX_ORDER)
    search = tuple((a, k) for a in range(1, 7) for k in range(1, int(caps[a - 1]) + 1))
    gravity = gravity_terms(robot)
    x0, columns = planned_columns(robot, q, search, gravity)
    names, groups = _library(search, gravity)
    problem = _Problem(
        np.zeros(len(x0)), x0, columns, groups, np.repeat(np.arange(len(q)), 3), len(q)
    )
    problem.separate[len(search) :] = SEPARATE_GRAVITY
    return caps, problem.reduce(names)


def identify_structure(
    robot: Robot,
    data: PoseSet,
    *,
    base_frame: bool = False,
    compliance: bool = False,
    harmonics: Terms = (),
    max_order: int | None = None,
    folds: int = 5,
    nested: bool = True,
    method: str = "ard",
) -> tuple[Identification, Selection]:
    """Choose the joint-error groups from the data (module docstring) and fit them.

    ``harmonics`` and ``compliance`` (with the robot's masses) are pinned: always in the model.
    ``max_order``: the highest order searched (default: ``DEFAULT_MAX_ORDER`` clamped to what the
    poses resolve, with the reason in ``Selection.max_order_rule``; a larger one given is refused
    naming the limit). ``folds`` >= 2: the cross-validation folds (also the nested estimate's outer
    folds). ``method``: "ard" (the default: group sparse Bayesian learning over the same candidates,
    ``sparse_bayes``: every group's prior precision by maximum evidence, each paying log m; the
    groups kept are fitted as the search's are) or "search" (forward selection, module docstring).
    InputError for too few poses, a bad ``max_order`` or ``folds``."""
    if method not in SELECTION:
        raise ValueError(f"unknown structure selection method {method!r}")
    with one_blas_thread():  # thousands of small solves: BLAS threads only wait on each other
        return _identify_structure(
            robot, data, base_frame, compliance, harmonics, max_order, folds, nested, method
        )


def _identify_structure(
    robot, data, base_frame, compliance, harmonics, max_order, folds, nested, method
) -> tuple[Identification, Selection]:
    if folds < 2 or folds > data.poses:
        raise InputError(f"--folds must be between 2 and the {data.poses} poses, got {folds}")
    resolved = max_order_of(data.q[np.unique(data.group, return_index=True)[1]])
    rule = f"a period must span {GAPS_PER_PERIOD:g} median gaps between the poses' angles"
    if max_order is None:
        max_order = DEFAULT_MAX_ORDER
    elif not 1 <= max_order <= resolved.max():
        raise InputError(
            f"--max-order {max_order}: these {data.poses} poses resolve harmonic orders 1.."
            f"{resolved.max()} at most (A{int(np.argmax(resolved)) + 1}; {rule}); measure more "
            "poses or lower it",
            data.path,
        )
    caps = np.minimum(resolved, max_order)
    clamped = [f"A{a + 1} to {caps[a]}" for a in range(6) if caps[a] < max_order]
    rule = f"clamped {', '.join(clamped)} ({rule})" if clamped else rule
    base = identify(
        robot, data, base_frame, compliance, harmonics=harmonics, selected=True, folds=0
    )
    pinned = tuple(harmonics)
    search = tuple(
        (axis, order)
        for axis in range(1, 7)
        for order in range(1, int(caps[axis - 1]) + 1)
        if (axis, order) not in pinned
    )
    library = len(search)
    screened: list[tuple[int, int]] = []
    # orders beyond the library: a periodogram of the DH fit's residuals per axis screens
    # caps+1..screen_limit and offers its screen_keep best to the same selection
    last = screen_limit(data.q[np.unique(data.group, return_index=True)[1]])
    first = caps + 1
    pool = int(np.maximum(last - first + 1, 0).sum())
    gravity = gravity_terms(robot)
    if pool:
        y, x0, ones = linearised(
            robot, data, base, base_frame, compliance, pinned, _FIRST_ORDERS, gravity
        )
        angle = np.repeat(data.q, 3, axis=0)
        joint = np.sin(angle) * ones[:, 0:12:2] + np.cos(angle) * ones[:, 1:12:2]  # (M, 6)
        screened = [
            t
            for t in _screen(
                y,
                np.column_stack([x0, ones[:, 12:]]),
                joint,
                angle,
                caps,
                last,
                screen_keep(data.poses),
            )
            if t not in pinned
        ]
        # their neighbouring orders, for the swap only (k149 may be picked for k150)
        nearby = tuple(
            dict.fromkeys(
                (a, k + d)
                for a, k in screened
                for d in (-2, -1, 1, 2)
                if (a, k + d) not in screened and (a, k + d) not in pinned and k + d > caps[a - 1]
            )
        )
        search += tuple(screened) + nearby
        ranges = ", ".join(
            f"A{a} to {last[a - 1]}" for a in range(1, 7) if last[a - 1] > caps[a - 1]
        )
        found = ", ".join(harmonic_name(*t) for t in screened) or "none"
        rule += f"; screened beyond: {ranges} (π / the smallest gap): {found}"
    y, x0, columns = linearised(robot, data, base, base_frame, compliance, pinned, search, gravity)
    names, groups = _library(search, gravity)
    distinct = data.q[np.unique(data.group, return_index=True)[1]]
    problem = _Problem(
        y, x0, columns, groups, np.repeat(data.group, 3), data.poses, joints=distinct
    )
    # a screened order is the best of its axis's whole periodogram: its bar counts that pool
    offered = library + len(screened)
    # the bar of a step: the best of the offered groups; a screened order's, of the whole pool
    problem.bars[:] = norm.isf(FALSE_STEP / (offered + len(gravity)))
    problem.bars[library:offered] = norm.isf(FALSE_STEP / (library + len(gravity) + pool))
    problem.screened[library:offered] = True
    problem.offered[offered : len(search)] = False
    index = {t: i for i, t in enumerate(search)}
    problem.neighbours = {
        i: [index[(a, k + d)] for d in (-2, -1, 1, 2) if (a, k + d) in index]
        for i, (a, k) in enumerate(search)
    }
    problem.separate[len(search) :] = SEPARATE_GRAVITY
    left_out = problem.reduce(names)
    strategy = SELECTION[method]
    fold = pose_folds(data.poses, folds)
    path, kept, chosen = strategy.choose(problem, fold, np.ones(data.poses, bool))
    replaced = [g for g, _ in path[1 : kept + 1] if g not in chosen]
    rejected = [g for g, _ in path[kept + 1 :] if g not in chosen]
    left_out += [
        (names[g], "replaced: held-out error lower without it or with another term instead")
        for g in replaced
    ]
    left_out += [(names[g], "its held-out gain is within its uncertainty") for g in rejected]
    estimate = _nested(problem, strategy, fold, folds, names, data) if nested else None
    carry = problem.carry_over(chosen, range_folds(distinct))
    picked_harmonics = pinned + tuple(search[g] for g in chosen if g < len(search))
    picked_gravity = tuple(gravity[g - len(search)] for g in chosen if g >= len(search))
    result = identify(
        robot,
        data,
        base_frame,
        compliance,
        harmonics=picked_harmonics,
        gravity=picked_gravity,
        selected=True,
    )
    curve = tuple(
        Step(
            "" if g is None else names[g],
            x0.shape[1] + sum(len(problem.groups[c]) for c, _ in path[1 : i + 1]),
            *problem.held_out_stats(held),
        )
        for i, (g, held) in enumerate(path)
    )
    if estimate is not None:  # the model's claim: the nested estimate, not the fit's residual
        result = replace(result, robot=replace(result.robot, validated_max_mm=estimate.max_mm))
    selection = Selection(
        pinned=tuple(harmonic_name(*t) for t in pinned) + (("compliance",) if compliance else ()),
        chosen=tuple(names[g] for g in chosen),
        harmonics=picked_harmonics,
        gravity=picked_gravity,
        curve=curve,
        kept=kept,
        left_out=tuple(left_out),
        max_order=max_order,
        max_order_rule=rule,
        folds=folds,
        candidates=len(names),
        nested=estimate,
        method=method,
        carry_over=carry,
    )
    return result, selection


def _library(search: Terms, gravity: tuple[GravityTerm, ...]):
    """The candidate groups' names and their column indices (harmonics, two columns each, then
    the gravity groups), in the column order of ``linearised`` and ``planned_columns``."""
    names = [harmonic_name(*t) for t in search] + [g.name for g in gravity]
    starts = np.cumsum([0] + [2] * len(search) + [g.size for g in gravity])
    return names, [np.arange(starts[i], starts[i + 1]) for i in range(len(names))]


class _Problem:
    """The linearised search: residuals y (M,), base columns X (M, r), candidate columns C
    (M, m) in groups (index arrays into C), the pose (M,) of each equation."""

    def __init__(
        self, y, x0, columns, groups, pose_of_row, poses: int, *, joints: np.ndarray | None = None
    ) -> None:
        self.y, self.x0, self.c, self.groups = y, x0, columns, groups
        self.pose, self.poses = pose_of_row, poses
        self.neighbours: dict[int, list[int]] = {}  # harmonic group -> neighbouring orders
        self.top = float(np.sqrt(np.mean(columns**2, axis=0)).max()) if columns.size else 1.0
        # a step is the best of len(groups) tries: the one-sided normal bar whose tail
        # FALSE_STEP is shared among them (Bonferroni), 3.3 standard errors for 100 groups
        self.screened = np.zeros(len(groups), bool)  # orders the periodogram offered
        self.offered = np.ones(len(groups), bool)  # False: a screened order's neighbour (swap)
        self.bars = np.full(len(groups), norm.isf(FALSE_STEP / max(len(groups), 1)))
        self.separate = np.full(len(groups), SEPARATE)
        self.joints = joints  # (P, 6) rad of the distinct poses (range pruning), or None

    def reduce(self, names: list[str]) -> list[tuple[str, str]]:
        """Keep of each group only its directions the data separate from the DH + TCP (+ pinned)
        model (relative singular value >= ``SEPARATE`` beyond X); groups left without any, or
        that do not move the TCP, are out: (name, reason)."""
        out = []
        q, _ = np.linalg.qr(self.x0)
        columns, groups = [], []
        start = 0
        for i, g in enumerate(self.groups):
            cols = self.c[:, g]
            norms = np.sqrt(np.mean(cols**2, axis=0))
            if norms.min() <= 1e-9 * self.top:
                out.append((names[i], "does not move the TCP at these poses"))
                groups.append(np.arange(start, start))
                continue
            cols = cols / norms
            rest = cols - q @ (q.T @ cols)
            _, sing, vt = np.linalg.svd(rest, full_matrices=False)
            keep = sing >= self.separate[i] * np.linalg.norm(cols, 2)
            if not keep.any():
                out.append(
                    (
                        names[i],
                        "these poses cannot tell it from the DH errors and TCP (accugrid plan "
                        "identify chooses poses that separate it)",
                    )
                )
            reduced = cols @ vt[keep].T
            reduced /= np.sqrt(np.mean(reduced**2, axis=0))
            columns.append(reduced)
            groups.append(np.arange(start, start + reduced.shape[1]))
            start += reduced.shape[1]
        self.c = np.column_stack(columns) if columns else np.zeros((len(self.y), 0))
        self.groups = groups
        self.size = np.array([len(g) for g in groups])
        self.observable = self.size > 0
        self.pairs = np.array([i for i, g in enumerate(groups) if len(g) == 2], dtype=int)
        self.others = [i for i, g in enumerate(groups) if len(g) not in (0, 2)]
        return out

    def cv_rows(self, fold_of_pose: np.ndarray, use: np.ndarray):
        """Per equation the fold (M,) and whether it is used (M,), and the folds used."""
        return fold_of_pose[self.pose], use[self.pose], np.unique(fold_of_pose[use])

    def design(self, chosen: list[int]) -> np.ndarray:
        if not chosen:
            return self.x0
        cols = np.concatenate([self.groups[g] for g in chosen])
        return np.column_stack([self.x0, self.c[:, cols]])

    def held_out(self, chosen, fold, rows, folds) -> np.ndarray:
        """Held-out residuals (M,) of the model ``chosen`` (NaN outside ``rows``)."""
        held = np.full(len(self.y), np.nan)
        x = self.design(chosen)
        for k in folds:
            train, test = rows & (fold != k), rows & (fold == k)
            beta = np.linalg.lstsq(x[train], self.y[train], rcond=None)[0]
            held[test] = self.y[test] - x[test] @ beta
        return held

    def pose_sse(self, held: np.ndarray) -> np.ndarray:
        ok = ~np.isnan(held)
        return np.bincount(self.pose[ok], held[ok] ** 2, minlength=self.poses)

    def carry_over(self, chosen: list[int], folds_by_joint: list[np.ndarray]) -> CarryOver:
        """``chosen`` and the DH + TCP (+ pinned) model held out by joint range (``CarryOver``):
        each fold of ``folds_by_joint`` (per joint, the fold (P,) of each pose) in turn."""
        every = np.ones(self.poses, bool)
        sse = np.zeros((2, 3))
        for fold_of_pose in folds_by_joint:
            fold, rows, folds = self.cv_rows(fold_of_pose, every)
            for i, model in enumerate((chosen, [])):
                held = self.held_out(model, fold, rows, folds).reshape(-1, 3)
                sse[i] += np.sum(held**2, axis=0)
        count = max(len(folds_by_joint), 1) * (len(self.y) // 3)
        return CarryOver(np.sqrt(sse[0] / count), np.sqrt(sse[1] / count))

    def held_out_stats(self, held: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """(RMS (3,), max |.| (3,), overall RMS) mm of held-out residuals (M,)."""
        per_axis = held.reshape(-1, 3)
        per_axis = per_axis[~np.isnan(per_axis[:, 0])]
        rms = np.sqrt(np.mean(per_axis**2, axis=0))
        return rms, np.abs(per_axis).max(axis=0), float(np.sqrt(np.mean(per_axis**2)))


Choice = tuple[list[tuple[int | None, np.ndarray]], int, list[int]]  # (path, kept, chosen)


class SelectionStrategy(Protocol):
    """How the candidate groups of a linearised problem are chosen."""

    def choose(self, p: _Problem, fold_of_pose: np.ndarray, use: np.ndarray) -> Choice:
        """On the poses ``use`` (P,) bool with cross-validation folds ``fold_of_pose`` (P,):
        (the path: [(group added or None, held-out residuals (M,))], its kept steps, the chosen
        groups)."""
        ...


class ArdSelection:
    """Group sparse Bayesian learning (``sparse_bayes``) over every candidate at once, the groups
    it keeps pruned by joint range (``range_prune``) when the problem knows its poses' joints."""

    def choose(self, p: _Problem, fold_of_pose: np.ndarray, use: np.ndarray) -> Choice:
        """Group ARD on the poses ``use`` (P,) bool (``SelectionStrategy``). The prior against a
        group is log m, m the candidates a step is the best of as its bar counts them (the
        library, or the screen's whole pool); its path adds the groups kept, largest effect
        first."""
        rows = use[p.pose]
        live = p.observable & p.offered
        groups = [g if live[i] else g[:0] for i, g in enumerate(p.groups)]
        penalty = np.log(FALSE_STEP / norm.sf(p.bars))
        y, x, c, floor = self._pose_means(p, rows)
        chosen = ard_choice(y, x, c, groups, None, penalty, floor)[0]
        if p.joints is not None:
            chosen = self.range_prune(p, chosen, use)
        fold, rows, folds = p.cv_rows(fold_of_pose, use)
        path = [
            (chosen[i - 1] if i else None, p.held_out(chosen[:i], fold, rows, folds))
            for i in range(len(chosen) + 1)
        ]
        return path, len(chosen), chosen

    def _pose_means(self, p: _Problem, rows: np.ndarray):
        """The equations ``rows`` (M,) bool averaged over each distinct pose and axis (K of them;
        equation e is axis e % 3 of a row): y (K,), X (K, r), C (K, m), and the variance the
        repeats' own scatter puts in such a mean (pooled; 0 without repeats), a floor for the
        noise of the means. ARD weighs equations as independent: repeats of a pose share its
        joints (identical without logged joints) and its tracker error, so counted one by one
        they would make a pose's error look like evidence; the search keeps them in one fold."""
        key = p.pose * 3 + np.arange(len(p.pose)) % 3
        at = np.flatnonzero(rows)
        at = at[np.argsort(key[at], kind="stable")]
        starts = np.flatnonzero(np.diff(key[at], prepend=-1))
        counts = np.diff(starts, append=len(at))

        def mean(a: np.ndarray) -> np.ndarray:
            sums = np.add.reduceat(a[at], starts, axis=0)
            return sums / counts.reshape(-1, *(1,) * (a.ndim - 1))

        y = mean(p.y)
        scatter = p.y[at] - np.repeat(y, counts)
        dof = int(np.sum(counts - 1))
        floor = float(scatter @ scatter) / dof / float(np.mean(counts)) if dof else 0.0
        return y, mean(p.x0), mean(p.c), floor

    def range_prune(self, p: _Problem, chosen: list[int], use: np.ndarray) -> list[int]:
        """``chosen`` without, one at a time, the group whose removal most lowers the error held
        out by joint range on the poses ``use`` (P,) bool (``range_folds`` of their joints, every
        joint's blocks in turn, pooled), while a removal does: terms that fit the poses only in
        their own joint combinations and miss where one joint leaves its block are dropped. The
        held-out sums come from each fold's normal equations (a removal deletes their rows and
        columns), solved in one batch per trial."""
        if not chosen:
            return chosen
        x = p.design(chosen)
        grams, rhs, held_gram, held_rhs, held_yy = [], [], [], [], 0.0
        for blocks in range_folds(p.joints[use]):
            fold_of_pose = np.full(p.poses, -1)
            fold_of_pose[use] = blocks
            fold, rows, ids = p.cv_rows(fold_of_pose, use)
            for k in ids:
                train, test = rows & (fold != k), rows & (fold == k)
                grams.append(x[train].T @ x[train])
                rhs.append(x[train].T @ p.y[train])
                held_gram.append(x[test].T @ x[test])
                held_rhs.append(x[test].T @ p.y[test])
                held_yy += float(p.y[test] @ p.y[test])
        grams, rhs = np.array(grams), np.array(rhs)
        held_gram, held_rhs = np.array(held_gram), np.array(held_rhs)
        base = p.x0.shape[1]
        starts = np.cumsum([base] + [len(p.groups[g]) for g in chosen])

        def sse(kept: list[int]) -> float:
            cols = np.concatenate(
                [np.arange(base)] + [np.arange(starts[i], starts[i + 1]) for i in kept]
            )
            try:
                w = np.linalg.solve(grams[:, cols][:, :, cols], rhs[:, cols, None])[..., 0]
            except np.linalg.LinAlgError:
                return np.inf
            fitted = np.einsum("fi,fij,fj->", w, held_gram[:, cols][:, :, cols], w)
            return held_yy - 2 * float(np.einsum("fi,fi->", w, held_rhs[:, cols])) + fitted

        kept = list(range(len(chosen)))
        best = sse(kept)
        while kept:
            trials = [sse(kept[:i] + kept[i + 1 :]) for i in range(len(kept))]
            at = int(np.argmin(trials))
            if not trials[at] < best:
                break
            best = trials[at]
            del kept[at]
        return [chosen[i] for i in kept]


class ForwardSearch:
    """Grouped forward selection by cross-validation, steps kept while they beat their own
    uncertainty, neighbouring orders swapped in, then a second pass (module docstring)."""

    def choose(self, p: _Problem, fold_of_pose: np.ndarray, use: np.ndarray) -> Choice:
        """The whole search on the poses ``use`` (P,) bool with folds ``fold_of_pose`` (P,): the
        library's path, its kept steps refined (neighbouring orders), then the path on from there
        with the screened orders offered too (their steps must clear the pool's bar), then the
        second pass. Returns (path: start, library steps kept, the continuation; kept steps; the
        chosen groups)."""
        first = self.path(p, fold_of_pose, use, [], p.offered & ~p.screened)
        kept = self.one_standard_error(p, first)
        greedy = [g for g, _ in first[1 : kept + 1]]
        chosen = self.refine(p, greedy, fold_of_pose, use)
        if not p.screened.any():
            return first, kept, self.second_pass(p, chosen, fold_of_pose, use)
        on = self.path(p, fold_of_pose, use, chosen, p.offered)
        more = self.one_standard_error(p, on)
        path = first[: kept + 1] + on[1:]
        added = chosen + [g for g, _ in on[1 : more + 1]]
        chosen = self.refine(p, added, fold_of_pose, use, len(chosen))
        return path, kept + more, self.second_pass(p, chosen, fold_of_pose, use)

    def second_pass(
        self, p: _Problem, chosen: list[int], fold_of_pose: np.ndarray, use: np.ndarray
    ):
        """``chosen`` revisited up to ``SECOND_PASSES`` times on the poses ``use`` (P,) bool with
        folds ``fold_of_pose`` (P,): terms the model no longer needs are dropped, terms are
        exchanged for others (``exchange``), and the path continues from there over the groups
        not dropped (steps must clear their bar again). A forward path never takes a step back:
        an early term that later ones made redundant, or an alias of two true terms, stays."""
        offered = p.offered.copy()
        for _ in range(SECOND_PASSES):
            before = list(chosen)
            changed = self.prune(p, chosen, fold_of_pose, use)
            changed = self.exchange(p, changed, fold_of_pose, use, offered)
            if changed == before:
                break
            offered[[g for g in before if g not in changed]] = False
            on = self.path(p, fold_of_pose, use, changed, offered)
            more = self.one_standard_error(p, on)
            added = changed + [g for g, _ in on[1 : more + 1]]
            chosen = self.refine(p, added, fold_of_pose, use, len(changed))
        return chosen

    def exchange(
        self, p: _Problem, chosen: list[int], fold_of_pose, use, offered: np.ndarray
    ) -> list[int]:
        """``chosen`` with, one at a time, the swap of a chosen group for an ``offered`` (groups,)
        bool group of the same size that most lowers the held-out sum of squares, while one does
        (the model's size stays; each swap is scored by the QR-updated trial of a forward step)."""
        fold, rows, folds = p.cv_rows(fold_of_pose, use)
        chosen = list(chosen)
        best = np.nansum(p.held_out(chosen, fold, rows, folds) ** 2)
        for _ in range(len(chosen)):
            top, swap = best, None
            for at, group in enumerate(chosen):
                allowed = p.observable & offered & (p.size == p.size[group])
                allowed[chosen] = False
                if not allowed.any():
                    continue
                trial = self._trial(p, chosen[:at] + chosen[at + 1 :], allowed, fold, rows, folds)
                other = int(np.argmin(trial))
                if trial[other] < top:
                    top, swap = trial[other], (at, other)
            if swap is None:
                break
            chosen[swap[0]] = swap[1]
            best = top
        return chosen

    def prune(
        self, p: _Problem, chosen: list[int], fold_of_pose: np.ndarray, use: np.ndarray
    ) -> list[int]:
        """``chosen`` without, one at a time, the group whose removal most lowers the held-out sum
        of squares, while a removal does."""
        fold, rows, folds = p.cv_rows(fold_of_pose, use)
        chosen = list(chosen)
        best = np.nansum(p.held_out(chosen, fold, rows, folds) ** 2)
        while chosen:
            trials = [
                np.nansum(p.held_out(chosen[:i] + chosen[i + 1 :], fold, rows, folds) ** 2)
                for i in range(len(chosen))
            ]
            at = int(np.argmin(trials))
            if trials[at] >= best:
                break
            best = trials[at]
            del chosen[at]
        return chosen

    def path(
        self,
        p: _Problem,
        fold_of_pose: np.ndarray,
        use: np.ndarray,
        start: list[int],
        offered: np.ndarray,
    ) -> list[tuple[int | None, np.ndarray]]:
        """Forward selection on the poses ``use`` (P,) bool with folds ``fold_of_pose`` (P,) from
        the groups ``start`` over the groups ``offered`` (groups,) bool: [(group added or None,
        held-out residuals (M,) with NaN off ``use``)], the start first."""
        rows = use[p.pose]
        fold = fold_of_pose[p.pose]
        folds = np.unique(fold_of_pose[use])
        train_eq = min(int(np.sum(rows & (fold != k))) for k in folds)
        chosen = list(start)
        held = p.held_out(chosen, fold, rows, folds)
        path = [(None, held)]
        sse = p.pose_sse(held)
        free = p.observable & offered
        free[chosen] = False
        budget = MAX_SHARE * train_eq - p.x0.shape[1]
        for _ in range(MAX_STEPS):
            used = int(p.size[chosen].sum()) if chosen else 0
            allowed = free & (used + p.size <= budget)
            if not allowed.any():
                break
            trial = self._trial(p, chosen, allowed, fold, rows, folds)
            best = int(np.argmin(trial))
            if not np.isfinite(trial[best]) or trial[best] >= sse.sum():
                break
            chosen.append(best)
            free[best] = False
            held = p.held_out(chosen, fold, rows, folds)
            sse = p.pose_sse(held)
            path.append((best, held))
        return path

    def _trial(self, p: _Problem, chosen, allowed, fold, rows, folds) -> np.ndarray:
        """Held-out sum of squares (groups,) of the model ``chosen`` plus each allowed group
        (inf where not allowed or inseparable on the data or a fold)."""
        x = p.design(chosen)
        out = np.where(allowed, 0.0, np.inf)
        q_all, _ = np.linalg.qr(x[rows])
        c_all = p.c[rows]
        rest_all = c_all - q_all @ (q_all.T @ c_all)
        # separable from the model so far: the smallest singular value of each group's rest
        # against its own largest (eigenvalues of the small Gram matrices, pairs in one batch)
        pairs = p.pairs[allowed[p.pairs]]
        if pairs.size:
            idx = np.stack([p.groups[i] for i in pairs])
            rest_gram = np.einsum("ngi,ngj->gij", rest_all[:, idx], rest_all[:, idx])
            own_gram = np.einsum("ngi,ngj->gij", c_all[:, idx], c_all[:, idx])
            ratio = np.linalg.eigvalsh(rest_gram)[:, 0] / np.linalg.eigvalsh(own_gram)[:, -1]
            out[pairs[ratio < p.separate[pairs] ** 2]] = np.inf
        for i in p.others:
            if (
                allowed[i]
                and _relative_floor(rest_all[:, p.groups[i]], c_all[:, p.groups[i]]) < p.separate[i]
            ):
                out[i] = np.inf
        pairs = p.pairs[np.isfinite(out[p.pairs])]
        others = [i for i in p.others if np.isfinite(out[i])]
        for k in folds:
            train, test = rows & (fold != k), rows & (fold == k)
            q, r = np.linalg.qr(x[train])
            yt = p.y[train]
            qty = q.T @ yt
            rt = yt - q @ qty
            et = p.y[test] - x[test] @ solve_triangular(r, qty)
            ct = p.c[train]
            a = q.T @ ct
            rest = ct - q @ a
            t = p.c[test] - x[test] @ solve_triangular(r, a)
            if pairs.size:
                idx = np.stack([p.groups[i] for i in pairs])  # (G, 2)
                pg, tg = rest[:, idx], t[:, idx]  # (n, G, 2)
                gram = np.einsum("ngi,ngj->gij", pg, pg)
                rhs = np.einsum("ngi,n->gi", pg, rt)
                det = gram[:, 0, 0] * gram[:, 1, 1] - gram[:, 0, 1] ** 2
                ok = det > 1e-12 * np.maximum(gram[:, 0, 0] * gram[:, 1, 1], 1e-300)
                safe = np.where(ok[:, None, None], gram, np.eye(2))
                w = np.linalg.solve(safe, rhs[:, :, None])[:, :, 0]
                new = et[:, None] - np.einsum("ngi,gi->ng", tg, w)
                out[pairs] += np.where(ok, np.sum(new**2, axis=0), np.inf)
            for i in others:
                g = p.groups[i]
                w = np.linalg.lstsq(rest[:, g], rt, rcond=None)[0]
                out[i] += np.sum((et - t[:, g] @ w) ** 2)
        return out

    def refine(
        self,
        p: _Problem,
        chosen: list[int],
        fold_of_pose: np.ndarray,
        use: np.ndarray,
        start: int = 0,
    ) -> list[int]:
        """``chosen`` with each harmonic from ``start`` on swapped for a neighbouring order of its
        axis (k ± 1, 2) where that lowers the held-out sum of squares (over a narrow angle range
        neighbouring orders differ by a fraction of a period; the greedy step may take the wrong
        one)."""
        rows = use[p.pose]
        fold = fold_of_pose[p.pose]
        folds = np.unique(fold_of_pose[use])
        best = np.nansum(p.held_out(chosen, fold, rows, folds) ** 2)
        chosen = list(chosen)
        for at in range(start, len(chosen)):
            for other in p.neighbours.get(chosen[at], []):
                if other in chosen or not p.observable[other]:
                    continue
                trial = chosen[:at] + [other] + chosen[at + 1 :]
                sse = np.nansum(p.held_out(trial, fold, rows, folds) ** 2)
                if sse < best:
                    chosen, best = trial, sse
        return chosen

    def one_standard_error(self, p: _Problem, path) -> int:
        """The number of steps of ``path`` kept: steps are kept while the next one, or the next
        2..``LOOK_AHEAD`` together (terms that only help as a set, e.g. neighbouring orders),
        lower the held-out sum of squares by more than ``bar`` standard errors of their paired
        per-pose differences (the gain's own uncertainty)."""
        used = np.unique(p.pose[~np.isnan(path[0][1])])
        sse = np.array([p.pose_sse(held)[used] for _, held in path])  # (steps, poses)
        step = 0
        while step + 1 < len(path):
            ahead = sse[step] - sse[step + 1 : step + 1 + LOOK_AHEAD]  # (1..LOOK_AHEAD, poses)
            se = ahead.std(axis=1, ddof=1) / np.sqrt(ahead.shape[1])
            added = [g for g, _ in path[step + 1 : step + 1 + len(ahead)]]
            bar = np.maximum.accumulate(p.bars[added])  # a set passes the bar of its hardest
            passed = np.flatnonzero(ahead.mean(axis=1) > bar * se)
            if not passed.size:
                break
            step += int(passed[0]) + 1
        return step


# the selection strategies by method name (``identify_structure``'s ``method``)
SELECTION: dict[str, SelectionStrategy] = {"ard": ArdSelection(), "search": ForwardSearch()}


def _relative_floor(rest: np.ndarray, cols: np.ndarray) -> float:
    """Smallest singular value of ``rest`` over the largest of ``cols`` (0 for empty)."""
    top = np.linalg.svd(cols, compute_uv=False)
    if top.size == 0 or top[0] <= 0:
        return 0.0
    return float(np.linalg.svd(rest, compute_uv=False)[-1] / top[0])


def _nested(
    problem: _Problem, strategy: SelectionStrategy, fold: np.ndarray, folds: int, names, data
) -> Nested:
    """The whole search repeated inside each outer fold (inner folds: another permutation of the
    training poses), the chosen groups fitted on the training poses, the held-out poses
    predicted (``Nested``)."""
    held = np.full(len(problem.y), np.nan)
    chosen_by_fold = []
    for k in range(folds):
        use = fold != k
        inner = np.full(problem.poses, -1)
        inner[use] = pose_folds(int(use.sum()), folds, _NESTED_SEED + k)
        chosen = strategy.choose(problem, inner, use)[2]
        chosen_by_fold.append(tuple(names[g] for g in chosen))
        x = problem.design(chosen)
        train, test = use[problem.pose], ~use[problem.pose]
        beta = np.linalg.lstsq(x[train], problem.y[train], rcond=None)[0]
        held[test] = problem.y[test] - x[test] @ beta
    rms, peak, _ = problem.held_out_stats(held)
    noise = _repeat_noise(data)
    model = None if noise is None else np.sqrt(np.maximum(rms**2 - noise**2, 0.0))
    return Nested(folds, rms, peak, noise, model, tuple(chosen_by_fold))


def _repeat_noise(data: PoseSet) -> float | None:
    """Row noise sigma mm per axis: the pooled scatter of the repeats of each pose (None when no
    pose is repeated)."""
    counts = np.bincount(data.group)
    repeated = counts[data.group] > 1
    if not repeated.any():
        return None
    mean = np.zeros((len(counts), 3))
    np.add.at(mean, data.group, data.measured)
    mean /= np.maximum(counts, 1)[:, None]
    scatter = data.measured[repeated] - mean[data.group[repeated]]
    dof = 3 * (int(np.sum(counts[counts > 1])) - int(np.sum(counts > 1)))
    return float(np.sqrt(np.sum(scatter**2) / dof))
