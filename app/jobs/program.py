"""The program command of every dialect (``accugrid krl``, ``gcode``, ``rapid``, ...) as one
job over the dialect's plug-in (``codegen.plugin``): read the inputs, build the corrected
program, make the header, render the files, write them (``write_program``). The commands only
parse their arguments into a ``ProgramRequest``."""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from accugrid.codegen.cell import load_cell
from accugrid.codegen.cell_record import Cell
from accugrid.codegen.correction import cell_grid, read_model
from accugrid.codegen.dialects import check_serves, plugin_of
from accugrid.codegen.header import grid_lines, header_lines, input_line
from accugrid.codegen.points import read_points
from accugrid.codegen.program import NOT_CORRECTED, Program, build_program
from accugrid.compensation.policy import PolicyRequest
from accugrid.infra.atomic import check_targets, write_files
from accugrid.infra.digest import file_sha256
from accugrid.infra.errors import InputError
from accugrid.infra.units import check_scale
from accugrid.kinematics.frames import transform_points
from accugrid.kinematics.model import reach_mm
from accugrid.kinematics.robot import load_robot

__all__ = ["Job", "ProgramRequest", "prepare", "program_job", "summary", "write_program"]


@dataclass(frozen=True)
class ProgramRequest:
    """What a program command (``accugrid DIALECT``) asks: the dialect (a name of
    ``codegen.dialects``), the points and cell files, the output (a folder or file, as the
    dialect writes), the grid and model overriding the cell's (``no_correction``: neither),
    ``allow_config_change`` (configuration.allow_change), a templates folder, the policy's
    options (``policy``) and the HTML report with its title."""

    dialect: str
    points: str
    cell: str
    output: Path
    grid: str | None = None
    model: str | None = None
    no_correction: bool = False
    allow_config_change: bool = False
    templates: str | None = None
    policy: PolicyRequest = PolicyRequest()
    report_html: Path | None = None
    report_title: str = ""


@dataclass
class Job:
    """A drilling-program job: the corrected program (its IK check may still run: ``finish``),
    its header lines, the files it read (never overwritten) and, once a dialect rendered it,
    what to write: ``files`` (text or text in pieces, by path, fetched as written), ``main``
    (among them, renamed last, in order) and ``stale`` (an earlier job's files to remove)."""

    program: Program
    header: list[str]
    inputs: list[Path]
    command: str = ""
    files: Mapping[Path, object] = field(default_factory=dict)
    main: list[Path] = field(default_factory=list)
    stale: list[Path] = field(default_factory=list)

    def finish(self) -> None:
        """Wait for the program's IK check (its InputError stops the job before anything is
        replaced: ``write_files(..., ready=job.finish)``) and print the program's warnings to
        stderr."""
        for warning in self.program.wait().warnings:
            print(f"accugrid {self.command}: warning: {warning}", file=sys.stderr)


def _model_path(req: ProgramRequest, cell: Cell) -> Path | None:
    """The calibrated model to correct with: --model, else the cell's correction.model; None
    with --no-correction."""
    if req.no_correction:
        if req.model is not None:
            raise InputError("--model and --no-correction exclude each other")
        return None
    return Path(req.model) if req.model is not None else cell.model_path


def _grid_path(req: ProgramRequest, cell: Cell, model: Path | None = None) -> Path | None:
    """The measurement to correct with: --grid, else the cell's; None with --no-correction, and
    None without one when a ``model`` corrects (the grid is then only its residual)."""
    if req.no_correction:
        if req.grid is not None:
            raise InputError("--grid and --no-correction exclude each other")
        return None
    if req.grid is None and cell.grid_path is None and model is not None:
        return None
    return cell.grid_file(req.grid, ", or use --no-correction")


def prepare(req: ProgramRequest, cell: Cell | None = None) -> tuple[Job, object]:
    """Read POINTS, CELL and the grid; build the corrected program, its IK check started in the
    background (``Job.finish`` waits for it and prints the warnings). The dialect's ``plan``
    runs after reading and before the correction and IK (the heavy work), with a header of as
    many lines as the job's: it refuses there what it could not write; its result is returned
    with the job. ``cell``: CELL when already read. The program keeps the joint angles of every
    pose where the dialect needs them (``Program.joints``)."""
    plugin = plugin_of(req.dialect)
    command = req.dialect
    cell = load_cell(req.cell) if cell is None else cell
    if req.allow_config_change:
        configuration = dataclasses.replace(cell.configuration, allow_change=True)
        cell = dataclasses.replace(cell, configuration=configuration)
    model_file = _model_path(req, cell)
    grid_file = _grid_path(req, cell, model_file)
    points = read_points(req.points)
    grid = None if grid_file is None else cell_grid(cell, grid_file)
    robot = load_robot(cell.robot_name).with_tool(cell.flange_T_tool)
    in_robot = transform_points(cell.robot_T_base, points.xyz)
    check_scale(in_robot, reach_mm(robot), "target", points.path, points.lines)
    check_serves(req.dialect, robot, req.cell)
    # the arm; the tool is the cell's, never the model's TCP
    model = None if model_file is None else read_model(model_file, robot)
    inputs = [input_line("points", req.points, file_sha256(req.points))]
    inputs.append(input_line("cell", req.cell, cell.sha256))
    details = []
    if model_file is not None:
        sha = file_sha256(model_file) if model_file.is_file() else "built-in"
        inputs.append(input_line("model", model_file, sha))
        residual = "" if grid is None else " and the residual grid"
        details.append(f"corrected by model {model.robot.name}{residual}")
    if grid is None and model is None:
        details = [NOT_CORRECTED]
    elif grid is not None:
        inputs += grid_lines(Path(grid_file).name, grid.source_sha256, grid.step)
    closing = [f"holes {len(points)}"]
    plan = plugin.plan(
        cell, len(points), header_lines(command, inputs, details, 0.0, "", closing), req.templates
    )
    program = build_program(
        points,
        cell,
        robot,
        grid,
        model,
        background=True,
        request=req.policy,
        keep_joints=plugin.joints,
    )
    largest, hole = program.largest_correction()
    where = f" at hole {points.ids[hole]}" if hole is not None else ""
    closing += program.uncorrected
    header = header_lines(command, inputs, details, largest, where, closing)
    inputs = [Path(req.points), Path(req.cell)] + ([grid_file] if grid_file else [])
    inputs += [model_file] if model_file is not None and model_file.is_file() else []
    return Job(program, header, inputs, command), plan


def program_job(req: ProgramRequest, cell: Cell | None = None) -> Job:
    """The whole job of ``req``: the corrected program rendered by its dialect into
    ``req.output``, with the HTML report when asked for. The program's IK check still runs:
    write with ``ready=job.finish``."""
    job, plan = prepare(req, cell)
    rendered = plugin_of(req.dialect).render(
        job.program, job.header, req.templates, req.output, plan
    )
    job = dataclasses.replace(job, files=rendered.files, main=rendered.main, stale=rendered.stale)
    return dataclasses.replace(job, files=with_report(job, req.report_html, req.report_title))


def write_program(req: ProgramRequest, force: bool = False) -> str:
    """Refuse existing outputs (without ``force``) before any work, make the job and write it
    as one; the line to print."""
    cell = load_cell(req.cell)
    targets = plugin_of(req.dialect).targets(cell, req.output)
    report = [req.report_html] if req.report_html else []
    inputs = [req.points, req.cell] + ([req.grid] if req.grid else [])
    check_targets(targets + report, inputs, force)
    job = program_job(req, cell)
    written = write_files(
        job.files, job.inputs, force, ready=job.finish, main=job.main, stale=job.stale
    )
    return summary(job, written)


def with_report(job: Job, report: Path | None, title: str) -> Mapping[Path, object]:
    """The job's files plus its HTML report (``app.reports.correction``) at ``report``, written
    last and naming each of them with its SHA-256; the files alone without one. The program's
    files stay rendered on demand (hashed as they are written, not copied). The plan view is in
    the cell's base frame, the points' frame. InputError for an uncorrected program
    (--no-correction: no correction to report)."""
    if not report:
        return job.files
    if job.program.verdict is None:
        raise InputError("--report-html reports the corrections; --no-correction makes none")
    from accugrid.app.reports.correction import (
        ReportedFiles,
        cell_setup,
        checks_text,
        correction_report,
        verdict_states,
    )
    from accugrid.kinematics.frames import transform_points

    roles = ["points", "cell"] + ["grid or model"] * (len(job.inputs) - 2)
    verdict = job.program.verdict
    cell = job.program.cell
    state, reasons = verdict_states(verdict)
    base_T_robot = np.linalg.inv(cell.robot_T_base)

    def page(outputs: list[tuple[str, str]]) -> str:
        return correction_report(
            title,
            transform_points(base_T_robot, verdict.points),
            transform_points(base_T_robot, verdict.command),
            state,
            reasons,
            job.program.points.label,
            list(zip(roles, [str(p) for p in job.inputs], strict=True)),
            f"base frame {cell.base_number}",
            outputs=outputs,
            setup=cell_setup(cell),
            checked=checks_text(verdict.policy),
        )

    return ReportedFiles(job.files, Path(report), page)


def summary(job: Job, written: list[Path]) -> str:
    """One line for stdout after writing."""
    largest, _ = job.program.largest_correction()
    names = ", ".join(str(p) for p in written[:3]) + (" ..." if len(written) > 3 else "")
    what = "corrected" if job.program.corrected else "uncorrected"
    if job.program.uncorrected:
        what += f" but {len(job.program.uncorrected)} (--allow-partial)"
    return f"wrote {names}: {len(job.program)} holes, {what}, largest correction {largest:.3f} mm"
