"""The calibrated robot file: a robot YAML (``kinematics.robot``) with the identified parameters.

It holds the nominal model (``dh``, ``limits_deg``), the identified DH errors (``errors``: per row
Δa mm, Δd mm, Δα rad, Δθ rad), the identified TCP (``tool``: x, y, z mm, a, b, c deg), with
compliance the ``joint_errors`` section (compliance rad/N·m and the gravity model) and an
``identification:`` summary that ``load_robot`` ignores. Loaded, its ``true_robot()`` is the
calibrated arm. Numbers are written with full float precision (shortest round-trip form), so the
reloaded model gives the same FK to the last bit of the DH values.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import yaml

from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import xyzabc_from_pose
from accugrid.kinematics.identification import ControllerMismatch, Identification
from accugrid.kinematics.joint_errors import JointErrors
from accugrid.kinematics.robot import Robot
from accugrid.kinematics.structure import STRUCTURE_WORD, Selection

if TYPE_CHECKING:
    from accugrid.kinematics.model import RobotModel

__all__ = [
    "axes_dict",
    "calibrated_yaml",
    "check_dh_model",
    "check_same_robot",
    "chosen_structure",
    "identification_summary",
    "model_structure",
    "pose_dict",
]

_SAME_TOL = 1e-9  # mm / deg: nominal DH values closer than this are the same robot


def pose_dict(pose: np.ndarray) -> dict[str, float]:
    """A pose (4, 4) mm as YAML data: x, y, z mm, a, b, c KUKA deg."""
    return {k: float(v) for k, v in zip("xyzabc", xyzabc_from_pose(pose), strict=True)}


def axes_dict(values: np.ndarray) -> dict[str, float]:
    """Values (3,) per axis as YAML data: x, y, z."""
    return {axis: float(v) for axis, v in zip("xyz", values, strict=True)}


def identification_summary(
    result: Identification,
    nominal: Robot,
    source: str | None = None,
    sha256: str | None = None,
    selection: Selection | None = None,
    controller: ControllerMismatch | None = None,
) -> dict:
    """The ``identification:`` section: plain data (mm, rad, deg as named) for the YAML;
    ``selection``: the structure chosen by cross-validation (None: DH + TCP and the pinned
    terms, ``--structure dh``); ``controller``: the logged joints' mismatch with the commanded
    positions, written as ``controller_mismatch`` {mean_mm, max_mm, rows} when some row misses
    by more than its printed decimals."""
    parameters = [
        {
            "name": name,
            "value": float(value),
            "std": float(std),
            "unit": unit,
            "identifiable": bool(ok),
        }
        for name, value, std, unit, ok in zip(
            result.names, result.x, result.std, result.units, result.identifiable, strict=True
        )
    ]
    summary: dict = {
        "robot": nominal.name,
        "measurements": {"file": source, "sha256": sha256},
        "controller_tool": pose_dict(nominal.flange_T_tool),
        "poses": result.poses,
        "rows": result.rows,
    }
    if controller is not None and controller.rows:
        summary["controller_mismatch"] = {
            "mean_mm": controller.mean_mm,
            "max_mm": controller.max_mm,
            "rows": controller.rows,
        }
    summary |= {
        "identifiable_parameters": result.rank,
        "unidentifiable_directions": list(result.unidentifiable_text),
        "condition_number": float(result.condition_number),
        "observability_o1": float(result.o1),
        "residual_rms_mm": axes_dict(result.rms_mm),
        "residual_max_mm": axes_dict(result.max_mm),
        "robust_sigma_mm": float(result.sigma_mm),
        "outliers": list(result.outliers),
        "parameters": parameters,
    }
    if result.tracker_T_robot is not None:
        summary["tracker_T_robot"] = pose_dict(result.tracker_T_robot)
    if result.cross_validation is not None:
        cv = result.cross_validation
        summary["cross_validation"] = {
            "folds": cv.folds,
            "predicted_rms_mm": axes_dict(cv.rms_mm),
            "predicted_max_mm": axes_dict(cv.max_mm),
        }
    summary["structure"] = structure_summary(selection)
    return summary


def structure_summary(selection: Selection | None) -> dict:
    """``identification.structure``: the mode (the ``--structure`` word: 'dh', 'auto' or 'search'),
    and unless 'dh' the search (the highest order and why, folds, number of candidate groups), the
    pinned and chosen groups, what was left out and why, the cross-validation curve (held-out RMS
    and max per axis, mm, against the groups added; the first ``kept_steps`` steps are the chosen
    model), the nested estimate and the model held out by joint range (``carry_over``, mm: the
    chosen model and DH + TCP only). Keys: ``robot.STRUCTURE_SCHEMA``."""
    if selection is None:
        return {"mode": "dh"}
    nested = selection.nested
    out = {
        "mode": STRUCTURE_WORD[selection.method],
        "max_order": selection.max_order,
        "max_order_rule": selection.max_order_rule,
        "folds": selection.folds,
        "candidates": selection.candidates,
        "pinned": list(selection.pinned),
        "chosen": list(selection.chosen),
        "left_out": [{"term": name, "reason": why} for name, why in selection.left_out],
        "cv_curve": [
            {
                "added": step.added or "start",
                "parameters": step.parameters,
                "held_out_rms_mm": axes_dict(step.rms_mm),
                "held_out_max_mm": axes_dict(step.max_mm),
            }
            for step in selection.curve
        ],
        "kept_steps": selection.kept,
    }
    if nested is not None:
        out["nested"] = {
            "folds": nested.folds,
            "held_out_rms_mm": axes_dict(nested.rms_mm),
            "held_out_max_mm": axes_dict(nested.max_mm),
            "noise_sigma_mm": None if nested.noise_mm is None else float(nested.noise_mm),
            "model_rms_mm": None if nested.model_rms_mm is None else axes_dict(nested.model_rms_mm),
            "chosen_by_fold": [list(c) for c in nested.chosen],
        }
    if selection.carry_over is not None:
        out["carry_over"] = {
            "held_out_rms_mm": axes_dict(selection.carry_over.rms_mm),
            "dh_held_out_rms_mm": axes_dict(selection.carry_over.dh_rms_mm),
        }
    return out


def calibrated_yaml(robot: Robot, summary: dict | None = None, header: str = "") -> str:
    """YAML text of ``robot`` (nominal DH, limits, tool, errors) plus the ``identification``
    section; ``header``: comment lines put on top (without ``#``)."""
    dh = robot.dh
    doc: dict = {
        "name": robot.name,
        "description": robot.description,
        **({"controller": robot.controller} if robot.controller else {}),
        "dh": [
            {
                "a_mm": float(dh.a[i]),
                "alpha_deg": float(np.degrees(dh.alpha[i])),
                "d_mm": float(dh.d[i]),
                "theta_offset_deg": float(np.degrees(dh.theta_offset[i])),
                "sign": int(dh.sign[i]),
            }
            for i in range(dh.n)
        ],
        "limits_deg": [[float(lo), float(hi)] for lo, hi in robot.joint_limits_deg],
        "tool": pose_dict(robot.flange_T_tool),
    }
    if robot.errors is not None:
        keys = ("da_mm", "dd_mm", "dalpha_rad", "dtheta_rad")
        doc["errors"] = [
            {k: float(v) for k, v in zip(keys, row, strict=True)} for row in robot.errors
        ]
    if robot.joint_errors is not None:
        doc["joint_errors"] = _joint_errors_dict(robot.joint_errors)
    if summary is not None:
        doc["identification"] = summary
    text = yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=100)
    comments = "".join(f"# {line}\n" for line in header.splitlines())
    return comments + text


def _joint_errors_dict(moves: JointErrors) -> dict:
    """The ``joint_errors:`` section ``load_robot`` reads (compliance, masses, gravity moments,
    harmonics, thermal, gravity)."""
    out: dict = {"compliance_rad_per_nm": [float(c) for c in moves.compliance]}
    out["masses"] = [
        {"link": m.link, "kg": float(m.kg), "at_mm": [float(v) for v in m.at_mm]}
        for m in moves.masses
    ]
    if moves.moments is not None:
        out["gravity_moments"] = [
            {
                "axis": int(axis) + 1,
                "link": int(link) + 1,
                "c_kg": float(moves.moments[axis, link, 0]),
                "c_kg_mm": [float(v) for v in moves.moments[axis, link, 1:]],
            }
            for axis, link in zip(*np.nonzero(np.abs(moves.moments).sum(axis=2)), strict=True)
        ]
    if moves.harmonics:
        out["harmonics"] = [
            {
                "axis": h.axis,
                "order": h.order,
                "amplitude_rad": float(h.amplitude_rad),
                "phase_deg": float(np.degrees(h.phase_rad)),
            }
            for h in moves.harmonics
        ]
    if moves.thermal is not None:
        out["thermal"] = {
            "delta_t_k": float(moves.thermal.delta_t_k),
            "expansion_per_k": float(moves.thermal.expansion_per_k),
        }
    out["gravity_mps2"] = float(moves.gravity_mps2)
    return out


def check_dh_model(model: RobotModel, where: str | None = None) -> None:
    """InputError unless ``model`` is a DH robot (a URDF robot has no calibrated model)."""
    if not isinstance(model, Robot):
        raise InputError(
            f"model {model.name} is a URDF robot, not a calibrated DH model "
            "(accugrid identify writes one)",
            where,
        )


def check_same_robot(model: Robot, robot: Robot, where: str | None = None) -> None:
    """InputError unless ``model`` (e.g. a calibrated file) has ``robot``'s nominal DH and
    joint limits (within 1e-9 mm/deg): a model identified on another robot type, or either of
    them a URDF robot (no DH table to compare)."""
    check_dh_model(model, where)
    if not isinstance(robot, Robot):
        raise InputError(
            f"robot {robot.name} is a URDF robot: a calibrated model applies to a DH robot only",
            where,
        )
    a, b = model.dh, robot.dh
    rows = [
        ("a_mm", a.a, b.a),
        ("d_mm", a.d, b.d),
        ("alpha_deg", np.degrees(a.alpha), np.degrees(b.alpha)),
        ("theta_offset_deg", np.degrees(a.theta_offset), np.degrees(b.theta_offset)),
        ("sign", a.sign, b.sign),
    ]
    if a.n != b.n:
        raise InputError(f"model {model.name} has {a.n} axes, robot {robot.name} {b.n}", where)
    for key, mine, theirs in rows:
        off = np.flatnonzero(np.abs(mine - theirs) > _SAME_TOL)
        if off.size:
            i = int(off[0])
            raise InputError(
                f"model {model.name} is of another robot than {robot.name}: dh[{i}].{key} "
                f"{mine[i]:g} vs {theirs[i]:g}",
                where,
            )
    off = np.argwhere(np.abs(model.joint_limits_deg - robot.joint_limits_deg) > _SAME_TOL)
    if off.size:
        i, j = off[0]
        raise InputError(
            f"model {model.name} is of another robot than {robot.name}: limits_deg[{i}][{j}] "
            f"{model.joint_limits_deg[i, j]:g} vs {robot.joint_limits_deg[i, j]:g}",
            where,
        )


def chosen_structure(path, robot: Robot):
    """The joint-error structure a calibrated file (``path``) was fitted with, for planning more
    poses on ``robot`` (its nominal model): (compliance under masses, harmonics (axis, order),
    gravity groups of ``kinematics.candidates``). InputError when the file is of another robot."""
    from accugrid.infra.yamlfile import load_yaml
    from accugrid.kinematics.robot import load_robot

    model = load_robot(path)
    check_same_robot(model, robot, str(path))
    chosen = load_yaml(path).get("identification", "structure", "chosen", default=[]) or []
    return model_structure(model, chosen)


def model_structure(model: Robot, chosen: list[str]):
    """(compliance under masses, harmonics (axis, order), gravity groups) of a calibrated
    ``model`` whose file names the groups ``chosen`` (``identification.structure.chosen``)."""
    from accugrid.kinematics.candidates import gravity_terms

    moves = model.joint_errors
    harmonics = tuple((h.axis, h.order) for h in moves.harmonics) if moves else ()
    compliance = bool(moves is not None and moves.masses and np.any(moves.compliance))
    library = {t.name: t for t in gravity_terms(model)}
    gravity = tuple(library[name] for name in chosen if name in library)  # identify's order
    return compliance, harmonics, gravity
