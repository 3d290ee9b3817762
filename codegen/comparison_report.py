"""`accugrid compare`'s result as text: the Markdown table and notes for the terminal, and the
CSV file (one row per budget, target set and method). Errors in mm with 3 decimals."""

from __future__ import annotations

from accugrid.codegen.textsafe import comment_text, fixed
from accugrid.compensation.comparison import Comparison, ComparisonRow

__all__ = ["csv_text", "report_text", "table_text"]


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
    lines = [result.settings, table_text(result)]
    for budget, (without, with_layer) in result.joint_cv.items():
        lines.append(
            f"joint residual, 5-fold cross-validation over the {budget} poses: held-out RMS "
            f"X Y Z {' '.join(fixed(v, 3) for v in without)} mm without, "
            f"{' '.join(fixed(v, 3) for v in with_layer)} mm with"
        )
    lines += [f"skipped {line}" for line in result.skipped]
    return "\n".join(lines)


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
