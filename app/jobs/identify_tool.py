"""``accugrid identify-tool``: the drill's TCP (and axis) measured on the calibrated arm
(``kinematics.tool_calibration``), written as a tool file (``codegen.tool_file``), with each
dialect's line that sets the tool on its controller."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accugrid.codegen.dialects import DIALECTS, plugin_of
from accugrid.codegen.tool_file import tool_yaml
from accugrid.compensation.measurements import read_measurements
from accugrid.infra.atomic import JobFiles
from accugrid.infra.csvtable import read_table
from accugrid.infra.digest import file_sha256
from accugrid.infra.errors import InputError, printable
from accugrid.infra.yamlfile import load_yaml
from accugrid.kinematics.frames import pose_from_xyzabc, xyzabc_from_pose
from accugrid.kinematics.robot import Robot, load_robot
from accugrid.kinematics.tool_calibration import ToolFit, fit_tool

__all__ = ["POINTS", "ToolRequest", "identify_tool_files"]

POINTS = ("tip", "axis")  # column ``point``: the SMR at the tool's point, or on its drill axis


@dataclass(frozen=True)
class ToolRequest:
    """MEAS (the measurement CSV: x,y,z commanded, x_meas,y_meas,z_meas in the robot frame,
    a1..a6 logged (or a,b,c and s, solved with ``taught``), optional ``point``), the calibrated
    MODEL, the output; ``taught``: the tool as taught (x, y, z mm, a, b, c deg), whose
    orientation is kept without axis rows and whose TCP the logged joints are checked against;
    ``number``: the tool number of the printed lines."""

    measurements: str
    model: str
    output: str
    taught: tuple[float, ...] | None = None
    number: int = 1


def _points(path: str) -> np.ndarray:
    """(N,) bool: the rows whose ``point`` is ``axis`` (all False without the column)."""
    table = read_table(path)
    if not table.has("point"):
        return np.zeros(len(table), dtype=bool)
    words = [cell.strip().lower() for cell in table.text("point")]
    for r, word in enumerate(words):
        if word not in POINTS:
            raise InputError(
                f"point {word!r}: one of {', '.join(POINTS)} (tip: the SMR at the tool's point; "
                "axis: a second point on the drill axis)",
                *table.where(r, "point"),
            )
    return np.array([w == "axis" for w in words])


def identify_tool_files(req: ToolRequest) -> JobFiles:
    """The tool file at ``req.output`` and the lines to print. InputError for a model that is
    not a calibrated DH robot, measurements without logged joints (and without a,b,c and the
    taught tool), joints that do not reproduce the commanded positions with the taught tool, or
    too few orientations (located)."""
    model = load_robot(req.model)
    if not isinstance(model, Robot) or model.errors is None:
        raise InputError(
            "is not a calibrated robot model (accugrid identify writes one)", req.model
        )
    meas = read_measurements(req.measurements)
    if meas.joints is None and req.taught is None:
        raise InputError(
            "identify-tool needs the joints the controller logged at each pose (columns "
            "a1..a6), or a,b,c with the taught --tool to solve them",
            req.measurements,
        )
    is_axis = _points(req.measurements)
    labels = [meas.where(r) for r in range(len(meas.commanded))]
    taught = pose_from_xyzabc(np.array(req.taught if req.taught else [0.0] * 6))
    if req.taught is None:
        q = np.radians(meas.joints)
    else:  # logged joints must reach the commanded TCP with the taught tool; else solved
        q = meas.pose_set(model.with_tool(taught), meas.status).q
    fit = fit_tool(model, q, meas.measured, is_axis, taught[:3, :3], labels, meas.path)
    nominal = str(load_yaml(req.model).get("identification", "robot", default=model.name))
    text = tool_yaml(
        fit,
        nominal,
        (printable(Path(req.model).name), file_sha256(req.model)),
        (printable(Path(req.measurements).name), meas.sha256),
    )
    lines = _summary(req, fit, taught if req.taught is not None else None, labels)
    return JobFiles({req.output: text}, [req.measurements, req.model], lines)


def _summary(
    req: ToolRequest, fit: ToolFit, taught: np.ndarray | None, labels: list[str]
) -> list[str]:
    x, y, z, a, b, c = xyzabc_from_pose(fit.flange_T_tool)
    tip = fit.tip
    worst = int(np.argmax(tip.residuals_mm))
    lines = [
        f"{req.output}: TCP x {x:.4f} y {y:.4f} z {z:.4f} mm (1 sigma {tip.sigma_mm[0]:.4f} mm "
        f"per axis), a {a:.4f} b {b:.4f} c {c:.4f} deg",
        f"tip: {len(tip.residuals_mm)} poses at {tip.orientations} orientations, residual "
        f"{tip.noise_mm:.4f} mm per axis, largest {tip.residuals_mm[worst]:.4f} mm at "
        f"{labels[tip.first_rows[worst]]}; a frame offset enters the TCP by "
        f"{tip.frame_sensitivity:.2f} of itself",
    ]
    if fit.axis is not None:
        length = np.linalg.norm(fit.tip.point_mm - fit.axis.point_mm)
        lines.append(
            f"drill axis: from the axis point {length:.2f} mm behind the tip, 1 sigma "
            f"{fit.axis_sigma_deg:.4f} deg ({fit.axis.orientations} orientations, residual "
            f"{fit.axis.noise_mm:.4f} mm per axis)"
        )
    if taught is not None:
        moved = fit.flange_T_tool[:3, 3] - taught[:3, 3]
        turned = np.degrees(np.arccos(np.clip(fit.flange_T_tool[:3, 2] @ taught[:3, 2], -1.0, 1.0)))
        lines.append(
            f"against the taught tool: TCP moved {' '.join(f'{v:+.4f}' for v in moved)} mm "
            f"({np.linalg.norm(moved):.4f} mm), drill axis turned {turned:.4f} deg"
        )
    for name, dialect in DIALECTS.items():
        lines.append(f"{dialect.title}: {plugin_of(name).tool_line(req.number, fit.flange_T_tool)}")
    lines.append(f"cell: tool: {{file: {os.fspath(req.output)}, number: {req.number}}}")
    return lines
