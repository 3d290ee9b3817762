"""G2/G3 arcs and helices as LinuxCNC reads them: the words of one arc block (``arc_of``) and the
geometry of many (``arc_centres``, ``arc_samples``).

The plane (G17, G18, G19) gives the arc's first and second axis and its helix axis: G17 (X, Y)
about Z with I, J; G18 (Z, X) about Y with K, I; G19 (Y, Z) about X with J, K (LinuxCNC's
order, in which a positive turn is counter-clockwise). The centre is I, J, K from the start
(G91.1, the default) or absolute (G90.1), a word not written being 0; or, in the R format, on the
perpendicular bisector of the chord, on the side R's sign and the direction choose (a negative R:
more than half a circle). P is the number of turns (1 when not written); the helix axis moves
linearly with the angle from the start to the end.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["PLANE_AXES", "Arc", "arc_centres", "arc_of", "arc_samples"]

PLANE_AXES = {"17": (0, 1, 2), "18": (2, 0, 1), "19": (1, 2, 0)}  # first, second, helix axis
_CENTRE_LETTERS = "IJK"  # I: X, J: Y, K: Z
_MAX_TURNS = 10_000  # P beyond this is reported (each turn is sampled)
_SAMPLE_RAD = math.pi / 16  # at most this angle between two samples of an arc
_SAMPLE_MM = 2.0  # ... and at most this length
_MAX_SAMPLES = 4096  # samples of one arc at most (a longer arc is sampled more sparsely)


class Arc(NamedTuple):
    """One G2/G3 block's arc words: ``plane`` "17"/"18"/"19", ``clockwise`` (G2), ``centre``
    the I, J, K words (``Word`` or None each), ``radius`` the R word (R format) or None,
    ``turns`` (P, 1 when not written), ``absolute`` (G90.1: I, J, K absolute)."""

    plane: str
    clockwise: bool
    centre: tuple
    radius: object
    turns: int
    absolute: bool


def arc_of(block, plane: str, absolute: bool, lineno: int, clockwise: bool):
    """The ``Arc`` of a G2/G3 block (the reader's ``_Line``: ``words`` letter -> Word or None,
    ``exprs`` letter -> text of the words whose parameter or expression is not decidable,
    ``why`` letter -> why not) and why it cannot be placed ("": it can)."""
    words, exprs = block.words, block.exprs
    first, second, _ = PLANE_AXES[plane]
    letters = _CENTRE_LETTERS[first] + _CENTRE_LETTERS[second]
    centre = tuple(words.get(k) for k in _CENTRE_LETTERS)
    radius = words.get("R")
    turns, why = 1, ""
    used = [k for k in "IJKP" if k in exprs]
    if used:
        k = used[0]
        why = f"arc {exprs[k]} uses a parameter or an expression: {block.why[k]} (line {lineno})"
    elif "P" in words:
        p = words["P"].value
        if p == int(p) and 1 <= p <= _MAX_TURNS:
            turns = int(p)
        else:
            why = f"arc P{words['P'].literal}: not a number of turns from 1 to {_MAX_TURNS}"
    has_centre = any(centre[k] is not None for k in (first, second))
    if not why and radius is not None and has_centre:
        why = f"arc with both R and {letters[0]}/{letters[1]} (line {lineno})"
    elif not why and radius is None and not has_centre:
        why = f"arc without a centre ({letters[0]}, {letters[1]}) or a radius R (line {lineno})"
    return Arc(plane, clockwise, centre, radius, turns, absolute), why


def arc_centres(arcs: list[Arc], start: np.ndarray, end: np.ndarray, scale: np.ndarray):
    """Centres (N, 3) mm (helix axis coordinate: the start's) of ``arcs`` that run from
    ``start`` to ``end`` (N, 3) mm; ``scale`` (N,) mm per program unit."""
    n = len(arcs)
    centre = start.copy()
    if not n:
        return centre
    axes = np.array([PLANE_AXES[a.plane] for a in arcs])
    rows = np.arange(n)
    first, second = axes[:, 0], axes[:, 1]
    given = np.array([[w.value if w is not None else 0.0 for w in a.centre] for a in arcs])
    absolute = np.array([a.absolute for a in arcs])
    ijk = np.flatnonzero(np.array([a.radius is None for a in arcs]))
    for axis in (first, second):
        value = given[rows, axis] * scale
        centre[ijk, axis[ijk]] = np.where(absolute, value, start[rows, axis] + value)[ijk]
    r_form = np.flatnonzero(np.array([a.radius is not None for a in arcs]))
    if len(r_form):
        radius = np.array([arcs[k].radius.value for k in r_form.tolist()]) * scale[r_form]
        cw = np.array([arcs[k].clockwise for k in r_form.tolist()])
        a, b = first[r_form], second[r_form]
        s1, s2 = start[r_form, a], start[r_form, b]
        e1, e2 = end[r_form, a], end[r_form, b]
        mid1, mid2 = (s1 + e1) / 2, (s2 + e2) / 2
        half = np.hypot(e1 - mid1, e2 - mid2)
        absolute_r = np.abs(radius)
        half = np.minimum(half, absolute_r)  # a chord a little longer than 2R: a half circle
        # the centre lies right of the chord for G2 with R > 0 (G3 with R < 0), else left
        right = cw == (radius > 0)
        theta = np.arctan2(e2 - s2, e1 - s1) + np.where(right, -np.pi / 2, np.pi / 2)
        offset = absolute_r * np.cos(np.arcsin(half / np.where(absolute_r > 0, absolute_r, 1)))
        centre[r_form, a] = mid1 + offset * np.cos(theta)
        centre[r_form, b] = mid2 + offset * np.sin(theta)
    return centre


def arc_samples(
    arcs: list[Arc], start: np.ndarray, end: np.ndarray, centre: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Points along each arc, start and end included: (M, 3) mm and the arc (M,) each belongs
    to (an index into ``arcs``), at most ``_SAMPLE_RAD`` and ``_SAMPLE_MM`` apart (up to
    ``_MAX_SAMPLES`` per arc). ``start``, ``end``, ``centre`` (N, 3) mm as ``arc_centres``
    gives; the radius goes linearly from the start's to the end's, like the helix axis."""
    n = len(arcs)
    if not n:
        return np.zeros((0, 3)), np.zeros(0, np.int64)
    axes = np.array([PLANE_AXES[a.plane] for a in arcs])
    rows = np.arange(n)
    a, b, h = axes[:, 0], axes[:, 1], axes[:, 2]
    r0 = np.hypot(start[rows, a] - centre[rows, a], start[rows, b] - centre[rows, b])
    r1 = np.hypot(end[rows, a] - centre[rows, a], end[rows, b] - centre[rows, b])
    t0 = np.arctan2(start[rows, b] - centre[rows, b], start[rows, a] - centre[rows, a])
    t1 = np.arctan2(end[rows, b] - centre[rows, b], end[rows, a] - centre[rows, a])
    cw = np.array([x.clockwise for x in arcs])
    turns = np.array([x.turns for x in arcs])
    sweep = np.where(cw, t0 - t1, t1 - t0) % (2 * np.pi)  # the first partial turn, >= 0
    closed = (start[rows, a] == end[rows, a]) & (start[rows, b] == end[rows, b])
    sweep = np.where(closed | (sweep < 1e-12), 2 * np.pi, sweep) + 2 * np.pi * (turns - 1)
    length = sweep * np.maximum(r0, r1)
    count = np.ceil(np.maximum(sweep / _SAMPLE_RAD, length / _SAMPLE_MM)).astype(np.int64)
    count = np.clip(count, 2, _MAX_SAMPLES)
    owner = np.repeat(rows, count + 1)
    first = np.cumsum(count + 1) - (count + 1)
    t = (np.arange(len(owner)) - first[owner]) / count[owner]  # 0 .. 1 along each arc
    angle = t0[owner] + np.where(cw[owner], -1.0, 1.0) * sweep[owner] * t
    radius = r0[owner] + (r1 - r0)[owner] * t
    points = np.empty((len(owner), 3))
    k = np.arange(len(owner))
    points[k, a[owner]] = centre[owner, a[owner]] + radius * np.cos(angle)
    points[k, b[owner]] = centre[owner, b[owner]] + radius * np.sin(angle)
    points[k, h[owner]] = start[owner, h[owner]] + (end - start)[owner, h[owner]] * t
    return points, owner
