"""The tool YAML file written by ``accugrid identify-tool`` and read by a cell's
``tool: {file: TOOL.yaml, number: N}``.

``tool`` holds ``flange_T_tool``: keys ``x, y, z`` (mm, the TCP in the calibrated flange's frame)
and ``a, b, c`` (KUKA ABC, deg). ``sigma`` holds the TCP's 1 sigma per axis (mm) and the drill
axis' (deg, when an axis point was measured). ``measured_on`` records the calibrated model the
tool was measured on (its robot, file name and SHA-256): the TCP belongs to that model's flange,
and a cell whose robot or correction model is another refuses the file.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from accugrid import __version__
from accugrid.codegen.cellfile import FRAME_KEYS, CellReader, frame_lines
from accugrid.infra.digest import file_sha256
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import fixed
from accugrid.infra.yamlfile import Schema, load_yaml
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.tool_calibration import ToolFit

__all__ = ["TOOL_SCHEMA", "read_tool", "tool_yaml"]

TOOL_SCHEMA: Schema = {
    "accugrid": None,
    "tool": dict.fromkeys(FRAME_KEYS),
    "sigma": {"x": None, "y": None, "z": None, "axis_deg": None},
    "noise_mm": None,
    "orientations": None,
    "frame_sensitivity": None,
    "measured_on": {"robot": None, "model": None, "sha256": None},
    "measurements": {"file": None, "sha256": None},
}


def tool_yaml(
    fit: ToolFit, robot: str, model: tuple[str, str], measurements: tuple[str, str]
) -> str:
    """The YAML text of a measured tool; ``robot`` the nominal robot's name, ``model`` and
    ``measurements`` (file name, SHA-256 hex)."""
    lines = [
        "# Tool measured on the calibrated arm (accugrid identify-tool): x, y, z (mm) the TCP in",
        "# the calibrated flange's frame, a, b, c KUKA ABC (deg). A cell takes it as",
        "# tool: {file: <this file>, number: N}; it belongs to the model in measured_on.",
        f"accugrid: {json.dumps(__version__)}",
        "tool:",
    ]
    lines += frame_lines(fit.flange_T_tool, 5, 6)
    lines.append("sigma:  # 1 sigma: TCP per axis mm, drill axis deg per transverse axis")
    lines += [f"  {k}: {fixed(v, 5)}" for k, v in zip("xyz", fit.tip.sigma_mm, strict=True)]
    if fit.axis_sigma_deg is not None:
        lines.append(f"  axis_deg: {fixed(fit.axis_sigma_deg, 5)}")
    lines += [
        f"noise_mm: {fixed(fit.tip.noise_mm, 5)}  # per-axis residual of the tip's pose means",
        f"orientations: {fit.tip.orientations}",
        f"frame_sensitivity: {fixed(fit.tip.frame_sensitivity, 4)}  # of a frame offset in the TCP",
        "measured_on:",
        f"  robot: {json.dumps(robot)}",
        f"  model: {json.dumps(model[0])}",
        f"  sha256: {model[1]}",
        f"measurements: {{file: {json.dumps(measurements[0])}, sha256: {measurements[1]}}}",
    ]
    return "\n".join(lines) + "\n"


def read_tool(
    r: CellReader, robot: str, model_path: str | None
) -> tuple[int | None, np.ndarray, np.ndarray | None]:
    """The cell's ``tool``: a frame {x, y, z, a, b, c, number} or a tool file {file, number}
    (relative to the cell); (number, flange_T_tool (4, 4) mm, the TCP's 1 sigma per axis (3,) mm
    of a tool file, None for a frame). A tool file measured on another
    model than the cell's (``model_path``, its correction model, else ``robot`` when that is a
    YAML path) or, without one, on another robot than ``robot``, is refused at ``tool.file``."""
    named = r.frame_file("tool", "accugrid identify-tool")
    if named is None:
        return (*r.frame(r.top.get("tool"), "tool", True), None)
    number, name = named
    path = r.path.parent / name
    doc = load_yaml(path)
    doc.check_keys(TOOL_SCHEMA)
    if "tool" not in doc.data or "measured_on" not in doc.data:
        raise InputError(
            "missing key 'tool' or 'measured_on' (is this a file written by accugrid "
            "identify-tool?)",
            os.fspath(path),
        )
    pose = pose_from_xyzabc(np.array([doc.number("tool", k) for k in FRAME_KEYS]))
    measured_robot = str(doc.get("measured_on", "robot"))
    measured_model = str(doc.get("measured_on", "model"))
    digest = str(doc.get("measured_on", "sha256"))
    model = model_path or (robot if robot.endswith((".yaml", ".yml")) else None)
    if model is not None and os.path.exists(model):
        if file_sha256(model) != digest:
            raise r.error(
                "tool.file",
                f"{Path(name).name} was measured on the calibrated model {measured_model} "
                f"(SHA-256 {digest[:12]}...), not on the cell's {Path(model).name}: measure the "
                "tool on the model the cell corrects with",
            )
    elif measured_robot != robot:
        raise r.error(
            "tool.file",
            f"{Path(name).name} was measured on robot {measured_robot}, the cell's robot is "
            f"{robot}",
        )
    sigma = None
    if doc.has("sigma"):
        sigma = np.array([doc.number("sigma", k) for k in "xyz"])
    return number, pose, sigma
