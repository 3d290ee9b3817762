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

from accugrid.codegen.plots import correction_map_png
from accugrid.codegen.report_html import Figure, Section, Table, report_html
from accugrid.compensation.policy import Verdict
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM

__all__ = ["correction_report"]

_LISTED = 100  # positions listed in the table of flagged / not corrected ones


def correction_report(
    title: str,
    verdict: Verdict,
    label: Callable[[int], str],
    inputs: list[tuple[str, str | None]],
    tolerance_mm: float = DEFAULT_TOLERANCE_MM,
) -> str:
    """The report page of ``verdict`` (its positions and commands (N, 3) mm robot frame);
    ``label(i)`` names position i (file:line, id); ``inputs`` (role, path)."""
    correction = verdict.command - verdict.points
    corrected = verdict.corrected
    reasons = verdict.reasons()
    flagged = np.array([bool(r) for r in reasons]) & corrected
    skipped = ~corrected
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
    listed = np.flatnonzero(skipped | flagged)
    rows = [
        [label(int(i)), "not corrected" if skipped[i] else "flagged", reasons[i]]
        for i in listed[:_LISTED]
    ]
    notes = [
        f"{len(verdict)} positions: {int(corrected.sum())} corrected ({int(flagged.sum())} of "
        f"them flagged), {int(skipped.sum())} not corrected"
        + (f" ({verdict.counts()})" if skipped.any() else "")
        + ".",
        "Correction c = command - target, robot frame, mm.",
    ]
    if listed.size > _LISTED:
        notes.append(f"The table lists the first {_LISTED} of {listed.size} such positions.")
    tables = [
        Table(["axis", "min (mm)", "max (mm)", "mean (mm)", "std (mm)"], stats, "Correction"),
        Table(
            ["position", "status", "reason"],
            rows or [["none", "", ""]],
            "Positions flagged or not corrected",
        ),
    ]
    figure = Figure(
        correction_map_png(verdict.points, correction, corrected, flagged),
        "Plan view of the positions coloured by the length of their correction; red arrows: "
        "its XY part (scaled, at most 400 drawn); black crosses: not corrected; orange rings: "
        "flagged.",
    )
    return report_html(
        title,
        "FAIL" if skipped.any() else "PASS",
        f"±{tolerance_mm:g} mm per axis, checked after correction by accugrid validate",
        inputs,
        [Section("Corrections", notes, tables[:1], [figure]), Section("Positions", [], tables[1:])],
        [("criterion", "PASS when every position is corrected")],
    )
