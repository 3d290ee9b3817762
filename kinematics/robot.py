"""Robot models: a standard-DH serial arm (seed Eq. 2) on Pinocchio, in its controller's angles.

A robot is YAML data (``kinematics/robots/*.yaml`` for the built-ins, or a user file): six DH rows
``{a_mm, alpha_deg, d_mm, theta_offset_deg, sign}`` with theta = sign * A + theta_offset, joint
limits ``limits_deg`` ([min, max] per axis), an optional ``tool`` {x, y, z, a, b, c}
(flange_T_tool), ``controller``, the maker of its controller (``kuka``, ``abb``: which program
dialects drive it; absent: any), and optional ``errors`` (per row Δa mm, Δd mm, Δα rad, Δθ rad)
and ``joint_errors`` (compliance under gravity, transmission harmonics, thermal growth;
``kinematics.joint_errors``) that define the "true" robot. A YAML file may instead name a URDF
(``urdf: file``, ``tip: frame``), see ``kinematics.urdf``.

Joint vectors are the controller's axis angles in radians (KUKA A1..A6; ABB axes 1..6 for
``irb6700``, as a RAPID jointtarget holds them), shape (N, 6); poses are (N, 4, 4) mm.

The configuration, its codes and the branch selection of ``Robot.ik``:
``kinematics.configuration``; ``IKSolution``: ``kinematics.model``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path

import numpy as np

from accugrid.infra.errors import InputError
from accugrid.infra.units import mm_text
from accugrid.infra.yamlfile import Schema, YamlDoc, load_yaml
from accugrid.kinematics import ik as closed
from accugrid.kinematics import numeric_ik as numeric
from accugrid.kinematics.configuration import ik_codes, ik_codes_at, select
from accugrid.kinematics.dh import DHTable, flange_poses
from accugrid.kinematics.frames import invert, pose_from_xyzabc, stack_times
from accugrid.kinematics.joint_errors import (
    GRAVITY_MPS2,
    MAX_ORDER,
    Harmonic,
    JointErrors,
    PointMass,
    Thermal,
)
from accugrid.kinematics.model import IKSolution

__all__ = [
    "BUILTIN",
    "ERROR_KEYS",
    "IDENTIFICATION_SCHEMA",
    "JOINT_ERRORS_SCHEMA",
    "ROBOT_SCHEMA",
    "STRUCTURE_SCHEMA",
    "VALIDATED_MAX_KEYS",
    "VALIDITY_KEYS",
    "Robot",
    "load_robot",
]

BUILTIN = ("kr210", "kr210-paper", "kr210-realistic", "irb6700", "r2000ic-165f", "ur10")
_LIMIT_TOL = 1e-9


@dataclass(frozen=True)
class Robot:
    """A serial robot in standard DH form, in its controller's axis angles, with a tool."""

    name: str
    dh: DHTable
    joint_limits_deg: np.ndarray  # (6, 2) [min, max]
    flange_T_tool: np.ndarray = field(default_factory=lambda: np.eye(4))
    errors: np.ndarray | None = None  # (6, 4) Δa mm, Δd mm, Δα rad, Δθ rad of the true robot
    description: str = ""
    joint_errors: JointErrors | None = None  # non-geometric errors of the true robot
    fk_joint_errors: JointErrors | None = None  # δ(q) this robot's own ``fk`` adds (true robots)
    # (3,) mm per axis: the largest held-out error its identification predicts (a calibrated
    # file's cross-validated max, else its fit residual max); None: the model makes no claim
    validated_max_mm: np.ndarray | None = None
    source: str | None = None  # the robot file (for messages); None: built in code
    controller: str = ""  # the maker of its controller, lower case ("kuka", "abb"; "": not said)

    def __repr__(self) -> str:
        parts = [repr(self.name)]
        if self.errors is not None:
            parts.append("DH errors")
        if self.joint_errors is not None:
            parts.append("joint errors")
        if not np.array_equal(self.flange_T_tool, np.eye(4)):
            parts.append(f"tool xyz {mm_text(self.flange_T_tool[:3, 3], 3)} mm")
        return f"Robot({', '.join(parts)})"

    def with_tool(self, flange_T_tool: np.ndarray) -> Robot:
        """The same robot with another tool (4, 4) mm."""
        return replace(self, flange_T_tool=np.array(flange_T_tool, dtype=float).reshape(4, 4))

    def true_robot(self) -> Robot | None:
        """The "real" arm, or None without errors: DH errors added, thermal growth applied, and
        an ``fk`` that adds the joint errors δ(q) to the commanded joints (its ``ik`` does not
        know δ; use it for FK only)."""
        if self.errors is None and self.joint_errors is None:
            return None
        dh = self.dh if self.errors is None else self.dh.with_errors(self.errors)
        moves = None
        if self.joint_errors is not None:
            if self.joint_errors.thermal is not None:
                dh = self.joint_errors.thermal.apply(dh)
            je = self.joint_errors
            if np.any(je.compliance) or je.harmonics or je.moments is not None:
                moves = je
        return Robot(
            f"{self.name} (true)",
            dh,
            self.joint_limits_deg,
            self.flange_T_tool,
            None,
            self.description,
            None,
            moves,
        )

    @property
    def phi_rad(self) -> float:
        """A3 angle (rad) at which the A2 axis, A3 axis and wrist point are in line (stretched):
        the forearm (a3 along x3, d4 along z3) points where the upper arm (a2 along x2) does."""
        beta = np.arctan2(-np.sin(self.dh.alpha[2]) * self.dh.d[3], self.dh.a[2])
        beta -= np.arctan2(0.0, self.dh.a[1])  # pi for an upper arm along -x2 (a UR's)
        return float(closed.wrap(self.dh.axis_angles(np.array([0, 0, -beta, 0, 0, 0]))[2]))

    def fk(self, q: np.ndarray) -> np.ndarray:
        """TCP poses robot_T_tcp (N, 4, 4) mm for joint vectors q (N, 6) rad."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        if self.fk_joint_errors is not None:
            q = q + self.fk_joint_errors.delta(self.dh, q)
        return stack_times(flange_poses(self.dh, q), self.flange_T_tool)

    def fk_pinocchio(self, q: np.ndarray) -> np.ndarray:
        """The same as ``fk`` through Pinocchio, one pose at a time (reference and peer; slow)."""
        import pinocchio as pin

        model, frame = self.pinocchio_model()
        data = model.createData()
        q = np.atleast_2d(np.asarray(q, dtype=float)) * self.dh.sign
        out = np.empty((len(q), 4, 4))
        for k, qk in enumerate(q):
            pin.framesForwardKinematics(model, data, qk)
            out[k] = data.oMf[frame].homogeneous
        return out

    def pinocchio_model(self):
        """(pinocchio.Model, tcp frame id): revolute-Z joints with q_pin = sign * A (rad, mm)."""
        return _pinocchio_model(self.dh, self.joint_limits_deg, self.flange_T_tool)

    def ik(self, robot_T_tcp: np.ndarray, status=None, turn=None, reference=None) -> IKSolution:
        """Joint solutions for TCP poses (N, 4, 4) mm in configuration and sign codes
        (``kinematics.configuration``; int or (N,) ints: KUKA's Status and Turn numbers).

        ``status=None``: basic area and A3 >= phi (code bits 0, 1 = 0, 1), and of the two wrist
        solutions the one closest (sum of squared joint differences, angles wrapped) to the
        reference configuration ``reference`` ((6,) or (N, 6) rad; default KUKA home
        A = 0, -90, 90, 0, 0, 0 deg), i.e. by default the wrist with |A4| + |A6| < 180 deg.
        Per pose this choice still switches branch somewhere (any per-pose rule must); to keep
        one configuration along a path or a grid, give one ``status`` for all poses.
        ``turn=None``: every angle in (-180, 180] (closest to 0).
        An arm without a spherical wrist (a UR) is solved numerically (``kinematics.numeric_ik``):
        ``status`` is then its configuration code (``Configuration``: shoulder + 2 elbow +
        4 wrist) and ``status=None`` takes, of all its solutions, the one nearest ``reference``.
        """
        if closed.closed_form_supported(self.dh):
            flange, wrist = self.flange_wrist(robot_T_tcp)
            q, found, reach = select(self, flange, wrist, status, reference)
        else:  # no spherical wrist: numerical
            poses = np.asarray(robot_T_tcp, dtype=float).reshape(-1, 4, 4)
            flange = stack_times(poses, invert(self.flange_T_tool))
            q, found, reach = numeric.select(self, flange, status, reference)
            wrist = None
        n = len(flange)
        reason = np.full(n, "", dtype=object)
        reason[~found] = "unreachable"
        reason[~found & reach] = "no solution with the requested status"
        if turn is not None:
            want_neg = np.broadcast_to(np.asarray(turn, dtype=int), (n,))[:, None] >> np.arange(6)
            want_neg = (want_neg & 1).astype(bool)
            round_off = ~want_neg & (q < 0) & (q > -_LIMIT_TOL)  # e.g. -1e-17 for an A1 of 0
            q = np.where(round_off, 0.0, q)
            q = np.where(want_neg & (q >= 0), q - 2 * np.pi, q)
            q = np.where(~want_neg & (q < 0), q + 2 * np.pi, q)
        return self.within_limits(q, found, reason, wrist)

    def flange_wrist(self, robot_T_tcp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Flange poses (N, 4, 4) mm and wrist centres (N, 3) mm of TCP poses (N, 4, 4) mm;
        InputError for a DH structure without the closed-form inverse."""
        poses = np.asarray(robot_T_tcp, dtype=float).reshape(-1, 4, 4)
        if not closed.closed_form_supported(self.dh):
            raise InputError(
                f"robot {self.name}: its dh structure has no closed-form inverse (it needs "
                "alpha +-90 deg in rows 1, 3, 4, 5, alpha 0 in row 2, d2 = d3 = a4 = a5 = d5 = 0)",
                self.source,
            )
        flange = stack_times(poses, invert(self.flange_T_tool))
        return flange, closed.wrist_points(self.dh, flange)

    def within_limits(self, q, found, reason, wrist) -> IKSolution:
        """The IKSolution of the chosen joints q (N, 6) rad (found (N,) bool, ``reason`` (N,)
        object, changed in place) with the joint limits applied; wrist centres (N, 3) mm (None:
        from q)."""
        lo, hi = np.radians(self.joint_limits_deg).T
        outside = (q < lo - _LIMIT_TOL) | (q > hi + _LIMIT_TOL)  # NaN (not found): False
        beyond = outside[:, 0].copy()
        for axis in range(1, 6):  # axis by axis: a reduction over the short axis is slow
            beyond |= outside[:, axis]
        beyond = np.flatnonzero(beyond)
        for axis in range(5, -1, -1) if beyond.size else ():  # the lowest axis outside is named
            lo_deg, hi_deg = self.joint_limits_deg[axis]
            hit = beyond[outside[beyond, axis]]
            reason[hit] = f"A{axis + 1} outside limits {lo_deg:g}..{hi_deg:g} deg"
        ok = found.copy()
        ok[beyond] = False
        # after the sign code: A3, A5 may have moved by 360 deg
        final = q if found.all() else np.where(found[:, None], q, 0.0)
        s, t = ik_codes(self, final) if wrist is None else ik_codes_at(self, final, wrist)
        return IKSolution(q, ok, reason, np.where(found, s, -1), np.where(found, t, -1))

    def ik_all(self, robot_T_tcp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """All 8 closed-form solutions (N, 8, 6) rad in (-pi, pi] and their reachability mask
        (N, 8); InputError for a DH structure without the closed-form inverse."""
        return closed.all_solutions(self.dh, self.flange_wrist(robot_T_tcp)[0])


def load_robot(name_or_path: str | os.PathLike[str]) -> Robot:
    """A built-in robot by name (``BUILTIN``) or a robot YAML file by path."""
    text_name = os.fspath(name_or_path)
    if text_name in BUILTIN:
        data = (
            resources.files("accugrid.kinematics")
            .joinpath("robots", f"{text_name}.yaml")
            .read_text()
        )
        return _robot_from_doc(YamlDoc.parse(data, f"<built-in {text_name}>"))
    path = Path(text_name)
    if not path.exists():
        if path.suffix.lower() not in (".yaml", ".yml") and os.sep not in text_name:
            raise InputError(f"unknown robot {text_name!r} (built-in: {', '.join(BUILTIN)})")
        raise InputError("robot file not found", path)
    doc = load_yaml(path)
    if doc.has("urdf"):
        from accugrid.kinematics.urdf import urdf_robot_from_doc

        return urdf_robot_from_doc(doc, path.parent)
    return _robot_from_doc(doc)


_XYZ: Schema = dict.fromkeys("xyz")
_POSE: Schema = dict.fromkeys("xyzabc")
# The ``identification:`` summary of a calibrated file (``calibrated.identification_summary``
# writes it; ``_validated_max`` and ``app.jobs.correct_model`` read it). A key written there is
# declared here.
# ``identification.structure`` (written by ``calibrated.structure_summary`` only)
STRUCTURE_SCHEMA: Schema = {
    "mode": None,
    "max_order": None,
    "max_order_rule": None,
    "folds": None,
    "candidates": None,
    "pinned": None,
    "chosen": None,
    "left_out": [dict.fromkeys(("term", "reason"))],
    "cv_curve": [
        {"added": None, "parameters": None, "held_out_rms_mm": _XYZ, "held_out_max_mm": _XYZ}
    ],
    "kept_steps": None,
    "nested": {
        "folds": None,
        "held_out_rms_mm": _XYZ,
        "held_out_max_mm": _XYZ,
        "noise_sigma_mm": None,
        "model_rms_mm": _XYZ,
        "chosen_by_fold": None,
    },
    "carry_over": {"held_out_rms_mm": _XYZ, "dh_held_out_rms_mm": _XYZ},
}
VALIDITY_KEYS = (  # identification.validity, read by kinematics.validity
    "box_min_mm",
    "box_max_mm",
    "tool_axis",
    "tilt_deg",
    "joints_deg",
    "validated_max_mm",
)
IDENTIFICATION_SCHEMA: Schema = {
    "robot": None,
    "measurements": {"file": None, "sha256": None},
    "controller_tool": _POSE,
    "poses": None,
    "rows": None,
    "controller_mismatch": dict.fromkeys(("mean_mm", "max_mm", "rows")),
    "identifiable_parameters": None,
    "unidentifiable_directions": None,
    "condition_number": None,
    "observability_o1": None,
    "residual_rms_mm": _XYZ,
    "residual_max_mm": _XYZ,
    "robust_sigma_mm": None,
    "outliers": None,
    "parameters": [dict.fromkeys(("name", "value", "std", "unit", "identifiable"))],
    "tracker_T_robot": _POSE,
    "cross_validation": {"folds": None, "predicted_rms_mm": _XYZ, "predicted_max_mm": _XYZ},
    "validity": dict.fromkeys(VALIDITY_KEYS),  # kinematics.validity reads and checks its values
    "structure": STRUCTURE_SCHEMA,
    "support": None,  # kinematics.support reads and checks its keys
    "budget": None,  # compensation.budget reads and checks its keys
}
# ``joint_errors:`` (``_joint_errors_from_doc``)
JOINT_ERRORS_SCHEMA: Schema = {
    "compliance_rad_per_nm": None,
    "masses": [dict.fromkeys(("link", "kg", "at_mm"))],
    "harmonics": [dict.fromkeys(("axis", "order", "amplitude_rad", "phase_deg"))],
    "thermal": dict.fromkeys(("delta_t_k", "expansion_per_k")),
    "gravity_mps2": None,
    "gravity_moments": [dict.fromkeys(("axis", "link", "c_kg", "c_kg_mm"))],
}
ERROR_KEYS = ("da_mm", "dd_mm", "dalpha_rad", "dtheta_rad")  # one ``errors:`` row
# A DH robot file, calibrated or not: every key ``_robot_from_doc`` reads.
ROBOT_SCHEMA: Schema = {
    "name": None,
    "description": None,
    "controller": None,
    "dh": [dict.fromkeys(("a_mm", "alpha_deg", "d_mm", "theta_offset_deg", "sign"))],
    "limits_deg": None,
    "tool": _POSE,
    "errors": [dict.fromkeys(ERROR_KEYS)],
    "joint_errors": JOINT_ERRORS_SCHEMA,
    "identification": IDENTIFICATION_SCHEMA,
}


def _robot_from_doc(doc: YamlDoc) -> Robot:
    doc.check_keys(ROBOT_SCHEMA)
    name = doc.string("name")
    rows = doc.sequence("dh", length=6)
    a, alpha, d, offset, sign = (np.empty(6) for _ in range(5))
    for i in range(len(rows)):
        key = ("dh", i)
        a[i] = doc.number(*key, "a_mm")
        alpha[i] = np.radians(doc.number(*key, "alpha_deg"))
        d[i] = doc.number(*key, "d_mm")
        offset[i] = np.radians(doc.number(*key, "theta_offset_deg", default=0.0))
        sign[i] = doc.number(*key, "sign", default=1.0)
        if sign[i] not in (1.0, -1.0):
            raise doc.error(f"{doc.keyname(*key, 'sign')} must be 1 or -1", *key, "sign")
    limits = np.empty((6, 2))
    doc.sequence("limits_deg", length=6)
    for i in range(6):
        doc.sequence("limits_deg", i, length=2)
        limits[i] = [doc.number("limits_deg", i, 0), doc.number("limits_deg", i, 1)]
        if limits[i, 0] >= limits[i, 1]:
            raise doc.error(
                f"{doc.keyname('limits_deg', i)}: min must be below max", "limits_deg", i
            )
    tool = np.eye(4)
    if doc.has("tool"):
        tool = pose_from_xyzabc([doc.number("tool", k, default=0.0) for k in "xyzabc"])
    errors = None
    if doc.has("errors"):
        doc.sequence("errors", length=6)
        errors = np.array([[doc.number("errors", i, k) for k in ERROR_KEYS] for i in range(6)])
    table = DHTable(a=a, d=d, alpha=alpha, theta_offset=offset, sign=sign)
    description = doc.string("description", default="")
    joint_errors = _joint_errors_from_doc(doc) if doc.has("joint_errors") else None
    validated = _validated_max(doc)
    return Robot(
        name,
        table,
        limits,
        tool,
        errors,
        description,
        joint_errors,
        validated_max_mm=validated,
        source=doc.path,
        controller=doc.string("controller", default="").strip().lower(),
    )


# where in ``identification:`` a calibrated file's validated error stands, the first found wins:
# the nested estimate (a structure chosen from the data), the cross-validation, the fit
VALIDATED_MAX_KEYS = (
    ("structure", "nested", "held_out_max_mm"),
    ("cross_validation", "predicted_max_mm"),
    ("residual_max_mm",),
)


def _validated_max(doc: YamlDoc) -> np.ndarray | None:
    """(3,) mm from a calibrated file's ``identification:`` section (module ``calibrated``):
    the nested cross-validation's held-out max per axis (a structure chosen from the data), else
    the cross-validated held-out max, else the fit's residual max; None without."""
    for key in VALIDATED_MAX_KEYS:
        if doc.has("identification", *key):
            values = np.array([doc.number("identification", *key, axis) for axis in "xyz"])
            if np.any(values < 0):
                axis = "xyz"[int(np.argmax(values < 0))]
                where = ("identification", *key, axis)
                raise doc.error(f"{doc.keyname(*where)} must be >= 0 mm", *where)
            return values
    return None


def _joint_errors_from_doc(doc: YamlDoc) -> JointErrors:
    """The ``joint_errors:`` section: ``compliance_rad_per_nm`` (6 numbers), ``masses`` (list of
    {link 1..6, kg, at_mm [x, y, z]}), ``gravity_moments`` (list of {axis 1..6, link 1..6, c_kg
    rad/(N·m)·kg, c_kg_mm [x, y, z] rad/(N·m)·kg·mm}: compliance × first moments without masses,
    ``kinematics.joint_errors``), ``harmonics`` (list of {axis 1..6, order, amplitude_rad,
    phase_deg}), ``thermal`` {delta_t_k, expansion_per_k}, ``gravity_mps2``."""
    key = "joint_errors"
    doc.get(key, "compliance_rad_per_nm", default={})  # checks that the section is a mapping
    compliance = np.zeros(6)
    if doc.has(key, "compliance_rad_per_nm"):
        doc.sequence(key, "compliance_rad_per_nm", length=6)
        compliance = np.array([doc.number(key, "compliance_rad_per_nm", i) for i in range(6)])
    masses = []
    if doc.has(key, "masses"):
        for i in range(len(doc.sequence(key, "masses"))):
            k = (key, "masses", i)
            link = _whole(doc, 1, 6, *k, "link")
            kg = doc.number(*k, "kg")
            if kg < 0:
                raise doc.error(f"{doc.keyname(*k, 'kg')} must not be negative", *k, "kg")
            doc.sequence(*k, "at_mm", length=3)
            masses.append(PointMass(link, kg, tuple(doc.number(*k, "at_mm", j) for j in range(3))))
    moments = None
    if doc.has(key, "gravity_moments"):
        moments = np.zeros((6, 6, 4))
        for i in range(len(doc.sequence(key, "gravity_moments"))):
            k = (key, "gravity_moments", i)
            axis, link = _whole(doc, 1, 6, *k, "axis"), _whole(doc, 1, 6, *k, "link")
            if link < axis:
                raise doc.error(
                    f"{doc.keyname(*k, 'link')} must be a link the axis carries (>= axis)",
                    *k,
                    "link",
                )
            doc.sequence(*k, "c_kg_mm", length=3)
            moments[axis - 1, link - 1] = [doc.number(*k, "c_kg")] + [
                doc.number(*k, "c_kg_mm", j) for j in range(3)
            ]
    harmonics = []
    if doc.has(key, "harmonics"):
        for i in range(len(doc.sequence(key, "harmonics"))):
            k = (key, "harmonics", i)
            harmonics.append(
                Harmonic(
                    _whole(doc, 1, 6, *k, "axis"),
                    _whole(doc, 0, MAX_ORDER, *k, "order"),
                    doc.number(*k, "amplitude_rad"),
                    np.radians(doc.number(*k, "phase_deg", default=0.0)),
                )
            )
    if np.any(compliance) and not masses:
        raise doc.error(
            f"{doc.keyname(key, 'compliance_rad_per_nm')} needs 'masses' (the gravity model)",
            key,
            "compliance_rad_per_nm",
        )
    thermal = None
    if doc.has(key, "thermal"):
        thermal = Thermal(
            doc.number(key, "thermal", "delta_t_k", default=0.0),
            doc.number(key, "thermal", "expansion_per_k", default=Thermal.expansion_per_k),
        )
    gravity = doc.number(key, "gravity_mps2", default=GRAVITY_MPS2)
    return JointErrors(compliance, tuple(masses), tuple(harmonics), thermal, gravity, moments)


def _whole(doc: YamlDoc, lo: int, hi: int, *keys) -> int:
    """An integer in lo..hi at ``keys``, else a located InputError."""
    value = doc.number(*keys)
    if value != int(value) or not lo <= value <= hi:
        raise doc.error(f"{doc.keyname(*keys)} must be a whole number {lo}..{hi}", *keys)
    return int(value)


def _pinocchio_model(dh: DHTable, limits_deg: np.ndarray, flange_T_tool: np.ndarray):
    import pinocchio as pin

    model = pin.Model()
    parent, placement = 0, pin.SE3.Identity()
    for i in range(dh.n):
        parent = model.addJoint(parent, pin.JointModelRZ(), placement, f"A{i + 1}")
        fixed = _rot_z(dh.theta_offset[i])
        fixed[2, 3] = dh.d[i]
        fixed = fixed @ _trans_x_rot_x(dh.a[i], dh.alpha[i])
        placement = pin.SE3(fixed)
    limits = np.sort(dh.sign[:, None] * np.radians(limits_deg), axis=1)
    model.lowerPositionLimit, model.upperPositionLimit = limits[:, 0].copy(), limits[:, 1].copy()
    flange = model.addFrame(pin.Frame("flange", parent, placement, pin.FrameType.OP_FRAME))
    tcp = pin.SE3(placement.homogeneous @ flange_T_tool)
    frame = model.addFrame(pin.Frame("tcp", parent, flange, tcp, pin.FrameType.OP_FRAME))
    return model, frame


def _rot_z(angle: float) -> np.ndarray:
    out = np.eye(4)
    c, s = np.cos(angle), np.sin(angle)
    out[:2, :2] = [[c, -s], [s, c]]
    return out


def _trans_x_rot_x(a: float, alpha: float) -> np.ndarray:
    out = np.eye(4)
    c, s = np.cos(alpha), np.sin(alpha)
    out[1:3, 1:3] = [[c, -s], [s, c]]
    out[0, 3] = a
    return out
