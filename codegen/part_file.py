"""The part-frame YAML file written by ``accugrid fit-part`` and read by a cell's
``base: {file: PART.yaml, number: N}``.

``base`` holds ``robot_T_base``: keys ``x, y, z`` (mm) and ``a, b, c`` (KUKA ABC, deg). The rest
records the fit: the part's ``scale``, the noise ``sigma_mm`` with its ``dof``, the parameter
``covariance`` about ``centroid`` (translation mm, rotation rad, scale), the largest 95 % bound
``u95_mm`` at the datums, the inputs' SHA-256 and every datum (id, CAD point, measured point in
the robot frame, residual). A cell reads ``base`` and the datums' measured points (to check that
its robot reaches the part).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accugrid import __version__
from accugrid.codegen.cellfile import FRAME_KEYS, CellReader, frame_lines
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import fixed
from accugrid.infra.yamlfile import Schema, load_yaml
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.part_frame import PartFit, reach_mm
from accugrid.kinematics.robot import load_robot

__all__ = ["PART_SCHEMA", "PartFile", "load_part", "part_yaml", "read_base"]

PART_SCHEMA: Schema = {
    "accugrid": None,
    "base": dict.fromkeys(FRAME_KEYS),
    "scale": None,
    "scale_from": None,
    "sigma_mm": None,
    "dof": None,
    "u95_mm": None,
    "centroid": None,
    "covariance": None,
    "inputs": None,
    "datums": [{"id": None, "nominal": None, "measured": None, "residual_mm": None}],
}


@dataclass(frozen=True)
class PartFile:
    """``robot_T_base`` (4, 4) mm of a part file, its datums' ``ids`` and ``measured`` points
    (N, 3) mm in the robot frame, the part's ``scale`` (its size over its CAD size) and the
    frame's ``covariance`` (6, 6) of (translation mm at ``centroid`` (3,) mm robot frame,
    rotation rad) (None: not recorded)."""

    robot_T_base: np.ndarray
    ids: list[str]
    measured: np.ndarray
    scale: float = 1.0
    covariance: np.ndarray | None = None
    centroid: np.ndarray | None = None


def part_yaml(
    fit: PartFit,
    ids: Sequence[str],
    nominal: np.ndarray,
    measured: np.ndarray,
    scale_from: str,
    inputs: Mapping[str, tuple[str, str]],
) -> str:
    """The YAML text of a fitted part frame; ``nominal`` and ``measured`` (N, 3) mm the datums
    (CAD, robot frame), ``scale_from`` how the scale was decided (rigid, fit, cte), ``inputs``
    maps datums/nominal[/frame] to (file name, SHA-256 hex)."""
    u95 = fit.sigma_at(nominal)[1]
    lines = [
        "# Part frame fitted from datums (accugrid fit-part). base is robot_T_base, the part",
        "# frame in the robot frame: x, y, z in mm, a, b, c KUKA ABC in degrees",
        "# (R = Rz(a) Ry(b) Rx(c)). A cell takes it as base: {file: <this file>, number: N}.",
        f"accugrid: {json.dumps(__version__)}",
        "base:",
    ]
    lines += frame_lines(fit.robot_T_base, 6, 8)
    lines += [
        f"scale: {fixed(fit.scale, 9)}  # the part's size over its CAD size",
        f"scale_from: {scale_from}",
        f"sigma_mm: {fixed(fit.sigma_mm, 5)}  # per-axis noise estimated from the residuals",
        f"dof: {fit.dof}",
        f"u95_mm: {fixed(float(u95.max()), 4)}  # largest 95 % bound of the frame at the datums",
        f"centroid: [{', '.join(fixed(v, 4) for v in fit.centroid)}]  # robot frame, mm",
        "covariance:  # about the centroid: translation mm, rotation rad[, scale]",
    ]
    lines += [f"  - [{', '.join(f'{v:.6e}' for v in row)}]" for row in fit.covariance]
    lines.append("inputs:")
    for key, (name, digest) in inputs.items():
        lines.append(f"  {key}: {{file: {json.dumps(str(name))}, sha256: {digest}}}")
    lines.append("datums:")
    for i, name in enumerate(ids):
        lines.append(
            f"  - {{id: {json.dumps(name)}, "
            f"nominal: [{', '.join(fixed(v, 4) for v in nominal[i])}], "
            f"measured: [{', '.join(fixed(v, 4) for v in measured[i])}], "
            f"residual_mm: {fixed(fit.residuals_mm[i], 4)}}}"
        )
    return "\n".join(lines) + "\n"


def load_part(path: str | os.PathLike[str]) -> PartFile:
    """robot_T_base and the datums of a part file; InputError naming the key and line."""
    doc = load_yaml(path)
    doc.check_keys(PART_SCHEMA)
    if "base" not in doc.data:
        raise InputError(
            "missing key 'base' (is this a file written by accugrid fit-part?)", os.fspath(path)
        )
    xyzabc = np.array([doc.number("base", k) for k in FRAME_KEYS])
    datums = doc.get("datums", default=None) or []
    if not isinstance(datums, list):
        raise doc.error("'datums' must be a list", "datums")
    ids = [str(doc.get("datums", i, "id")) for i in range(len(datums))]
    measured = np.array(
        [[doc.number("datums", i, "measured", k) for k in range(3)] for i in range(len(datums))]
    ).reshape(-1, 3)
    scale = doc.number("scale", default=1.0)
    covariance = centroid = None
    if doc.has("covariance") and doc.has("centroid"):
        rows = doc.sequence("covariance")
        size = len(rows)
        if size not in (6, 7):
            raise doc.error("'covariance' must be 6 or 7 rows", "covariance")
        covariance = np.array(
            [[doc.number("covariance", i, j) for j in range(size)] for i in range(size)]
        )[:6, :6]  # a cell's base is rigid: the scale's row is not a frame's
        centroid = np.array([doc.number("centroid", k) for k in range(3)])
    return PartFile(pose_from_xyzabc(xyzabc), ids, measured, scale, covariance, centroid)


SCALE_LIMIT_MM = 0.005  # the largest datum move by a part's scale a rigid cell base may ignore


def read_base(
    r: CellReader, robot: str, flange_T_tool: np.ndarray
) -> tuple[int | None, np.ndarray, PartFile | None]:
    """The cell's ``base``: a frame {x, y, z, a, b, c, number} or a part file {file, number}
    (relative to the cell); (number, robot_T_base (4, 4) mm, the part file, None for a frame).
    A part whose datums lie beyond the
    reach of ``robot`` (a name or path) with ``flange_T_tool`` (its origin, when the file lists no
    datums) is refused at ``base.file``."""
    named = r.frame_file("base", "accugrid fit-part")
    if named is None:
        return (*r.frame(r.top.get("base"), "base", True), None)
    number, name = named
    part = load_part(r.path.parent / name)
    reach = reach_mm(load_robot(robot).with_tool(flange_T_tool))
    points = part.measured if len(part.ids) else part.robot_T_base[None, :3, 3]
    far = np.linalg.norm(points, axis=1)
    worst = int(np.argmax(far))
    if far[worst] > reach:
        what = f"datum {part.ids[worst]}" if worst < len(part.ids) else "the part frame's origin"
        raise r.error(
            "base.file",
            f"{Path(name).name}: {what} lies {far[worst]:.0f} mm from the robot's origin, "
            f"beyond its reach ({reach:.0f} mm): was the part measured in the tracker frame "
            "without fit-part --frame?",
        )
    # A cell's base is rigid: a part of another size than its CAD (a fitted or thermal scale)
    # would put every hole off by (scale - 1) x its distance from the part's origin.
    spread = np.linalg.norm(points - part.robot_T_base[:3, 3], axis=1).max()
    if abs(part.scale - 1.0) * spread > SCALE_LIMIT_MM:
        raise r.error(
            "base.file",
            f"{Path(name).name}: the part is {part.scale:.6f} times its CAD size, which moves its "
            f"datums by up to {abs(part.scale - 1.0) * spread:.3f} mm; a cell's base is rigid: "
            "multiply the CAD coordinates of the datums and the holes by the scale and fit the "
            "part again without --scale/--cte",
        )
    return number, part.robot_T_base, part
