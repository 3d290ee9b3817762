"""What ``accugrid krl`` and ``accugrid gcode`` share: read the inputs, build the corrected
program, make the header, report warnings. Each dialect's ``job.py`` renders the files into the
``Job``; the commands write them."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from accugrid.app.cli_options import OUTSIDE_WORDS, add_policy, add_table_format
from accugrid.codegen.cell import Cell, load_cell
from accugrid.codegen.header import grid_lines, header_lines, input_line
from accugrid.codegen.points import read_points
from accugrid.codegen.program import Program, build_program
from accugrid.compensation import GridModel
from accugrid.infra.csvtable import declared_or
from accugrid.infra.digest import file_sha256
from accugrid.infra.errors import InputError
from accugrid.kinematics.robot import load_robot

__all__ = ["Job", "add_job_arguments", "grid_path", "prepare", "summary", "with_report"]


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


def add_job_arguments(parser: argparse.ArgumentParser) -> None:
    """The options both dialect commands take (besides -o)."""
    parser.add_argument("points", metavar="POINTS", help="drilling points CSV (BASE frame, mm)")
    parser.add_argument("--cell", required=True, metavar="CELL", help="cell YAML file")
    parser.add_argument(
        "--grid",
        metavar="MEAS",
        help="grid measurement CSV (robot frame, mm); overrides the cell file's grid",
    )
    parser.add_argument(
        "--model",
        metavar="CAL",
        help="calibrated robot YAML (accugrid identify): correct by the model, the grid (if any) "
        "then holds its residual; overrides the cell file's correction.model",
    )
    parser.add_argument(
        "--no-correction",
        action="store_true",
        help="write the nominal (uncorrected) program; no grid is read",
    )
    parser.add_argument(
        "--allow-config-change",
        action="store_true",
        help="let a hole that cannot reach the program's KUKA Status take another one "
        "(same as configuration.allow_change in the cell file)",
    )
    parser.add_argument(
        "--templates",
        metavar="DIR",
        help="folder with your copies of the templates (a copy of templates/ or of its "
        "krl/ or gcode/ folder)",
    )
    add_policy(parser, "holes")
    parser.add_argument(
        "--report-html",
        metavar="FILE",
        help="also write the self-contained HTML report (inputs with SHA-256, a map of the "
        "corrections, the holes flagged or not corrected with the reasons)",
    )
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")
    add_table_format(parser)


def model_path(args: argparse.Namespace, cell: Cell) -> Path | None:
    """The calibrated model to correct with: --model, else the cell's correction.model; None
    with --no-correction."""
    if args.no_correction:
        if args.model is not None:
            raise InputError("--model and --no-correction exclude each other")
        return None
    return Path(args.model) if args.model is not None else cell.model_path


def grid_path(args: argparse.Namespace, cell: Cell, model: Path | None = None) -> Path | None:
    """The measurement to correct with: --grid, else the cell's; None with --no-correction, and
    None without one when a ``model`` corrects (the grid is then only its residual)."""
    if args.no_correction:
        if args.grid is not None:
            raise InputError("--grid and --no-correction exclude each other")
        return None
    if args.grid is None and cell.grid_path is None and model is not None:
        return None
    return cell.grid_file(args.grid, ", or use --no-correction")


def prepare(
    args: argparse.Namespace,
    command: str,
    check: Callable[[Cell, int, list[str]], None] | None = None,
    cell: Cell | None = None,
    joints: bool = False,
) -> Job:
    """Read POINTS, CELL and the grid; build the corrected program, its IK check started in the
    background (``Job.finish`` waits for it and prints the warnings).
    ``check(cell, holes, header)``, when given, runs after reading and before the correction and IK
    (the heavy work), with a header of as many lines as the job's: a dialect refuses there what
    it could not write. ``cell``: CELL when the command already read it. ``joints``: the program
    keeps the joint angles of every pose (``Program.joints``)."""
    cell = load_cell(args.cell) if cell is None else cell
    outside = OUTSIDE_WORDS[getattr(args, "outside", "refuse")]
    cell = dataclasses.replace(cell, correction=cell.correction.but(outside=outside))
    if args.allow_config_change:
        configuration = dataclasses.replace(cell.configuration, allow_change=True)
        cell = dataclasses.replace(cell, configuration=configuration)
    model_file = model_path(args, cell)
    grid_file = grid_path(args, cell, model_file)
    points = read_points(args.points)
    grid = None
    if grid_file is not None:
        grid = GridModel.from_measurements(grid_file, fmt=declared_or(cell.tracker))
    robot = load_robot(cell.robot_name).with_tool(cell.flange_T_tool)
    model = validity = None
    if model_file is not None:  # the arm; the tool is the cell's, never the model's TCP
        from accugrid.app.correct_model import read_model  # model jobs only

        found = read_model(model_file, robot)
        model, validity = found.robot, found.validity
    inputs = [input_line("points", args.points, file_sha256(args.points))]
    inputs.append(input_line("cell", args.cell, cell.sha256))
    details = []
    if model_file is not None:
        sha = file_sha256(model_file) if model_file.is_file() else "built-in"
        inputs.append(input_line("model", model_file, sha))
        residual = "" if grid is None else " and the residual grid"
        details.append(f"corrected by model {model.name}{residual}")
    if grid is None and model is None:
        details = ["grid none (--no-correction): positions are not corrected"]
    elif grid is not None:
        inputs += grid_lines(Path(grid_file).name, grid.source_sha256, grid.step)
    closing = [f"holes {len(points)}"]
    if check is not None:
        check(cell, len(points), header_lines(command, inputs, details, 0.0, "", closing))
    program = build_program(
        points,
        cell,
        robot,
        grid,
        model,
        background=True,
        validity=validity,
        allow_partial=getattr(args, "allow_partial", False),
        strict=getattr(args, "strict", False),
        keep_joints=joints,
    )
    largest, hole = program.largest_correction()
    where = f" at hole {points.ids[hole]}" if hole is not None else ""
    closing += program.uncorrected
    header = header_lines(command, inputs, details, largest, where, closing)
    inputs = [Path(args.points), Path(args.cell)] + ([grid_file] if grid_file else [])
    inputs += [model_file] if model_file is not None and model_file.is_file() else []
    return Job(program, header, inputs, command)


def with_report(job: Job, report: str | None, title: str) -> Mapping[Path, object]:
    """The job's files plus its HTML report (``app.correction_report``) at ``report``;
    the files alone without one. The program's files stay
    rendered on demand (a chain of mappings, not a copy). InputError for an uncorrected
    program (--no-correction: no correction to report)."""
    if not report:
        return job.files
    if job.program.verdict is None:
        raise InputError("--report-html reports the corrections; --no-correction makes none")
    from collections import ChainMap

    from accugrid.app.correction_report import correction_report, verdict_states

    roles = ["points", "cell"] + ["grid or model"] * (len(job.inputs) - 2)
    verdict = job.program.verdict
    state, reasons = verdict_states(verdict)
    page = correction_report(
        title,
        verdict.points,
        verdict.command,
        state,
        reasons,
        job.program.points.label,
        list(zip(roles, [str(p) for p in job.inputs], strict=True)),
    )
    return ChainMap({Path(report): page}, job.files)


def summary(job: Job, written: list[Path]) -> str:
    """One line for stdout after writing."""
    largest, _ = job.program.largest_correction()
    names = ", ".join(str(p) for p in written[:3]) + (" ..." if len(written) > 3 else "")
    what = "corrected" if job.program.corrected else "uncorrected"
    if job.program.uncorrected:
        what += f" but {len(job.program.uncorrected)} (--allow-partial)"
    return f"wrote {names}: {len(job.program)} holes, {what}, largest correction {largest:.3f} mm"
