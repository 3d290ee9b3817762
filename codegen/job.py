"""What ``accugrid krl`` and ``accugrid gcode`` share: read the inputs, build the corrected
program, make the header, report warnings. The dialect commands only render and write."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accugrid.codegen.cell import Cell, load_cell
from accugrid.codegen.header import grid_lines, header_lines, input_line
from accugrid.codegen.points import read_points
from accugrid.codegen.program import Program, build_program, program_status
from accugrid.compensation import GridModel
from accugrid.compensation.model_correction import residual_grid
from accugrid.kinematics.digest import file_sha256
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.robot import Robot, load_robot

__all__ = [
    "Job",
    "add_job_arguments",
    "check_same_robot",
    "grid_path",
    "model_path",
    "prepare",
    "summary",
]


@dataclass
class Job:
    program: Program
    header: list[str]
    inputs: list[Path]  # never overwritten


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
        help="calibrated robot YAML (accugrid identify); overrides the cell's correction.model; "
        "the grid then holds the residual after the model",
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
    parser.add_argument("--force", action="store_true", help="overwrite existing outputs")


def grid_path(args: argparse.Namespace, cell: Cell) -> Path | None:
    """The measurement to correct with: --grid, else the cell's; None with --no-correction."""
    if args.no_correction:
        if args.grid is not None:
            raise InputError("--grid and --no-correction exclude each other")
        return None
    return cell.grid_file(args.grid, ", or use --no-correction")


def model_path(args: argparse.Namespace, cell: Cell) -> Path | None:
    """The calibrated model to correct with: --model, else the cell's correction.model; None
    without either or with --no-correction."""
    model = getattr(args, "model", None)
    if args.no_correction:
        if model is not None:
            raise InputError("--model and --no-correction exclude each other")
        return None
    return Path(model) if model is not None else cell.model_path


def check_same_robot(model: Robot, robot: Robot, path: Path) -> None:
    """InputError when the calibrated ``model`` (file ``path``) is not of ``robot``: its nominal
    DH table must be the cell robot's."""
    a, b = model.dh, robot.dh
    same = all(
        np.allclose(getattr(a, f), getattr(b, f), rtol=0.0, atol=1e-9)
        for f in ("a", "d", "alpha", "theta_offset", "sign")
    )
    if not same:
        raise InputError(
            f"the model is of robot {model.name}, whose nominal DH table is not that of the "
            f"cell's robot {robot.name}",
            path,
        )


def prepare(args: argparse.Namespace, command: str) -> Job:
    """Read POINTS, CELL and the grid; build the program; print its warnings to stderr."""
    cell = load_cell(args.cell)
    if args.allow_config_change:
        cell = dataclasses.replace(cell, allow_config_change=True)
    model_file = model_path(args, cell)
    grid_file = grid_path(args, cell) if model_file is None or args.grid or cell.grid_path else None
    points = read_points(args.points)
    robot = load_robot(cell.robot_name).with_tool(cell.flange_T_tool)
    model = status = None
    if model_file is not None:
        model = load_robot(model_file)
        check_same_robot(model, robot, model_file)
        status = program_status(points, cell, robot) if len(points) else None
    if grid_file is None:
        grid = None
    elif model is None:
        grid = GridModel.from_measurements(grid_file)
    else:
        grid = residual_grid(model, grid_file, status, controller_tool=cell.flange_T_tool)
    program = build_program(points, cell, robot, grid, model, status)
    for warning in program.warnings:
        print(f"accugrid {command}: warning: {warning}", file=sys.stderr)
    largest, hole = program.largest_correction()
    inputs = [input_line("points", args.points, file_sha256(args.points))]
    inputs.append(input_line("cell", args.cell, cell.sha256))
    details = []
    if model_file is not None:
        inputs.append(input_line("model", model_file, file_sha256(model_file)))
        details.append(f"model {model.name}, KUKA Status {status}")
    if grid is not None:
        inputs += grid_lines(Path(grid_file).name, grid.source_sha256, grid.step)
        if model is not None:
            details.append("grid holds the residual after the model")
    elif model is None:
        details = ["grid none (--no-correction): positions are not corrected"]
    where = f" at hole {points.ids[hole]}" if hole is not None else ""
    header = header_lines(command, inputs, details, largest, where, [f"holes {len(program)}"])
    inputs = [Path(args.points), Path(args.cell)] + [f for f in (grid_file, model_file) if f]
    return Job(program, header, inputs)


def summary(job: Job, written: list[Path]) -> str:
    """One line for stdout after writing."""
    largest, _ = job.program.largest_correction()
    names = ", ".join(str(p) for p in written[:3]) + (" ..." if len(written) > 3 else "")
    what = "corrected" if job.program.corrected else "uncorrected"
    return f"wrote {names}: {len(job.program)} holes, {what}, largest correction {largest:.3f} mm"
