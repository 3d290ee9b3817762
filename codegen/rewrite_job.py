"""``accugrid rewrite`` as one call: from what the command line asks (``RewriteRequest``) to the
bytes of every output file (``RewriteJob``). Reads the cell, the grid, the calibrated model and
the programs, rewrites them (``codegen.krl.rewrite`` / ``codegen.gcode.rewrite``, or the
dialect's plug-in, ``codegen.plugin``), adds the
header and makes the report; the command only parses, calls ``rewrite_job``, writes and prints.
"""

from __future__ import annotations

import gc
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accugrid.codegen.cell import load_cell
from accugrid.codegen.dialects import dialect_of, plugin_of
from accugrid.codegen.program_text import add_header, read_program
from accugrid.codegen.rewrite import (
    CORRECTED,
    OUTSIDE,
    SKIPPED,
    Options,
    Result,
    header_lines,
    report_csv,
    warning_lines,
)
from accugrid.compensation.corrector import Corrector

__all__ = ["RewriteJob", "RewriteRequest", "rewrite_job"]


@dataclass
class RewriteRequest:
    """What to rewrite: the programs (a KRL .src/.dat pair or one file) and the output path of
    each, and the options of ``accugrid rewrite`` (``Options`` for their meaning)."""

    outputs: dict[Path, Path]  # input program -> output file, the .src (what runs) first
    cell: str
    grid: str | None = None
    model: str | None = None
    report: Path | None = None
    config_dat: Path | None = None
    header: bool = False
    decimals: int | None = None
    strict: bool = False
    base: int | None = None
    trust_calls: bool = False
    ignore_external_axes: bool = False
    max_bytes: int = 64 * 2**20
    orientation_tol: float = 0.0
    orientation_limit: float = 0.0
    allow_orientation: bool = False
    tolerance_mm: float = 0.0


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
    read = [*inputs, Path(req.cell)] + ([req.config_dat] if req.config_dat else [])
    cell = load_cell(req.cell)
    grid = cell.grid_file(req.grid)
    model_file = Path(req.model) if req.model is not None else cell.model_path
    calibrated = None
    if model_file is not None:  # the model's modules imported only when there is one
        from accugrid.kinematics.calibrated import check_same_robot
        from accugrid.kinematics.robot import load_robot

        calibrated = load_robot(model_file)
        nominal = load_robot(cell.robot_name).with_tool(cell.flange_T_tool)
        check_same_robot(calibrated, nominal, os.fspath(model_file))
        if np.array_equal(calibrated.flange_T_tool, np.eye(4)):  # no TCP in the file: the cell's
            calibrated = calibrated.with_tool(cell.flange_T_tool)
        read.append(model_file)
    # with a model: residual grid in the Status the grid was measured in (wrist flips otherwise)
    corrector = Corrector.build(
        cell.correction,
        grid,
        calibrated,
        cell.configuration.status,
        cell.flange_T_tool if calibrated is not None else None,
    )
    opts = Options(
        model=corrector.grid,
        base_data=cell.base_data,
        robot_T_program=cell.gcode.robot_T_program,
        correction=cell.correction,
        decimals=req.decimals,
        strict=req.strict,
        base_override=req.base,
        tool_number=cell.tool_number,
        trust_calls=req.trust_calls,
        ignore_external_axes=req.ignore_external_axes,
        max_bytes=req.max_bytes,
        orientation_tol=req.orientation_tol,
        orientation_limit=req.orientation_limit,
        allow_orientation=req.allow_orientation,
        tolerance_mm=req.tolerance_mm,
        corrector=corrector,
        model_file=None if model_file is None else os.fspath(model_file),
        reference_abc=cell.configuration.reference_abc if calibrated is not None else None,
    )
    texts = {os.fspath(p): read_program(p, req.max_bytes) for p in inputs}
    # The readers build their tables from many small strings and tuples; the cycle collector
    # would walk them again and again while they are built, for nothing.
    collecting = gc.isenabled()
    gc.disable()
    try:
        name = dialect_of(inputs[0])
        plugin = plugin_of(name)
        if plugin is not None:
            result = plugin.rewrite(texts, opts, cell.dialects[name])
        elif name == "krl":  # each dialect's reader imported when it is needed
            from accugrid.codegen.krl.rewrite import rewrite_krl

            config = read_program(req.config_dat, req.max_bytes) if req.config_dat else None
            result = rewrite_krl(texts, opts, config)
        else:
            from accugrid.codegen.gcode.rewrite import rewrite_gcode

            result = rewrite_gcode(os.fspath(inputs[0]), texts[os.fspath(inputs[0])], opts)
    finally:
        if collecting:
            gc.enable()
    del texts
    files: dict[Path, bytes | bytearray] = {}
    for path, target in req.outputs.items():
        data = result.data.pop(os.fspath(path))  # the new program exists once, as bytes
        if req.header:
            lines = header_lines(result, os.fspath(path), os.fspath(req.cell), opts)
            text, kind = data.decode("latin-1"), dialect_of(path)
            plugin = plugin_of(kind)
            if plugin is None:
                text = add_header(text, lines, kind)
            else:
                text = plugin.add_header(text, lines)
            data = text.encode("latin-1")
        files[target] = data
    if req.report is not None:
        files[req.report] = report_csv(result.rows).encode("utf-8")
    return RewriteJob(files, [*read, grid], result, warning_lines(result, opts))
