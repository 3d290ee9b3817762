"""``accugrid rewrite`` as one call: from what the command line asks (``RewriteRequest``) to the
bytes of every output file (``RewriteJob``). Reads the cell, the grid, the calibrated model and
the programs, rewrites them over their dialect's plug-in (``codegen.rewrite.rewrite``,
``codegen.plugin``), adds its header and makes the report; the command only parses, calls
``rewrite_job``, writes and prints.
"""

from __future__ import annotations

import gc
import os
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from accugrid.codegen.cell import load_cell
from accugrid.codegen.correction import cell_grid, policy_for, read_model
from accugrid.codegen.dialects import check_serves, dialect_of, plugin_of
from accugrid.codegen.plugin_types import CORRECTED, OUTSIDE, SKIPPED, Options, ProgramContext
from accugrid.codegen.program_text import read_program
from accugrid.codegen.rewrite import Result, header_lines, report_csv, rewrite, warning_lines
from accugrid.compensation.policy import PolicyRequest
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM

__all__ = ["RewriteJob", "RewriteRequest", "rewrite_job"]


@dataclass(frozen=True)
class RewriteRequest:
    """What to rewrite: the programs (one file, or the two files of a dialect whose program is a
    pair, e.g. a KRL .src/.dat) and the output path of each, and the options of ``accugrid
    rewrite`` (``Options`` for their meaning; ``policy``: the policy's options,
    ``compensation.policy.PolicyRequest``; ``options``: the dialects' own options by key,
    ``codegen.plugin.DialectOption``, a file's as its path: the programs' dialect reads its
    own)."""

    outputs: dict[Path, Path]  # input program -> output file, the .src (what runs) first
    cell: str
    grid: str | None = None
    model: str | None = None
    report: Path | None = None
    report_html: Path | None = None
    header: bool = False
    decimals: int | None = None
    policy: PolicyRequest = PolicyRequest()
    options: Mapping[str, object] = field(default_factory=dict)
    max_bytes: int = 64 * 2**20
    tolerance_mm: float = DEFAULT_TOLERANCE_MM


@dataclass
class RewriteJob:
    """A rewrite done: the bytes of each output, the files read (never overwritten), the
    result (texts and report rows) and the warnings to print."""

    files: dict[Path, bytes | bytearray]
    read: list[Path]
    result: Result
    warnings: list[str]

    def summary(self) -> str:
        """One line: how many positions were corrected, left outside, skipped."""
        rows = self.result.rows
        largest, _ = self.result.largest()
        return (
            f"rewrite: {rows.count(CORRECTED)} corrected (largest {largest:.3f} mm), "
            f"{rows.count(OUTSIDE)} outside the grid, {rows.count(SKIPPED)} skipped"
        )


def rewrite_job(req: RewriteRequest) -> RewriteJob:
    """Read everything ``req`` names, rewrite the programs and return what to write."""
    inputs = list(req.outputs)
    plugin = plugin_of(dialect_of(inputs[0]))
    own = {option.key: req.options.get(option.key) for option in plugin.options}
    files = {o.key: Path(own[o.key]) for o in plugin.options if o.file and own[o.key] is not None}
    read = [*inputs, Path(req.cell), *files.values()]
    cell = load_cell(req.cell)
    cell = replace(cell, correction=cell.correction.but(outside=req.policy.outside))
    model_file = Path(req.model) if req.model is not None else cell.model_path
    grid = None  # a model corrects alone when neither --grid nor the cell names one
    if model_file is None or req.grid is not None or cell.grid_path is not None:
        grid = cell.grid_file(req.grid)
    measured = None if grid is None else cell_grid(cell, grid)
    model = nominal = None
    if model_file is not None or (measured is not None and measured.status is None):
        from accugrid.kinematics.robot import load_robot

        nominal = load_robot(cell.robot_name).with_tool(cell.flange_T_tool)
        check_serves(plugin.name, nominal, req.cell)
    if model_file is not None:  # the arm; the tool is the cell's, never the model's TCP
        model = read_model(model_file)
        read.append(model_file)
    # the grid (a residual one with a model) holds in the Status it was measured in
    policy = policy_for(cell, measured, model, req.policy, nominal)
    opts = Options(
        model=policy.grid,
        correction=cell.correction,
        decimals=req.decimals,
        allow_partial=req.policy.allow_partial,
        tool_number=cell.tool_number,
        flange_T_tool=cell.flange_T_tool,
        tool_data=cell.tool_data,
        max_bytes=req.max_bytes,
        tolerance_mm=req.tolerance_mm,
        policy=policy,
        model_file=None if model_file is None else os.fspath(model_file),
        reference_abc=cell.configuration.reference_abc if model is not None else None,
    )
    texts = {os.fspath(p): read_program(p, req.max_bytes) for p in inputs}
    own.update({key: read_program(path, req.max_bytes) for key, path in files.items()})
    context = ProgramContext(own)
    placement = plugin.placement(cell, context)
    del context
    # The readers build their tables from many small strings and tuples; the cycle collector
    # would walk them again and again while they are built, for nothing.
    collecting = gc.isenabled()
    gc.disable()
    try:
        result = rewrite(plugin, texts, opts, placement)
    finally:
        if collecting:
            gc.enable()
    del texts, placement
    files: dict[Path, bytes | bytearray] = {}
    for path, target in req.outputs.items():
        data = result.data.pop(os.fspath(path))  # the new program exists once, as bytes
        if req.header:
            lines = header_lines(result, os.fspath(path), os.fspath(req.cell), opts)
            data = plugin.add_header(data.decode("latin-1"), lines).encode("latin-1")
        files[target] = data
    if req.report is not None:
        # a non-UTF-8 byte in a file name is written as an escape (\\udcff), not refused
        files[req.report] = report_csv(result.rows).encode("utf-8", "backslashreplace")
    warnings = []
    if policy.grid_status is not None and measured is not None and measured.status is None:
        warnings.append(f"the grid does not record its Status: {policy.describe_status()}")
    read += [grid] if grid is not None else []
    if req.report_html is not None:
        files[req.report_html] = _html_report(req, result.rows, read, files, cell, policy)
    return RewriteJob(files, read, result, warnings + warning_lines(result, opts))


def _html_report(req: RewriteRequest, rows, read: list[Path], files, cell, policy) -> bytes:
    """The HTML report of the rewrite (``app.reports.correction``): the ``files`` written with
    their SHA-256, the ``cell``'s robot, tool and base, what the ``policy`` checked, every
    position as written and as rewritten (program frame), its status and reason."""
    from accugrid.app.reports.correction import (
        CORRECTED,
        FLAGGED,
        NOT_CORRECTED,
        SKIPPED,
        cell_setup,
        checks_text,
        correction_report,
    )
    from accugrid.codegen.plugin_types import CORRECTED as DONE
    from accugrid.codegen.plugin_types import OUTSIDE
    from accugrid.infra.digest import sha256_hex

    state = np.full(len(rows.line), SKIPPED, np.int8)
    state[(rows.status == OUTSIDE) | (rows.code != 0)] = NOT_CORRECTED  # as the job rule counts
    done = rows.status == DONE
    state[done] = CORRECTED
    state[done & np.array([bool(r) for r in rows.reason], dtype=bool)] = FLAGGED
    names = [Path(f).name for f in rows.files]

    def label(i: int) -> str:
        return f"{names[rows.file[i]]}:{rows.line[i]} {rows.name[i]}"

    roles = [("program", os.fspath(p)) for p in req.outputs]
    roles += [("cell", req.cell)] + [
        ("grid or model", os.fspath(p)) for p in read[len(roles) + 1 :]
    ]
    new = np.where(np.isnan(rows.new), rows.old, rows.new)
    return correction_report(
        "Rewritten program",
        rows.old,
        new,
        state,
        rows.reason,
        label,
        roles,
        "program frame",
        outputs=[(os.fspath(p), sha256_hex(data)) for p, data in files.items()],
        setup=cell_setup(cell),
        checked=checks_text(policy),
    ).encode("utf-8")
