"""The measurement CSV of a simulated laser-tracker session (``accugrid simulate``): a grid at
one orientation (id,x,y,z,a,b,c,s,x_meas,y_meas,z_meas; s the KUKA Status) or a plan's poses with
the controller's joints (id,x,y,z,a,b,c,s,a1..a6,x_meas,y_meas,z_meas), mm and deg, 4 decimals,
a ``#`` comment line with the settings first; and seed Fig. 3 of the robot's error field.

A corrected points CSV (``accugrid correct``: x,y,z targets, x_cmd,y_cmd,z_cmd commands) given as
the poses is measured after correction: the robot is commanded to x_cmd.. (at each point's a,b,c,
or its i,j,k drill axis oriented as ``correct`` does from ``--abc``) and the rows keep x,y,z, the
targets, beside x_meas.. (id,x,y,z,a,b,c,s,x_meas,y_meas,z_meas): the file ``accugrid validate``
checks.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accugrid.app.reports.plots import fig3_png
from accugrid.compensation.plans import grid_vertices
from accugrid.infra.atomic import JobFiles
from accugrid.infra.csvtable import Table, read_table
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import comment_text, fixed
from accugrid.kinematics.configuration import ik_codes
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.robot import Robot
from accugrid.kinematics.simulation import (
    FIG3_ABC,
    FIG3_Z,
    fig3_field,
    grid_status,
    reached_positions,
    simulate_measurements,
    simulate_pose_measurements,
)

__all__ = ["SimulateRequest", "simulate_files"]

_COMMAND = ("x_cmd", "y_cmd", "z_cmd")  # the command columns of a corrected points CSV


@dataclass(frozen=True)
class SimulateRequest:
    """One ``accugrid simulate`` job with ``robot`` (its tool included): the measurement CSV
    ``output`` of a grid (``region`` xmin..zmax and ``step_mm``, mm, at ``abc`` KUKA deg, one
    KUKA ``status``; None: the IK default's at the first vertex) or of the poses of the plan CSV
    ``poses``; and/or seed Fig. 3 as the PNG ``plot``. Noise: Gaussian sigma per axis (mm) of
    the tracker and of the robot's repeatability, ``repeats`` rows per point, ``seed``."""

    robot: Robot
    output: str | None = None
    plot: str | None = None
    region: tuple[float, ...] | None = None
    step_mm: float | None = None
    poses: str | None = None
    abc: tuple[float, float, float] = (0.0, 90.0, 0.0)
    status: int | None = None
    repeats: int = 1
    noise_tracker_mm: float = 0.0
    noise_repeat_mm: float = 0.0
    seed: int = 0
    smr: tuple[float, float, float] | None = None  # poses: the SMR really on the flange, mm
    smr_axis: tuple[float, float, float] | None = None  # ... on rows whose column point is axis


def simulate_files(request: SimulateRequest) -> JobFiles:
    """The files of the job (the CSV and/or the PNG) and the lines to print (notes, the error
    summary, the Fig. 3 ranges, what was written). InputError on bad settings or an unreachable
    point."""
    if not request.output and not request.plot:
        raise InputError("nothing to do: give -o CSV and/or --plot PNG")
    robot = request.robot
    lines: list[str] = []
    if robot.true_robot() is None:
        lines.append(
            f"note: robot {robot.name} has no parameter errors; the simulated error is noise only"
        )
    files: dict[str, bytes | str] = {}
    if request.output and request.poses and _is_corrected(request.poses):
        files[request.output] = _corrected_measurement_csv(request, lines)
    elif request.output and request.poses:
        files[request.output] = _pose_measurement_csv(request, lines)
    elif request.output:
        files[request.output] = _measurement_csv(request, lines)
    if request.plot:
        xs, ys, error = fig3_field(robot, status=request.status)
        for k, axis in enumerate("XYZ"):
            field = error[:, :, k]
            lines.append(f"  Fig. 3 D_{axis}: min {field.min():.3f}  max {field.max():.3f} mm")
        files[request.plot] = fig3_png(robot.name, xs, ys, error, FIG3_Z, FIG3_ABC)
    lines += [f"wrote {path}" for path in files]
    return JobFiles(files, [request.poses], lines)


def _measurement_csv(request: SimulateRequest, report: list[str]) -> str:
    """The grid measurement CSV; ``report`` gets the notes and the error summary."""
    robot, r = request.robot, request
    if r.region is None or r.step_mm is None:
        raise InputError("-o needs --region XMIN XMAX YMIN YMAX ZMIN ZMAX and --step MM")
    points, notes = grid_vertices(r.region, r.step_mm)
    report += [f"note: {note}" for note in notes]
    status = r.status if r.status is not None else grid_status(robot, points, r.abc)
    if status is not None:
        report.append(f"KUKA Status {status} (binary {status:03b}) for every vertex")
    commanded, measured = simulate_measurements(
        robot,
        points,
        r.abc,
        repeats=r.repeats,
        noise_tracker_mm=r.noise_tracker_mm,
        noise_repeat_mm=r.noise_repeat_mm,
        seed=r.seed,
        status=status,
    )
    error = points - reached_positions(robot, points, r.abc, status)
    report += _summary(robot, len(points), r.repeats, error, commanded - measured)

    region = " ".join(f"{v:g}" for v in r.region)
    header = comment_text(
        f"accugrid simulate: robot {robot.name}, region {region} mm, step {r.step_mm:g} mm, "
        f"abc {' '.join(f'{v:g}' for v in r.abc)} deg, status {status}, repeats {r.repeats}, "
        f"noise tracker {r.noise_tracker_mm:g} mm, repeat {r.noise_repeat_mm:g} mm, "
        f"seed {r.seed}",
        limit=400,
    )
    # the Status the grid was measured in, as column s (a grid holds in it only)
    lines = [
        f"# {header}",
        "id,x,y,z,a,b,c" + ("" if status is None else ",s") + ",x_meas,y_meas,z_meas",
    ]
    abc = ",".join(fixed(v, 4) for v in r.abc) + ("" if status is None else f",{status}")
    ids = np.repeat(np.arange(1, len(points) + 1), r.repeats)
    for ident, cmd, meas in zip(ids, commanded, measured, strict=True):
        cmd_text = ",".join(fixed(v, 4) for v in cmd)
        meas_text = ",".join(fixed(v, 4) for v in meas)
        lines.append(f"P{ident},{cmd_text},{abc},{meas_text}")
    return "\n".join(lines) + "\n"


def _pose_measurement_csv(request: SimulateRequest, report: list[str]) -> str:
    """The measurement CSV of the plan's poses, with the controller's joints a1..a6 and s."""
    robot, r = request.robot, request
    if r.region is not None or r.step_mm is not None:
        raise InputError("--poses and --region/--step exclude each other")
    table = read_table(r.poses)
    table.require(["x", "y", "z", "a", "b", "c"])
    if not len(table):
        raise InputError("no poses in the plan", r.poses)
    xyzabc = table.floats(["x", "y", "z", "a", "b", "c"])
    ids = table.text("id") if table.has("id") else [f"P{i + 1}" for i in range(len(table))]
    smr, points = _smr_points(r, table)
    q, measured = _measure_poses(r, table, xyzabc, smr)
    status_of = ik_codes(robot, q)[0]
    header = comment_text(
        f"accugrid simulate: robot {robot.name}, poses of {Path(r.poses).name}, repeats "
        f"{r.repeats}, noise tracker {r.noise_tracker_mm:g} mm, repeat "
        f"{r.noise_repeat_mm:g} mm, seed {r.seed}",
        limit=400,
    )
    report.append(
        f"{robot.name}: {len(table)} poses x {r.repeats} repeats = {len(table) * r.repeats} rows"
    )
    return _session_csv(header, ids, xyzabc, status_of, np.degrees(q), measured, r.repeats, points)


def _smr_points(r: SimulateRequest, table: Table) -> tuple[np.ndarray | None, list[str] | None]:
    """Where the SMR sits on the flange at each pose (N, 3) mm (None: at the TCP) and the plan's
    column point (None without it): ``smr`` on its tip rows, ``smr_axis`` on its axis rows."""
    words = [w.strip().lower() for w in table.text("point")] if table.has("point") else None
    if r.smr is None:
        if r.smr_axis is not None:
            raise InputError("--smr-axis goes with --smr")
        return None, words
    smr = np.tile(np.asarray(r.smr, dtype=float), (len(table), 1))
    if words is not None and r.smr_axis is not None:
        smr[np.array([w == "axis" for w in words])] = r.smr_axis
    return smr, words


def _measure_poses(
    request: SimulateRequest, table: Table, xyzabc: np.ndarray, smr: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The session at the poses x,y,z,a,b,c (N, 6) mm and KUKA deg of the file ``table``, each
    in its Status (column s, else --status, else the IK default per pose): the controller's
    joints (N, 6) rad and the measured positions (N * repeats, 3) mm; InputError at the file."""
    r = request
    status = r.status
    if table.has("s"):
        status = table.floats(["s"])[:, 0].astype(int)
    try:
        return simulate_pose_measurements(
            r.robot,
            pose_from_xyzabc(xyzabc),
            status,
            repeats=r.repeats,
            noise_tracker_mm=r.noise_tracker_mm,
            noise_repeat_mm=r.noise_repeat_mm,
            seed=r.seed,
            smr_mm=smr,
        )
    except InputError as exc:
        raise InputError(exc.message, r.poses) from None


def _is_corrected(path: str) -> bool:
    """The poses file is a corrected points CSV (it has the command columns x_cmd,y_cmd,z_cmd)."""
    table = read_table(path)
    return all(table.has(name) for name in _COMMAND)


def _corrected_measurement_csv(request: SimulateRequest, report: list[str]) -> str:
    """The tracker session after correction: commanded at x_cmd.., the rows keeping the
    targets x,y,z (id,x,y,z,a,b,c,s,x_meas,y_meas,z_meas)."""
    from accugrid.app.jobs.correct_model import point_orientations
    from accugrid.codegen.points import read_points

    robot, r = request.robot, request
    if r.region is not None or r.step_mm is not None:
        raise InputError("--poses and --region/--step exclude each other")
    points = read_points(r.poses)
    command = points.table.floats(list(_COMMAND))
    abc = point_orientations(points, np.array(r.abc, dtype=float))
    q, measured = _measure_poses(r, points.table, np.hstack([command, abc]))
    status_of = ik_codes(robot, q)[0]
    header = comment_text(
        f"accugrid simulate: robot {robot.name}, after correction: commands of "
        f"{Path(r.poses).name}, targets as x,y,z, repeats {r.repeats}, noise tracker "
        f"{r.noise_tracker_mm:g} mm, repeat {r.noise_repeat_mm:g} mm, seed {r.seed}",
        limit=400,
    )
    report.append(
        f"{robot.name}: {len(points)} corrected points measured at their commands x {r.repeats} "
        f"repeats = {len(points) * r.repeats} rows (x,y,z: the targets)"
    )
    targets = np.hstack([points.xyz, abc])
    return _session_csv(header, points.ids, targets, status_of, None, measured, r.repeats)


def _session_csv(
    header: str,
    ids: list[str],
    poses: np.ndarray,
    status: np.ndarray,
    joints_deg: np.ndarray | None,
    measured: np.ndarray,
    repeats: int,
    points: list[str] | None = None,
) -> str:
    """The measurement CSV of a simulated session: the comment ``header``, then per pose
    (``ids``, x,y,z,a,b,c ``poses`` (N, 6) mm and deg, KUKA ``status`` (N,), the controller's
    ``joints_deg`` (N, 6) or None for no a1..a6 columns) its ``repeats`` consecutive rows of
    ``measured`` (N * repeats, 3) mm, 4 decimals; ``points``: the plan's column point (N,)."""
    columns = "id,x,y,z,a,b,c,s," + ("a1,a2,a3,a4,a5,a6," if joints_deg is not None else "")
    columns += "point," if points is not None else ""
    lines = [f"# {header}", columns + "x_meas,y_meas,z_meas"]
    rows = np.repeat(np.arange(len(poses)), repeats)
    for row, meas in zip(rows, measured, strict=True):
        pose_text = ",".join(fixed(v, 4) for v in poses[row])
        joint_text = (
            "" if joints_deg is None else ",".join(fixed(v, 4) for v in joints_deg[row]) + ","
        )
        meas_text = ",".join(fixed(v, 4) for v in meas)
        ident = comment_text(ids[row], limit=40).replace(",", " ")
        point = "" if points is None else comment_text(points[row], limit=8).replace(",", " ") + ","
        lines.append(f"{ident},{pose_text},{status[row]},{joint_text}{point}{meas_text}")
    return "\n".join(lines) + "\n"


def _summary(
    robot: Robot, n_points: int, repeats: int, error: np.ndarray, measured_error: np.ndarray
) -> list[str]:
    """The error e = P - M (N, 3) mm without noise per axis, and the noise in the rows."""
    norm = np.linalg.norm(error, axis=1)
    out = []
    out.append(
        f"{robot.name}: {n_points} grid points x {repeats} repeats = {n_points * repeats} rows; "
        "error e = P - M (mm) without noise:"
    )
    for k, axis in enumerate("XYZ"):
        out.append(
            f"  e{axis.lower()}: min {error[:, k].min():8.3f}  max {error[:, k].max():8.3f}  "
            f"mean {error[:, k].mean():8.3f}"
        )
    out.append(f"  |e|: mean {norm.mean():.3f}  max {norm.max():.3f}")
    noise = np.linalg.norm(measured_error - np.repeat(error, repeats, axis=0), axis=1)
    out.append(f"  noise in the measured rows: rms {np.sqrt(np.mean(noise**2)):.4f} mm")
    return out
