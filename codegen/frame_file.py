"""The robot-frame YAML file written by ``accugrid fit-frame`` and read by ``accugrid transform``.

The frame is ``tracker_T_robot``: keys ``x, y, z`` (mm) and ``a, b, c`` (KUKA ABC, deg) define it;
the optional ``matrix`` (4×4) is a convenience copy and must agree with them. The fit residuals
and checks are informational and ignored when reading.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping

import numpy as np

from accugrid.codegen import __version__
from accugrid.codegen.textsafe import fixed
from accugrid.kinematics.base_frame import RobotFrameFit
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.fitting import CircleFit
from accugrid.kinematics.frames import pose_from_xyzabc, xyzabc_from_pose
from accugrid.kinematics.yamlfile import load_yaml

__all__ = ["KEYS", "MATRIX_TOL", "frame_yaml", "load_frame"]

KEYS = ("x", "y", "z", "a", "b", "c")
MATRIX_TOL = 1e-6
"""Largest difference accepted between ``matrix`` and the pose from x..c (rotation entries, and
translation in mm scaled by 1/1000, i.e. 1 µm)."""


def _circle_yaml(fit: CircleFit) -> str:
    return (
        f"{{points: {fit.n_points}, radius_mm: {fixed(fit.radius_mm, 4)}, "
        f"arc_deg: {fixed(fit.arc_deg, 2)}, rms_mm: {fixed(fit.rms_mm, 4)}, "
        f"max_mm: {fixed(fit.max_mm, 4)}}}"
    )


def frame_yaml(fit: RobotFrameFit, inputs: Mapping[str, tuple[str, str]]) -> str:
    """The YAML text for a fitted frame; ``inputs`` maps base_plane/a1_circle/flange_holes to
    (file name, SHA-256 hex)."""
    pose = fit.tracker_T_robot
    xyzabc = xyzabc_from_pose(pose)
    lines = [
        "# Robot base frame fitted from laser-tracker points (accugrid fit-frame, seed Sec. 4.1).",
        "# tracker_T_robot is the robot frame in the tracker frame: x, y, z in mm, a, b, c",
        "# KUKA ABC in degrees (R = Rz(a) Ry(b) Rx(c)). A tracker point p maps to the robot",
        "# frame as p_robot = inv(tracker_T_robot) p.",
        f"accugrid: {json.dumps(__version__)}",
        "tracker_T_robot:",
    ]
    lines += [f"  {k}: {fixed(v, 6)}" for k, v in zip(KEYS[:3], xyzabc[:3], strict=True)]
    lines += [f"  {k}: {fixed(v, 8)}" for k, v in zip(KEYS[3:], xyzabc[3:], strict=True)]
    lines.append("  matrix:")
    for row in pose:
        cells = [fixed(v, 10) for v in row[:3]] + [fixed(row[3], 6)]
        lines.append(f"    - [{', '.join(cells)}]")
    lines.append(f"smr_radius_mm: {fixed(fit.base_offset_mm, 4)}")
    lines.append("inputs:")
    for key, (name, digest) in inputs.items():
        lines.append(f"  {key}: {{file: {json.dumps(str(name))}, sha256: {digest}}}")
    plane = fit.plane
    lines += [
        "fits:  # residuals are point-to-plane / point-to-circle distances of the SMR centres",
        f"  base_plane: {{points: {plane.n_points}, rms_mm: {fixed(plane.rms_mm, 4)}, "
        f"max_mm: {fixed(plane.max_mm, 4)}}}",
        f"  a1_circle: {_circle_yaml(fit.a1_circle)}",
        f"  flange_holes: {_circle_yaml(fit.flange_holes)}",
        "checks:",
        f"  axis_tilt_deg: {fixed(fit.axis_tilt_deg, 4)}  # A1 axis vs base-plane normal",
        f"  flange_axis_deg: {fixed(fit.flange_axis_deg, 4)}  # flange-hole circle normal vs "
        "robot X (about 0 at mechanical zero)",
    ]
    return "\n".join(lines) + "\n"


def _number(value: object) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value) if np.isfinite(value) else None


def load_frame(path: str | os.PathLike[str]) -> np.ndarray:
    """Read tracker_T_robot (4, 4) mm from a frame YAML; InputError naming file, line and key."""
    path = os.fspath(path)
    doc = load_yaml(path)
    data = doc.data

    def fail(message: str, *keys: str) -> InputError:
        return InputError(message, path, doc.line(*keys))

    if not isinstance(data, dict) or "tracker_T_robot" not in data:
        raise fail("missing key 'tracker_T_robot' (is this a file written by accugrid fit-frame?)")
    frame = data["tracker_T_robot"]
    if not isinstance(frame, dict):
        raise fail("key 'tracker_T_robot' must be a mapping of x, y, z, a, b, c", "tracker_T_robot")
    values = []
    for key in KEYS:
        if key not in frame:
            raise fail(f"missing key 'tracker_T_robot.{key}'", "tracker_T_robot")
        number = _number(frame[key])
        if number is None:
            raise fail(
                f"key 'tracker_T_robot.{key}' must be a finite number, got {frame[key]!r}",
                "tracker_T_robot",
                key,
            )
        values.append(number)
    pose = pose_from_xyzabc(np.array(values))
    if "matrix" in frame:
        _check_matrix(frame["matrix"], pose, fail)
    return pose


def _check_matrix(matrix: object, pose: np.ndarray, fail) -> None:
    where = ("tracker_T_robot", "matrix")
    rows = matrix if isinstance(matrix, list) else []
    cells = [_number(v) for row in rows if isinstance(row, list) for v in row]
    if len(rows) != 4 or len(cells) != 16 or any(v is None for v in cells):
        raise fail("key 'tracker_T_robot.matrix' must be 4 rows of 4 finite numbers", *where)
    given = np.array(cells, dtype=float).reshape(4, 4)
    scale = np.array([1.0, 1.0, 1.0, 1e-3])
    worst = float(np.max(np.abs(given - pose) * scale))
    if worst > MATRIX_TOL:
        raise fail(
            "key 'tracker_T_robot.matrix' disagrees with x, y, z, a, b, c (largest difference "
            f"{worst:.2e}); edit both or delete the matrix",
            *where,
        )
