"""The HTML report of a correction job (``correct --report-html``): the correction applied per
position on a plan-view map, its statistics, and every position flagged or left uncorrected
with the correction policy's words (``compensation.policy.Verdict``).

Verdict: PASS when every position is corrected; FAIL when some are left as they are (a job
written with --allow-partial). The tolerance is stated for the validation that follows (the
accuracy itself is measured by ``accugrid validate``). Lengths mm, robot frame.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from accugrid.app.plots import correction_map_png
from accugrid.app.report_html import Figure, Section, Table, report_html
from accugrid.compensation.policy import Verdict
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM

__all__ = [
    "CORRECTED",
    "FLAGGED",
    "NOT_CORRECTED",
    "SKIPPED",
    "correction_report",
    "verdict_states",
]

_LISTED = 100  # positions listed in the table of flagged / not corrected ones


CORRECTED, FLAGGED, NOT_CORRECTED, SKIPPED = 0, 1, 2, 3  # the states of a position
_STATE_WORDS = ("corrected", "flagged", "not corrected", "skipped")


def verdict_states(verdict: Verdict) -> tuple[np.ndarray, list[str]]:
    """The state (N,) of each position of the policy's ``verdict`` and its words (N)."""
    reasons = verdict.reasons()
    state = np.where(verdict.corrected, CORRECTED, NOT_CORRECTED)
    state[verdict.corrected & np.array([bool(r) for r in reasons], dtype=bool)] = FLAGGED
    return state, reasons


def correction_report(
    title: str,
    points: np.ndarray,
    command: np.ndarray,
    state: np.ndarray,
    reasons: list[str],
    label: Callable[[int], str],
    inputs: list[tuple[str, str | None]],
    frame: str = "robot frame",
    tolerance_mm: float = DEFAULT_TOLERANCE_MM,
) -> str:
    """The report page: positions and commands (N, 3) mm in ``frame`` (NaN rows: positions
    that are not points, left off the map), ``state`` (N,) of CORRECTED..SKIPPED, the policy's
    ``reasons`` (N), ``label(i)`` naming position i (file:line, id), ``inputs`` (role, path).
    SKIPPED: what is not a drilling position (a frame, a constant), listed, never a failure."""
    state = np.asarray(state)
    correction = np.where(state[:, None] <= FLAGGED, command - points, 0.0)
    corrected = state <= FLAGGED
    length = np.linalg.norm(correction, axis=1)
    stats = []
    done = np.flatnonzero(corrected)
    if done.size:
        for k, axis in enumerate("XYZ"):
            c = correction[done, k]
            stats.append(
                [axis, f"{c.min():+.3f}", f"{c.max():+.3f}", f"{c.mean():+.3f}", f"{c.std():.3f}"]
            )
        c = length[done]
        stats.append(
            ["|c|", f"{c.min():.3f}", f"{c.max():.3f}", f"{c.mean():.3f}", f"{c.std():.3f}"]
        )
    listed = np.flatnonzero(state != CORRECTED)
    rows = [[label(int(i)), _STATE_WORDS[state[i]], reasons[i]] for i in listed[:_LISTED]]
    counts = np.bincount(state, minlength=4)
    notes = [
        f"{len(state)} positions: {counts[CORRECTED] + counts[FLAGGED]} corrected "
        f"({counts[FLAGGED]} of them flagged), {counts[NOT_CORRECTED]} not corrected, "
        f"{counts[SKIPPED]} skipped (not drilling positions).",
        f"Correction c = command - target, {frame}, mm.",
    ]
    if listed.size > _LISTED:
        notes.append(f"The table lists the first {_LISTED} of {listed.size} such positions.")
    on_map = np.flatnonzero(np.isfinite(points).all(axis=1) & (state != SKIPPED))
    figure = Figure(
        correction_map_png(
            points[on_map],
            correction[on_map],
            corrected[on_map],
            state[on_map] == FLAGGED,
            frame,
        ),
        "Plan view of the positions coloured by the length of their correction; red arrows: "
        "its XY part (scaled, at most 400 drawn); black crosses: not corrected; orange rings: "
        "flagged.",
    )
    tables = [
        Table(["axis", "min (mm)", "max (mm)", "mean (mm)", "std (mm)"], stats, "Correction"),
        Table(
            ["position", "status", "reason"],
            rows or [["none", "", ""]],
            "Positions flagged, not corrected or skipped",
        ),
    ]
    return report_html(
        title,
        "FAIL" if counts[NOT_CORRECTED] else "PASS",
        f"±{tolerance_mm:g} mm per axis, checked after correction by accugrid validate",
        inputs,
        [Section("Corrections", notes, tables[:1], [figure]), Section("Positions", [], tables[1:])],
        [("criterion", "PASS when every drilling position is corrected")],
    )
