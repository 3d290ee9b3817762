"""`accugrid correct --model CAL.yaml [--grid MEAS]`: correction by a calibrated robot model.

Every point P (robot frame, mm) at its orientation gets the command P' that the calibrated arm,
driven by the nominal controller in one KUKA Status, takes to P (``compensation.model_correction``,
iterated to 0.001 mm); with ``--grid`` the grid holds the residual after the model and is added.
Orientation: a,b,c columns as given; i,j,k drill axes oriented along the axis nearest ``--abc``;
points without orientation at ``--abc``. The output CSV is the one of ``accugrid correct``.
Tools: without --tool the points are where the SMR the model was measured with is to land (the
file's identification.controller_tool on the controller, the identified TCP on the arm); with
--tool they are where that tool's tip (the drill as taught) is to land, on the calibrated arm.
The verdicts are the correction policy's (``compensation.policy``).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from accugrid.app.jobs.correct import (
    CorrectRequest,
    check_added_columns,
    corrected_file,
    point_status,
)
from accugrid.codegen.correction import read_model
from accugrid.codegen.header import grid_lines, input_line
from accugrid.codegen.points import Points, read_points
from accugrid.compensation.model_correction import TOL_MM
from accugrid.compensation.policy import Policy
from accugrid.infra.atomic import JobFiles
from accugrid.infra.digest import file_sha256
from accugrid.infra.errors import InputError
from accugrid.infra.units import check_scale
from accugrid.kinematics.frames import (
    abc_to_matrix,
    matrix_to_abc,
    orient_along_axes,
    pose_from_xyzabc,
    too_tilted,
)
from accugrid.kinematics.model import reach_mm

if TYPE_CHECKING:
    pass

__all__ = ["correct_by_model", "point_orientations"]

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


def correct_by_model(request: CorrectRequest) -> JobFiles:
    """The ``correct`` job with a model (``corrected.correct_points`` without one): the
    corrected CSV and the printed summary; InputError naming the first point not corrected
    (unless ``allow_partial``)."""
    request.policy.check()
    settings, model_file = request.correction, request.model
    is_file = Path(model_file).is_file()
    model = read_model(model_file)
    calibrated = model.robot
    if request.tool is None:
        tools = model.smr_tools
    else:
        given = pose_from_xyzabc(np.array(request.tool, dtype=float))
        tools = (given, given)
    points = read_points(request.points)
    check_scale(points.xyz, reach_mm(calibrated), "target", points.path, points.lines)
    check_added_columns(points)
    abc = point_orientations(points, np.array(request.abc, dtype=float))
    policy = Policy.build(
        settings,
        request.grid,
        calibrated,
        request.status,
        tools,
        request.repeat_tol_mm,
        points.xyz,
        abc,
        validity=model.validity,
        **request.policy.limits(),
    )
    grid, status = policy.grid, policy.status
    own = point_status(points, None)
    verdict = policy.decide(points.xyz, abc_to_matrix(abc).reshape(-1, 3, 3), status=own)
    sources = [input_line("model", model_file, file_sha256(model_file) if is_file else "-")]
    details = [f"robot {calibrated.name}, KUKA Status {status}"]
    lines = []
    if grid is not None:
        sources += grid_lines(Path(request.grid).name, grid.source_sha256, grid.step)
        details.append(f"residual grid: method {settings.method}, power {settings.power:g}")
        lines.append(grid.describe().replace("grid       ", "residual   ", 1))
        lines.append(policy.describe_status())
    done = verdict.corrected
    miss = np.nanmax(verdict.numbers.get("miss", [0.0]), initial=0.0)
    lines += [
        f"model      {model_file} ({calibrated.name}), KUKA Status {status}",
        f"corrected  {int(done.sum())} point(s), largest miss {miss:.6f} mm (tolerance {TOL_MM:g})",
    ]
    return corrected_file(request, points, verdict, sources, details, lines)
