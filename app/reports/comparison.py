"""`accugrid compare`'s result as text: the Markdown table and notes for the terminal, the
CSV file (one row per budget, target set and method) and the HTML report (``--report-html``).
Errors in mm with 3 decimals."""

from __future__ import annotations

from accugrid.compensation.comparison import Comparison, ComparisonRow
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM
from accugrid.infra.textsafe import comment_text, fixed

__all__ = ["csv_text", "html_report", "report_text", "table_text"]


def _cells(row: ComparisonRow) -> list[str]:
    return [fixed(v, 3) for v in (*row.max_mm, *row.std_mm)]


def table_text(result: Comparison) -> str:
    """The rows as a Markdown table (budget 0: uncorrected)."""
    lines = [
        "| targets | budget | method | points | max X | max Y | max Z | std X | std Y | std Z |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for targets in dict.fromkeys(r.targets for r in result.rows):
        for r in (r for r in result.rows if r.targets == targets):
            budget = "-" if r.method == "uncorrected" else str(r.budget)
            lines.append(
                f"| {targets} | {budget} | {r.method} | {r.points} | "
                + " | ".join(_cells(r))
                + " |"
            )
    return "\n".join(lines)


def report_text(result: Comparison) -> str:
    """What the command prints: the settings line, the table, the joint residual's
    cross-validation per budget and the rows a budget could not have."""
    return "\n".join([result.settings, table_text(result), *_notes(result)])


def _notes(result: Comparison) -> list[str]:
    """The joint residual's cross-validation per budget and the rows a budget could not have."""
    lines = []
    for budget, (without, with_layer) in result.joint_cv.items():
        lines.append(
            f"joint residual, 5-fold cross-validation over the {budget} poses: held-out RMS "
            f"X Y Z {' '.join(fixed(v, 3) for v in without)} mm without, "
            f"{' '.join(fixed(v, 3) for v in with_layer)} mm with"
        )
    return lines + [f"skipped {line}" for line in result.skipped]


def csv_text(result: Comparison) -> str:
    """comparison.csv: a ``#`` line with the settings, then one row per result row."""
    header = comment_text(f"accugrid compare: {result.settings}", limit=600)
    lines = [
        f"# {header}",
        "targets,budget,method,points,max_x,max_y,max_z,std_x,std_y,std_z",
    ]
    for r in result.rows:
        lines.append(f"{r.targets},{r.budget},{r.method},{r.points}," + ",".join(_cells(r)))
    return "\n".join(lines) + "\n"


def html_report(
    result: Comparison,
    figures: dict[str, bytes],
    inputs: list[tuple[str, str | None]],
    tolerance_mm: float = DEFAULT_TOLERANCE_MM,
) -> str:
    """The HTML report: the settings, the methods within the tolerance on both target sets at
    the largest budget, the table, the figures (``figures``: stat -> PNG). A comparison of
    methods has no pass criterion (verdict INFO)."""
    from accugrid.app.reports.html import Figure, Section, Table, report_html

    largest = max(r.budget for r in result.rows)
    at_largest = [r for r in result.rows if r.budget == largest and r.method != "uncorrected"]
    sets = {r.targets for r in at_largest}
    within = [
        m
        for m in dict.fromkeys(r.method for r in at_largest)
        if all(max(r.max_mm) <= tolerance_mm for r in at_largest if r.method == m)
        and {r.targets for r in at_largest if r.method == m} == sets
    ]
    table = Table(
        ["targets", "budget", "method", "points"]
        + [f"max {a} (mm)" for a in "XYZ"]
        + [f"std {a} (mm)" for a in "XYZ"],
        [
            [
                r.targets,
                "-" if r.method == "uncorrected" else str(r.budget),
                r.method,
                str(r.points),
                *_cells(r),
            ]
            for r in result.rows
        ],  # fmt: skip
        "Held-out error per target set, budget and method",
    )
    notes = [result.settings, *_notes(result)]
    pictures = [
        Figure(png, f"Held-out {stat} of the remaining error against the measured points; "
               f"dashed: the {'tolerance' if stat == 'max' else 'std limit'}.")
        for stat, png in figures.items()
    ]  # fmt: skip
    return report_html(
        "Comparison of correction methods",
        "INFO",
        f"±{tolerance_mm:g} mm per axis (held-out max)",
        inputs,
        [Section("Results", notes, [table]), Section("Figures", figures=pictures)],
        [
            (
                f"within ±{tolerance_mm:g} mm at {largest} points",
                ", ".join(within) or "no method",
            )
        ],
    )
