"""The one self-contained HTML report of a command (``--report-html FILE``, docs/validation.md).

One Jinja page (``templates/report/report.html.j2``, autoescaped): the title and the verdict
(PASS, FAIL, or INFO for a job without a pass criterion; a job may say in its own words what
the box holds), the command line, the accugrid version, the date, the tolerance, every input
and output with its SHA-256, then the command's sections (text, tables, figures as inline
base64 PNG: no network, a raster keeps a plot of 1e4 holes small). Print CSS lays it out on A4.
The text is returned; the command writes it with its other files (``atomic.write_files``), so
the report and the job's outputs are all old or all new.

The date is the time of the run (UTC), or ``SOURCE_DATE_EPOCH`` (seconds since 1970, the
reproducible-builds convention) when set, so the same inputs can give the same bytes.
"""

from __future__ import annotations

import base64
import os
import shlex
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import jinja2

from accugrid import __version__
from accugrid.infra.digest import file_sha256
from accugrid.infra.errors import printable
from accugrid.templates import TEMPLATE_DIR

__all__ = ["Figure", "Section", "Table", "report_date", "report_html"]

_VERDICTS = {"PASS": "PASS", "FAIL": "FAIL", "INFO": "no pass criterion"}


@dataclass(frozen=True)
class Figure:
    """A PNG figure and its caption (also the image's alt text)."""

    png: bytes
    caption: str

    @property
    def base64(self) -> str:
        return base64.b64encode(self.png).decode("ascii")


@dataclass(frozen=True)
class Table:
    """A table: header cells and rows of text (numbers already formatted, with their unit in
    the header)."""

    header: list[str]
    rows: list[list[str]]
    title: str = ""


@dataclass(frozen=True)
class Section:
    """A heading with paragraphs, tables and figures, in that order."""

    title: str
    lines: list[str] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)


def _environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(os.fspath(TEMPLATE_DIR / "report")),
        undefined=jinja2.StrictUndefined,
        autoescape=True,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.tests["number_cell"] = _is_number
    return env


def _is_number(cell: object) -> bool:
    """A cell right-aligned as a number: it parses as a float."""
    try:
        float(str(cell).replace("±", ""))
    except ValueError:
        return False
    return True


def report_date() -> str:
    """The report's date and time, UTC: ``SOURCE_DATE_EPOCH`` when set, else now."""
    epoch = os.environ.get("SOURCE_DATE_EPOCH", "").strip()
    try:
        seconds = float(epoch) if epoch else time.time()
    except ValueError:
        seconds = time.time()  # as the reproducible-builds convention: a bad value is ignored
    return time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime(seconds))


def report_html(
    title: str,
    verdict: str,
    tolerance: str,
    inputs: list[tuple[str, str | None]],
    sections: list[Section],
    facts: list[tuple[str, str]] | None = None,
    argv: list[str] | None = None,
    outputs: list[tuple[str, str]] | None = None,
    verdict_text: str | None = None,
) -> str:
    """The report page. ``verdict``: PASS, FAIL or INFO (its box's colour), ``verdict_text``
    what the box says (default: the verdict's word); ``inputs``: (role, path) pairs (a path
    None is left out; a name that is no file, e.g. a built-in robot, gets '-' as hash);
    ``outputs``: (path, SHA-256) of the files the job wrote beside the report; ``facts``: more
    (key, value) lines under the header; ``argv``: the command line (default: this
    process's)."""
    if verdict not in _VERDICTS:
        raise ValueError(f"verdict must be one of {sorted(_VERDICTS)}")
    rows = []
    for role, path in inputs:
        if path is None:
            continue
        digest = file_sha256(path) if Path(path).is_file() else "-"
        rows.append({"role": role, "name": printable(path), "sha256": digest})
    words = ["accugrid", *(sys.argv[1:] if argv is None else argv)]
    return (
        _environment()
        .get_template("report.html.j2")
        .render(
            title=title,
            verdict=verdict,
            verdict_text=verdict_text or _VERDICTS[verdict],
            command=printable(shlex.join(words), limit=2000),
            version=__version__,
            date=report_date(),
            tolerance=tolerance,
            facts=facts or [],
            inputs=rows,
            outputs=[{"name": printable(path), "sha256": sha} for path, sha in outputs or []],
            sections=sections,
        )
    )
