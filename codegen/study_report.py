"""The study's tables as text: Tables 4 and 5 of the seed, for the terminal (aligned columns),
CSV and the Markdown report. Errors in mm with 3 decimals."""

from __future__ import annotations

from accugrid.compensation.study import AXES, StudyResult, Summary

__all__ = ["STAT_HEADER", "csv_text", "md_table", "table4", "table5", "text_table"]


def _fmt(v: float) -> str:
    return f"{v:.3f}"


def text_table(header: list[str], rows: list[list[str]]) -> str:
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(header)]
    line = lambda cells: "  ".join(c.rjust(w) for c, w in zip(cells, widths, strict=True))  # noqa: E731
    return "\n".join([line(header), line(["-" * w for w in widths])] + [line(r) for r in rows])


STAT_HEADER = [f"{k} {a}" for k in ("max", "min", "std") for a in AXES]


def _stat_cells(row: Summary) -> list[str]:
    return [_fmt(v) for v in (*row.max, *row.min, *row.std)]


def table4(result: StudyResult) -> tuple[list[str], list[list[str]]]:
    rows = [[f"{s:g}", *_stat_cells(r)] for s, r in zip(result.steps, result.table, strict=True)]
    return ["step mm", *STAT_HEADER], rows


def table5(before: Summary, after: Summary) -> tuple[list[str], list[list[str]]]:
    return ["", *STAT_HEADER], [["before", *_stat_cells(before)], ["after", *_stat_cells(after)]]


def csv_text(header: list[str], rows: list[list[str]]) -> str:
    names = [h.replace(" mm", "_mm").replace(" ", "_").lower() or "calibration" for h in header]
    return "\n".join([",".join(names)] + [",".join(r) for r in rows]) + "\n"


def md_table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])
