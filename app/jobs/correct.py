"""``accugrid correct`` (``correct_points``): the corrected-points CSV (docs/formats.md)
both jobs (grid here, model in ``correct_model``) write from the correction policy's
verdict (``compensation.policy``): every input column untouched, then x_cmd,y_cmd,z_cmd (the
command, mm), ex,ey,ez (the correction applied, P' - P, mm; 4 decimals) and flag (why a point
deserves a look, or "not corrected: ..." with --allow-partial)."""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accugrid.codegen.header import csv_comment, grid_lines, header_lines, input_line
from accugrid.codegen.linebytes import SLOT, image_bytes, line_image, number_cells
from accugrid.codegen.points import Points, read_points
from accugrid.compensation.measurements import REPEAT_TOL_MM
from accugrid.compensation.policy import Policy, PolicyRequest, Verdict
from accugrid.compensation.settings import CorrectionSettings
from accugrid.infra.atomic import JobFiles
from accugrid.infra.digest import file_sha256
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import fixed_texts
from accugrid.kinematics.frames import abc_to_matrix

__all__ = [
    "ADDED",
    "BLOCK",
    "DECIMALS",
    "CorrectRequest",
    "check_added_columns",
    "correct_points",
    "corrected_csv",
    "corrected_file",
    "flag_texts",
    "point_status",
]

ADDED = ["x_cmd", "y_cmd", "z_cmd", "ex", "ey", "ez", "flag"]
DECIMALS = 4
_LISTED = 5  # how many points a message names


def check_added_columns(points: Points) -> None:
    """InputError when the points CSV already has a column that correct writes."""
    clash = [name for name in ADDED if points.table.has(name)]
    if clash:
        raise InputError(
            f"column(s) {', '.join(clash)} would be written by accugrid correct; rename them",
            points.path,
            1,
        )


def point_status(points: Points, status: int | None) -> np.ndarray | int | None:
    """Each point's KUKA Status: the points' column ``s`` (N,) ints, else ``status`` (--status).
    InputError at a value that is not a Status 0..7."""
    if not points.table.has("s"):
        return status
    values = points.table.floats(["s"])[:, 0]
    bad = np.flatnonzero(~np.isin(values, np.arange(8)))
    if bad.size:
        raise InputError(
            f"column 's' must be a KUKA Status 0..7, got {values[bad[0]]:g}",
            *points.table.where(int(bad[0]), "s"),
        )
    return values.astype(np.int64)


def flag_texts(verdict: Verdict) -> list[str]:
    """The flag column (N): "not corrected: <reason>" for points left as they are (with
    --allow-partial), the flags' words for the others, "" for none."""
    out = verdict.reasons()
    for i in verdict.refused.tolist():
        out[i] = "not corrected: " + out[i]
    return out


def _plain_lines(rows: np.ndarray, numbers: np.ndarray, flags: list[str]) -> bytes:
    """CSV lines, UTF-8: each row as read (``rows`` (n, r) uint8 NUL-padded), its numbers
    (n, k) as ``fixed`` text with ``DECIMALS`` places, its flag (n) (nothing ``csv.writer``
    would quote), LF; one line image (``codegen.linebytes``)."""
    n, k = numbers.shape
    cells = number_cells(numbers, DECIMALS)  # (n, k, w)
    notes = np.array([f.encode() for f in flags], dtype=bytes)  # UTF-8, NUL-padded
    template = SLOT + f",{SLOT}" * (k + 1) + "\n"
    columns = [rows, *(cells[:, j] for j in range(k)), notes.view(np.uint8).reshape(n, -1)]
    return image_bytes(line_image(template, columns))


def corrected_csv(
    points: Points,
    command: np.ndarray,
    correction: np.ndarray,
    flag: list[str],
    header: list[str],
) -> Iterator[str | bytes]:
    """The corrected CSV text in pieces (comment header and column names, then blocks of
    ``BLOCK`` rows), for writing a million points without holding the text whole."""
    out = io.StringIO()
    out.write(csv_comment(header))
    csv.writer(out, lineterminator="\n").writerow([*points.table.header, *ADDED])
    yield out.getvalue()
    numbers = np.column_stack([command, correction])
    plain = points.table.row_bytes(0, 0) is not None and not _NEEDS_QUOTES.search("".join(flag))
    for lo in range(0, len(points), BLOCK):
        hi = min(lo + BLOCK, len(points))
        if plain:  # the block's lines built as bytes by numpy from the rows as read
            yield _plain_lines(points.table.row_bytes(lo, hi), numbers[lo:hi], flag[lo:hi])
            continue
        out = io.StringIO()
        writer = csv.writer(out, lineterminator="\n")
        texts = fixed_texts(numbers[lo:hi], DECIMALS).tolist()
        for row, text, note in zip(points.table.rows[lo:hi], texts, flag[lo:hi], strict=True):
            writer.writerow([*row, *text, note])
        yield out.getvalue()


BLOCK = 65536  # rows formatted at a time
_NEEDS_QUOTES = re.compile(r'[,"\r\n]')  # what csv.writer would quote


def corrected_file(
    request: CorrectRequest,
    points: Points,
    verdict: Verdict,
    sources: list[str],
    details: list[str],
    lines: list[str],
) -> JobFiles:
    """The job rule of the policy (``Verdict.enforce``: refused for a correction beyond the
    safety limit, and for any point not corrected unless --allow-partial), else the corrected
    CSV (header: the points file, ``sources`` and ``details`` lines) to write, with ``lines``
    and the summary every correct job ends with (largest correction, flagged points) to print,
    and the partial job's counts for stderr."""
    warnings = verdict.enforce(
        points.label, points.table.where, request.policy.allow_partial, what="point"
    )
    correction = verdict.command - points.xyz
    length = verdict.length
    worst = int(np.argmax(length)) if len(points) else None
    where = "" if worst is None else f" at hole {points.ids[worst]}"
    largest = 0.0 if worst is None else float(length[worst])
    inputs = [input_line("points", request.points, file_sha256(request.points)), *sources]
    closing = [f"points {len(points)}"]
    if verdict.refused.size:
        closing.append(f"not corrected {verdict.refused.size} ({verdict.counts()})")
    header = header_lines("correct", inputs, details, largest, where, closing)
    flags = flag_texts(verdict)
    text = corrected_csv(points, verdict.command, correction, flags, header)
    if worst is not None:
        lines.append(
            f"largest correction {length[worst]:.4f} mm at {points.label(worst)}; "
            f"mean {length.mean():.4f} mm"
        )
    flagged = [i for i, f in enumerate(flags) if f] if any(flags) else []
    lines.append(f"flagged    {len(flagged)} point(s)")
    lines += [f"  {points.label(i)}: {flags[i]}" for i in flagged[:_LISTED]]
    if len(flagged) > _LISTED:
        lines.append(f"  ... and {len(flagged) - _LISTED} more (see the flag column)")
    lines.append(f"wrote {request.output}")
    model = request.model if request.model and Path(request.model).is_file() else None
    files = {request.output: text}
    if request.report_html:
        from accugrid.app.reports.correction import (
            ReportedFiles,
            checks_text,
            correction_report,
            verdict_states,
        )

        roles = [("points", request.points), ("model", request.model), ("grid", request.grid)]
        state, reasons = verdict_states(verdict)

        def page(outputs: list[tuple[str, str]]) -> str:
            return correction_report(
                "Corrected points",
                points.xyz,
                verdict.command,
                state,
                reasons,
                points.label,
                roles,
                outputs=outputs,
                checked=checks_text(verdict.policy),
            )

        files = ReportedFiles(files, request.report_html, page)
        lines.append(f"wrote {request.report_html}")
    return JobFiles(files, [request.points, request.grid, model], lines, warnings)


@dataclass(frozen=True)
class CorrectRequest:
    """One ``accugrid correct`` job: POINTS (robot frame) to OUTPUT, by a grid measurement
    and/or a calibrated model (paths), with the correction ``settings`` (their ``outside`` is
    ``policy.outside``) and the policy's options (``policy``); ``repeat_tol_mm`` merges repeated
    grid vertices. With a model: ``status`` (KUKA, None: the default rule), ``abc`` (KUKA deg,
    orientation of points without one, reference for i,j,k), ``tool`` (the controller's x, y,
    z, a, b, c; None: the file's)."""

    points: str
    output: str
    grid: str | None
    model: str | None
    settings: CorrectionSettings
    policy: PolicyRequest = PolicyRequest()
    repeat_tol_mm: float = REPEAT_TOL_MM
    status: int | None = None
    abc: tuple[float, float, float] = (0.0, 90.0, 0.0)
    tool: tuple[float, ...] | None = None
    report_html: str | None = None  # the HTML report to write beside the CSV

    @property
    def correction(self) -> CorrectionSettings:
        """The correction settings with the policy's ``outside``."""
        return self.settings.but(outside=self.policy.outside)


def correct_points(request: CorrectRequest) -> JobFiles:
    """The ``accugrid correct`` job with the grid alone (with a model: ``correct_model``): the
    corrected-points CSV and the printed summary. InputError (nothing to write) on bad input, a
    correction beyond the safety limit, or a point the policy does not correct (outside the
    grid, orientation beyond the limit, another Status than the grid's) unless
    ``allow_partial``."""
    request.policy.check()
    if request.grid is None:
        raise InputError("give --grid MEAS, --model CAL.yaml or both")
    settings = request.correction
    policy = Policy.build(
        settings,
        request.grid,
        status=request.status,
        repeat_tol_mm=request.repeat_tol_mm,
        **request.policy.limits(),
    )
    model = policy.grid
    points = read_points(request.points)
    check_added_columns(points)
    rotations = None if points.abc is None else abc_to_matrix(points.abc).reshape(-1, 3, 3)
    own = point_status(points, request.status)
    verdict = policy.decide(points.xyz, rotations, points.axis, own)
    sources = grid_lines(Path(request.grid).name, model.source_sha256, model.step)
    method, power, its = settings.method, settings.power, settings.iterations
    details = [f"method {method}, power {power:g}, iterations {its}"]
    iterations = f"{its} iteration{'s' if its != 1 else ''}"
    power_text = f" power {power:g}" if method == "idw" else ""
    if model.status is None:
        said = "status     not recorded in the grid file (column s): not checked"
    elif own is None:
        said = "status     the points' KUKA Status is not given (column s, --status): not checked"
    else:
        said = "status     checked against the points' (column s or --status)"
    lines = [
        model.describe() + "\n" + said,
        f"corrected  {int(verdict.corrected.sum())} point(s), {method}{power_text}, {iterations}",
    ]
    return corrected_file(request, points, verdict, sources, details, lines)
