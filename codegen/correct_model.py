"""`accugrid correct --model CAL.yaml [--grid MEAS]`: correction by a calibrated robot model.

Every point P (robot frame, mm) at its orientation gets the command P' that the calibrated arm,
driven by the nominal controller in one KUKA Status, takes to P (``compensation.model_correction``,
iterated to 0.001 mm); with ``--grid`` the grid holds the residual after the model and is added.
Orientation: a,b,c columns as given; i,j,k drill axes oriented along the axis nearest ``--abc``;
points without orientation at ``--abc``. The output CSV is the one of ``accugrid correct``.
Refused (exit 2, nothing written): a point the nominal controller cannot reach in the Status or
that does not converge, points outside the residual grid (unless --outside clamp), any correction
longer than --max-correction.
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import numpy as np

from accugrid.codegen.atomic import JobFiles
from accugrid.codegen.corrected import (
    CorrectRequest,
    Flags,
    check_added_columns,
    check_outside,
    corrected_file,
)
from accugrid.codegen.header import grid_lines, input_line
from accugrid.codegen.points import Points, read_points
from accugrid.compensation.corrector import Corrector
from accugrid.compensation.model_correction import TOL_MM
from accugrid.kinematics.digest import file_sha256
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.frames import (
    abc_to_matrix,
    matrix_to_abc,
    orient_along_axes,
    pose_from_xyzabc,
    too_tilted,
)
from accugrid.kinematics.robot import load_robot
from accugrid.kinematics.yamlfile import load_yaml

__all__ = ["controller_tool", "correct_by_model", "point_orientations"]

_LISTED = 5


def point_orientations(points: Points, reference_abc: np.ndarray) -> np.ndarray:
    """KUKA A, B, C (N, 3) deg per point: its a,b,c; for i,j,k the rotation about the drill axis
    nearest ``reference_abc`` (3,) deg; without orientation columns the reference itself."""
    reference = abc_to_matrix(np.asarray(reference_abc, dtype=float))
    if points.abc is not None:
        return points.abc
    if points.axis is None:
        return np.tile(np.asarray(reference_abc, dtype=float), (len(points), 1))
    tilted = np.flatnonzero(too_tilted(points.axis, reference))
    if tilted.size:
        i = int(tilted[0])
        raise InputError(
            f"{points.label(i)}: drill axis too far from the --abc tool Z axis to orient",
            *points.table.where(i),
        )
    return matrix_to_abc(orient_along_axes(points.axis, reference))


def controller_tool(model: str, tool: list[float] | None) -> np.ndarray | None:
    """The controller's flange_T_tool (4, 4) mm: ``--tool``, else the ``controller_tool`` the
    calibrated file records (``identification:``, written by ``accugrid identify``), else None
    (the model's identified TCP)."""
    if tool is not None:
        return pose_from_xyzabc(np.array(tool, dtype=float))
    if not Path(model).is_file():
        return None
    doc = load_yaml(model)
    if not doc.has("identification", "controller_tool"):
        return None
    return pose_from_xyzabc([doc.number("identification", "controller_tool", k) for k in "xyzabc"])


def correct_by_model(request: CorrectRequest) -> JobFiles:
    """The ``correct`` job with a model (``correct_points`` dispatches here): the corrected CSV
    and the printed summary; InputError naming the first point not corrected."""
    settings, model_file = request.settings, request.model
    is_file = Path(model_file).is_file()
    calibrated = load_robot(model_file)
    tool = controller_tool(model_file, request.tool)
    points = read_points(request.points)
    check_added_columns(points)
    abc = point_orientations(points, np.array(request.abc, dtype=float))
    corrector = Corrector.build(
        settings,
        request.grid,
        calibrated,
        request.status,
        tool,
        request.repeat_tol_mm,
        points.xyz,
        abc,
    )
    grid, status = corrector.grid, corrector.status
    flags: Flags = defaultdict(list)
    if grid is not None:
        found = corrector.check(points.xyz, abc_to_matrix(abc).reshape(-1, 3, 3))
        check_outside(points, grid, found.outside, settings.outside, flags)
        if found.angle is not None:  # the model holds at any orientation: flag, never refuse
            for i in np.flatnonzero(found.angle > request.orientation_tol_deg):
                flags[int(i)].append(f"orientation {found.angle[i]:.1f} deg from residual grid")
    result = corrector.correct(points.xyz, abc)
    if not result.ok.all():
        bad = result.failed
        named = "; ".join(f"{points.label(int(i))}: {result.reason[i]}" for i in bad[:_LISTED])
        more = f" and {bad.size - _LISTED} more" if bad.size > _LISTED else ""
        raise InputError(
            f"{bad.size} point(s) not corrected by model {calibrated.name} in Status {status}: "
            f"{named}{more}",
            *points.table.where(int(bad[0])),
        )
    sources = [input_line("model", model_file, file_sha256(model_file) if is_file else "-")]
    details = [f"robot {calibrated.name}, KUKA Status {status}"]
    lines = []
    if grid is not None:
        sources += grid_lines(Path(request.grid).name, grid.source_sha256, grid.step)
        details.append(f"residual grid: method {settings.method}, power {settings.power:g}")
        lines.append(grid.describe().replace("grid       ", "residual   ", 1))
    lines += [
        f"model      {model_file} ({calibrated.name}), KUKA Status {status}",
        f"corrected  {len(points)} point(s) in {result.iterations} pass(es), largest miss "
        f"{np.nanmax(result.miss_mm, initial=0.0):.6f} mm (tolerance {TOL_MM:g})",
    ]
    return corrected_file(request, points, result.command, flags, sources, details, lines)
