"""Kinematic identification from laser-tracker positions: DH errors, TCP offset, tracker frame.

The parameter vector x (n,) starts with the 24 DH errors of seed Eq. 2, link-major as
``error_model``: Δa_i mm, Δd_i mm, Δα_i rad, Δθ_i rad for i = 1..6; then the TCP offset in the
flange frame (Δx, Δy, Δz mm, added to the tool's translation); with ``base_frame`` then the
correction of the tracker frame: translation (mm) and rotation vector (rad) of
``T0⁻¹ · tracker_T_robot``, where T0 is the rigid fit of the commanded to the measured positions;
with ``compliance`` the compliance of A2 and A3 (rad/N·m): the arm reaches FK(q + δ) with
δ_j = c_j · τ_j(q), τ the gravity torque of the robot's lumped masses; with ``gravity`` the
parameters of each mass-free gravity group (``kinematics.candidates.GravityTerm``, rad per unit
torque function); with ``harmonics`` last, per
(axis, order) term, the sine and cosine coefficients s, c (rad) of a reducer transmission error
δ_axis += s · sin(order · A_axis) + c · cos(order · A_axis) (``kinematics.joint_errors``, the same
model the calibrated robot's ``true_robot`` applies; the orders come from the reducers' data
sheets or a one-axis spectrum, the coefficients from the fit).

Residuals are positions only: the measured TCP position (in the robot frame, or ``T0⁻¹ ·``
tracker coordinates with ``base_frame``) minus the model's TCP position at the pose's joints, in
mm. The fit is Gauss-Newton (``scipy.optimize.least_squares``, trust region) with the full
nonlinear FK, the analytic DH Jacobian of ``error_model`` and a Huber loss whose scale comes from
the MAD of a first least-squares fit.

Identifiability: the Jacobian at the nominal model, each column scaled to unit RMS, is split by
its SVD; right singular vectors with a singular value below ``RTOL`` times the largest are
unidentifiable directions (position data cannot see them, e.g. link 6 against the TCP offset, Δd2
against Δd3 for the parallel A2/A3 axes, Δd1/Δθ1 against the tracker frame). The fit runs in the
identifiable subspace, so the estimate has no component along those directions ("held at
zero"). A robot's structural directions are those of a spread-out reference pose set; data that
lose more (all poses in one orientation, ...) are refused.

The split between the last link and the TCP: positions see link 6's Δa6, Δd6, Δα6, Δθ6 only
together with the TCP offset (each column is the flange rotation times a vector, which the TCP
columns span), so these four are held at zero (``LAST_LINK``) and the TCP takes the whole
share: the calibrated flange is the nominal last link on the calibrated wrist, and a tool
measured on it (``kinematics.tool_calibration``) carries everything beyond the wrist.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from accugrid.infra.errors import InputError
from accugrid.kinematics.candidates import GravityTerm, reference_joints
from accugrid.kinematics.dh import PARAMETERS, flange_poses
from accugrid.kinematics.error_model import error_jacobian
from accugrid.kinematics.frames import abc_to_matrix, rotation_angle_deg
from accugrid.kinematics.joint_errors import MAX_ORDER, Harmonic, JointErrors, gravity_basis
from accugrid.kinematics.robot import Robot

__all__ = [
    "COMPLIANT_AXES",
    "CONTROLLER_MISMATCH_MAX_MM",
    "LAST_LINK",
    "MAX_HARMONICS",
    "RTOL",
    "ControllerMismatch",
    "CrossValidation",
    "Identification",
    "PoseSet",
    "identification_jacobian",
    "harmonic_terms",
    "identify",
    "parameter_names",
    "parameter_units",
    "linearised",
    "planned_columns",
    "pose_folds",
    "pose_o1",
    "pose_set",
    "rigid_fit",
    "select_poses",
]

LAST_LINK = slice(20, 24)  # Δa6 Δd6 Δα6 Δθ6 in x: held at zero, their share goes to the TCP
COMPLIANT_AXES = (1, 2)  # A2, A3 (0-based): the axes that carry the arm against gravity
RTOL = 1e-7  # singular value / largest below this: unidentifiable direction (scaled Jacobian)
MAX_HARMONICS = 60  # reducer harmonic terms (axis, order) one identification takes at most
OUTLIER_SIGMA = 3.0  # a row is an outlier when an axis residual is beyond this many robust sigmas
OUTLIER_FLOOR_MM = 1e-3  # ... and beyond this (below any tracker's resolution)
PLANE_RATIO = 0.02  # positions whose thinnest principal spread is below this share: one plane
ONE_ORIENTATION_DEG = 1.0  # every pose within this of the first: one orientation
# logged joints farther than this from their commanded position under the nominal model: the
# robot, tool, base or joint columns are wrong (a controller's own calibration: tenths of a mm)
CONTROLLER_MISMATCH_MAX_MM = 5.0
_HUBER = 1.345  # Huber threshold in robust sigmas (95 % efficiency for Gaussian residuals)
_MAD = 1.4826  # MAD to sigma for Gaussian residuals
_FD_RAD = 1e-5  # central-difference step of the tracker-frame rotation columns
_REFERENCE_POSES = 96  # size of the spread-out pose set that gives the structural directions
_GROUP_MM, _GROUP_DEG = 1e-3, 1e-3  # rows this close in commanded pose are repeats of one pose
_SHOW = 5
_HELD_TEXT = "da6 dd6 dalpha6 dtheta6 (in the TCP)"  # LAST_LINK, as identify reports it
_LENGTH = {"a": "mm", "d": "mm", "alpha": "rad", "theta": "rad"}

Terms = tuple[tuple[int, int], ...]  # reducer harmonics to identify: (axis 1..6, order)


def parameter_names(
    base_frame: bool = False,
    compliance: bool = False,
    harmonics: Terms = (),
    gravity: tuple[GravityTerm, ...] = (),
) -> list[str]:
    """Names of the parameters in x order: ``da1 dd1 dalpha1 dtheta1 ... tool_x tool_y tool_z``
    [``base_x base_y base_z base_rx base_ry base_rz``] [``compliance_a2 compliance_a3``]
    [``gravity_a2_forearm_1`` ... per gravity group parameter]
    [``harmonic_a2_k7_sin harmonic_a2_k7_cos`` ... per (axis, order) of ``harmonics``]."""
    names = [f"d{p}{i}" for i in range(1, 7) for p in PARAMETERS]
    names += ["tool_x", "tool_y", "tool_z"]
    if base_frame:
        names += ["base_x", "base_y", "base_z", "base_rx", "base_ry", "base_rz"]
    if compliance:
        names += [f"compliance_a{axis + 1}" for axis in COMPLIANT_AXES]
    for term in gravity:
        stem = term.name.replace(" ", "_").lower()
        names += [f"{stem}_{b + 1}" for b in range(term.size)]
    for axis, order in harmonics:
        names += [f"harmonic_a{axis}_k{order}_{part}" for part in ("sin", "cos")]
    return names


def parameter_units(
    base_frame: bool = False,
    compliance: bool = False,
    harmonics: Terms = (),
    gravity: tuple[GravityTerm, ...] = (),
) -> list[str]:
    """Unit of each parameter in x order: 'mm', 'rad' or 'rad/Nm'."""
    units = [_LENGTH[p] for _ in range(6) for p in PARAMETERS] + ["mm"] * 3
    units += ["mm"] * 3 + ["rad"] * 3 if base_frame else []
    units += ["rad/Nm"] * len(COMPLIANT_AXES) if compliance else []
    units += ["rad"] * sum(term.size for term in gravity)
    return units + ["rad"] * (2 * len(harmonics))


def harmonic_terms(spec: Sequence[tuple[int, int]]) -> Terms:
    """The (axis 1..6, order 1..MAX_ORDER) reducer harmonics to identify, checked, duplicates
    dropped, in the given order. InputError for an axis or order out of range, or more than
    MAX_HARMONICS terms (each costs two parameters and a pose and a half of data)."""
    terms: list[tuple[int, int]] = []
    for axis, order in spec:
        if not 1 <= int(axis) <= 6 or not 1 <= int(order) <= MAX_ORDER:
            raise InputError(
                f"harmonic A{axis} order {order}: axis 1..6 and order 1..{MAX_ORDER} only"
            )
        if (int(axis), int(order)) not in terms:
            terms.append((int(axis), int(order)))
        if len(terms) > MAX_HARMONICS:
            raise InputError(f"more than {MAX_HARMONICS} harmonic terms to identify")
    return tuple(terms)


@dataclass(frozen=True)
class ControllerMismatch:
    """How far the commanded positions lie from the nominal model's FK of the joints the
    controller logged: mean and max over the rows (mm) and how many rows miss by more than the
    round-off of their printed decimals. A controller with its own calibration (a UR's factory
    calibration, a KUKA's absolute-accuracy option, a re-mastered arm) commands its TCP through
    a model that is not the nominal one: the logged joints are what the robot did."""

    mean_mm: float
    max_mm: float
    rows: int


@dataclass(frozen=True)
class PoseSet:
    """Identification data: joints q (N, 6) rad, measured TCP positions (N, 3) mm, the pose group
    of each row (N,) int (repeats of one commanded pose share it), commanded positions (N, 3) mm
    and orientations (N, 3, 3), row labels for messages ('line 12') and the source file."""

    q: np.ndarray
    measured: np.ndarray
    group: np.ndarray
    commanded: np.ndarray
    rotations: np.ndarray
    labels: tuple[str, ...]
    path: str | None = None
    controller: ControllerMismatch | None = None  # None: no logged joints

    def __len__(self) -> int:
        return len(self.q)

    @property
    def poses(self) -> int:
        """Number of distinct commanded poses."""
        return int(self.group.max()) + 1 if len(self.group) else 0


def pose_set(
    robot: Robot,
    commanded: np.ndarray,
    measured: np.ndarray,
    abc_deg: np.ndarray | None = None,
    joints_deg: np.ndarray | None = None,
    status: int | np.ndarray | None = None,
    joint_decimals: np.ndarray | None = None,
    position_decimals: np.ndarray | None = None,
    labels: list[str] | None = None,
    path: str | None = None,
) -> PoseSet:
    """The joints of each measured row: the logged a1..a6 (KUKA deg, (N, 6)) when given, their
    mismatch with the commanded positions (N, 3) mm under the nominal model with the robot's
    tool measured (``ControllerMismatch``; InputError naming rows and the likely fix beyond
    ``CONTROLLER_MISMATCH_MAX_MM``), else the nominal IK of the commanded pose (needs a,b,c
    (N, 3) deg) in ``status`` (one int or (N,) ints; None: the IK default per pose).
    ``*_decimals``: digits printed per cell (the round-off the mismatch allows; default:
    exact). InputError naming rows when a row fails."""
    commanded = np.asarray(commanded, dtype=float).reshape(-1, 3)
    measured = np.asarray(measured, dtype=float).reshape(-1, 3)
    n = len(commanded)
    labels = tuple(labels) if labels is not None else tuple(f"row {i}" for i in range(n))
    if joints_deg is not None:
        q = np.radians(np.asarray(joints_deg, dtype=float).reshape(-1, 6))
        controller = _controller_mismatch(
            robot, q, commanded, joint_decimals, position_decimals, labels, path
        )
        rotations = robot.fk(q)[:, :3, :3]
        if abc_deg is not None:
            rotations = abc_to_matrix(np.asarray(abc_deg, dtype=float).reshape(-1, 3))
        key = np.column_stack([commanded / _GROUP_MM, np.degrees(q) / _GROUP_DEG])
    else:
        if abc_deg is None:
            raise InputError(
                "identification needs each row's orientation: columns a,b,c (or the logged "
                "joints a1..a6)",
                path,
            )
        abc = np.asarray(abc_deg, dtype=float).reshape(-1, 3)
        rotations = abc_to_matrix(abc)
        poses = np.tile(np.eye(4), (n, 1, 1))
        poses[:, :3, :3], poses[:, :3, 3] = rotations, commanded
        sol = robot.ik(poses, status=status)
        bad = np.flatnonzero(~sol.ok)
        if bad.size:
            rows = ", ".join(f"{labels[r]} ({sol.reason[r]})" for r in bad[:_SHOW])
            raise InputError(
                f"{bad.size} of {n} commanded poses have no nominal IK solution for "
                f"{robot.name}" + ("" if status is None else " in the given Status") + f": {rows}",
                path,
            )
        q = sol.q
        key = np.column_stack([commanded / _GROUP_MM, abc / _GROUP_DEG])
        controller = None
    _, group = np.unique(np.round(key), axis=0, return_inverse=True)
    group = group.reshape(-1)
    return PoseSet(q, measured, group, commanded, rotations, labels, path, controller)


def _controller_mismatch(
    robot, q, commanded, joint_decimals, position_decimals, labels, path
) -> ControllerMismatch:
    """The mismatch between the commanded positions (N, 3) mm and the nominal FK of the logged
    joints q (N, 6) rad; rows count where it exceeds the round-off of the printed joints and
    positions (first-order bound). InputError naming the rows and the likely fix where it
    exceeds ``CONTROLLER_MISMATCH_MAX_MM``: no controller calibration is that far off."""
    reached = robot.fk(q)
    off = np.linalg.norm(reached[:, :3, 3] - commanded, axis=1)
    half = np.zeros(q.shape) if joint_decimals is None else 0.5 * 10.0**-joint_decimals
    lever = np.linalg.norm(error_jacobian(robot, q)[:, :3, 3::4], axis=1)  # (N, 6) mm/rad
    allowed = (lever * np.radians(half)).sum(axis=1)
    if position_decimals is not None:
        allowed += np.linalg.norm(0.5 * 10.0 ** -np.asarray(position_decimals), axis=1)
    allowed = 1.5 * allowed + 1e-6
    far = np.flatnonzero(off > CONTROLLER_MISMATCH_MAX_MM)
    if far.size:
        rows = ", ".join(f"{labels[r]} ({off[r]:.4f} mm)" for r in far[:_SHOW])
        raise InputError(
            f"the logged joints a1..a6 of {far.size} of {len(q)} rows miss their commanded "
            f"position under the nominal {robot.name} with this tool by more than "
            f"{CONTROLLER_MISMATCH_MAX_MM:g} mm (a controller's own calibration differs by "
            f"tenths): {rows}; {_likely_fix(robot, reached, commanded)}",
            path,
        )
    return ControllerMismatch(float(off.mean()), float(off.max()), int((off > allowed).sum()))


def _likely_fix(robot: Robot, reached: np.ndarray, commanded: np.ndarray) -> str:
    """What to check when the logged joints miss their commanded positions (N, 3) mm by far:
    the tool when one tool translation (flange frame, least squares over the TCP poses
    ``reached`` (N, 4, 4) mm) brings every row within a tenth of the limit, else the rest."""
    flange = reached @ np.linalg.inv(robot.flange_T_tool)
    rot = flange[:, :3, :3]
    gap = commanded - flange[:, :3, 3]
    tool, *_ = np.linalg.lstsq(rot.reshape(-1, 3), gap.reshape(-1), rcond=None)
    left = np.linalg.norm(gap - rot @ tool, axis=1).max()
    if left <= 0.1 * CONTROLLER_MISMATCH_MAX_MM:
        x, y, z = tool
        return (
            f"a tool at x {x:.3f} y {y:.3f} z {z:.3f} mm on the flange brings every row within "
            f"{left:.3f} mm: is the --tool wrong?"
        )
    return (
        "is the robot or the base wrong (commanded positions must be in the robot frame), or "
        "are the joint columns in another order or unit (a1..a6 in degrees)?"
    )


def identification_jacobian(
    robot: Robot,
    q: np.ndarray,
    x: np.ndarray | None = None,
    base_frame: bool = False,
    compliance: bool = False,
    harmonics: Terms = (),
    gravity: tuple[GravityTerm, ...] = (),
) -> np.ndarray:
    """∂(model TCP position)/∂x: (N, 3, n) mm per parameter unit at joints q (N, 6) rad and
    parameters x (n,) (default 0, the nominal model), for pose planning and ``identify``."""
    model = _Model(robot, base_frame, np.eye(4), compliance, harmonics, gravity)
    x = np.zeros(model.n) if x is None else np.asarray(x, dtype=float)
    return model.jacobian(x, np.atleast_2d(np.asarray(q, dtype=float)))


def _masses(robot: Robot) -> tuple:
    """The robot's gravity model (``joint_errors.masses``) for compliance; InputError if none."""
    masses = () if robot.joint_errors is None else robot.joint_errors.masses
    if not masses:
        raise InputError(
            f"robot {robot.name} has no gravity model: compliance needs joint_errors.masses "
            "(lumped link masses) in the robot YAML"
        )
    return masses


class _Model:
    """The measured-position model of a parameter vector x (layout: module docstring)."""

    def __init__(
        self,
        robot: Robot,
        base_frame: bool,
        base_T0: np.ndarray,
        compliance: bool = False,
        harmonics: Terms = (),
        gravity: tuple[GravityTerm, ...] = (),
    ) -> None:
        self.robot, self.base_frame, self.base_T0 = robot, base_frame, base_T0
        self.masses = _masses(robot) if compliance else ()
        self.compliance, self.harmonics = compliance, tuple(harmonics)
        self.gravity = tuple(gravity)
        self.i_comp = 27 + (6 if base_frame else 0)
        self.i_grav = self.i_comp + (len(COMPLIANT_AXES) if compliance else 0)
        self.i_harm = self.i_grav + sum(term.size for term in self.gravity)
        self.n = self.i_harm + 2 * len(self.harmonics)

    def _gravity_slices(self):
        start = self.i_grav
        for term in self.gravity:
            yield term, slice(start, start + term.size)
            start += term.size

    def joint_errors(self, x: np.ndarray) -> JointErrors | None:
        """The compliance, gravity moments and reducer harmonics of x as ``JointErrors`` (None
        without any)."""
        if not self.compliance and not self.harmonics and not self.gravity:
            return None
        c = np.zeros(6)
        if self.compliance:
            c[list(COMPLIANT_AXES)] = x[self.i_comp : self.i_grav]
        moments = None
        if self.gravity:
            moments = sum(term.moments(x[part]) for term, part in self._gravity_slices())
        terms = []
        for k, (axis, order) in enumerate(self.harmonics):
            s, co = x[self.i_harm + 2 * k : self.i_harm + 2 * k + 2]
            # s·sin(kA) + c·cos(kA) = A·sin(kA + φ) with A = |(s, c)|, φ = atan2(c, s)
            terms.append(Harmonic(axis, order, float(np.hypot(s, co)), float(np.arctan2(co, s))))
        return JointErrors(
            compliance=c, masses=tuple(self.masses), harmonics=tuple(terms), moments=moments
        )

    def arm(self, x: np.ndarray) -> Robot:
        """The nominal robot with the DH errors, TCP offset, compliance and harmonics of x
        applied, as a robot without errors (its ``fk`` is the calibrated arm's)."""
        r = self.robot
        tool = r.flange_T_tool.copy()
        tool[:3, 3] += x[24:27]
        dh = r.dh.with_errors(x[:24].reshape(6, 4))
        return Robot(r.name, dh, r.joint_limits_deg, tool, fk_joint_errors=self.joint_errors(x))

    def _base(self, x: np.ndarray) -> np.ndarray:
        from scipy.spatial.transform import Rotation

        return Rotation.from_rotvec(x[30:33]).as_matrix()

    def positions(self, x: np.ndarray, q: np.ndarray) -> np.ndarray:
        """Model TCP positions (N, 3) mm in the measurement frame (robot frame, or T0⁻¹·tracker)."""
        p = self.arm(x).fk(q)[:, :3, 3]
        if self.base_frame:
            p = p @ self._base(x).T + x[27:30]
        return p

    def jacobian(self, x: np.ndarray, q: np.ndarray) -> np.ndarray:
        """(N, 3, n) derivatives of ``positions`` (the compliance columns hold the gravity
        torques fixed, which is exact in c; their change with the DH errors is ignored; the
        harmonic columns are exact: δ is linear in s, c)."""
        arm = self.arm(x)
        moved = q
        if arm.fk_joint_errors is not None:
            moved = q + arm.fk_joint_errors.delta(arm.dh, q)
        static = Robot(arm.name, arm.dh, arm.joint_limits_deg, arm.flange_T_tool)
        jac = np.empty((len(q), 3, self.n))
        jac[:, :, :24] = error_jacobian(static, moved)[:, :3]
        flange = flange_poses(arm.dh, moved)
        jac[:, :, 24:27] = flange[:, :3, :3]
        if self.compliance:
            torque = arm.fk_joint_errors.gravity_torques(arm.dh, q)  # (N, 6) N·m = ∂δ/∂c
            for k, axis in enumerate(COMPLIANT_AXES):  # ∂p/∂A = sign · ∂p/∂θ (Δθ column)
                column = jac[:, :, 4 * axis + 3] * arm.dh.sign[axis]
                jac[:, :, self.i_comp + k] = column * torque[:, axis, None]
        if self.gravity:
            unit = gravity_basis(arm.dh, q, arm.fk_joint_errors.gravity_mps2)
            for term, part in self._gravity_slices():
                column = jac[:, :, 4 * (term.axis - 1) + 3] * arm.dh.sign[term.axis - 1]
                jac[:, :, part] = column[:, :, None] * term.functions(unit)[:, None, :]
        for k, (axis, order) in enumerate(self.harmonics):
            column = jac[:, :, 4 * (axis - 1) + 3] * arm.dh.sign[axis - 1]
            angle = order * q[:, axis - 1, None]
            jac[:, :, self.i_harm + 2 * k] = column * np.sin(angle)
            jac[:, :, self.i_harm + 2 * k + 1] = column * np.cos(angle)
        if self.base_frame:
            from scipy.spatial.transform import Rotation

            rot = self._base(x)
            rest = np.r_[0:27, self.i_comp : self.n]
            jac[:, :, rest] = rot @ jac[:, :, rest]
            jac[:, :, 27:30] = np.eye(3)
            p = flange[:, :3, :3] @ arm.flange_T_tool[:3, 3] + flange[:, :3, 3]
            for k in range(3):
                step = np.zeros(3)
                step[k] = _FD_RAD
                plus = Rotation.from_rotvec(x[30:33] + step).as_matrix()
                minus = Rotation.from_rotvec(x[30:33] - step).as_matrix()
                jac[:, :, 30 + k] = p @ ((plus - minus) / (2 * _FD_RAD)).T
        return jac


@dataclass(frozen=True)
class CrossValidation:
    """k-fold prediction of held-out poses: residual (measured − model) RMS and max |.| per axis
    (3,) mm over every held-out row, and the number of folds."""

    folds: int
    rms_mm: np.ndarray
    max_mm: np.ndarray


@dataclass(frozen=True)
class Identification:
    """Result of ``identify`` (shapes in the field comments; x layout: module docstring)."""

    robot: Robot  # calibrated: nominal DH, errors (6, 4), tool = identified TCP
    names: list[str]
    units: list[str]
    x: np.ndarray  # (n,) identified parameters
    std: np.ndarray  # (n,) standard deviations (0 along nothing identifiable)
    identifiable: np.ndarray  # (n,) bool: determined alone (no null component, not held at 0)
    null_space: np.ndarray  # (k, n) unidentifiable directions in parameter units (LAST_LINK held)
    singular_values: np.ndarray  # (n,) of the column-scaled Jacobian, descending
    rank: int
    condition_number: float
    o1: float  # Sun & Hollerbach O1 = (σ1 … σL)^(1/L) / √m of the identifiable part, m rows
    residuals: np.ndarray  # (N, 3) measured − model, mm
    sigma_mm: float  # robust residual sigma per axis (MAD)
    outliers: list[str]  # labels of rows beyond OUTLIER_SIGMA
    poses: int
    rows: int
    tracker_T_robot: np.ndarray | None = None  # (4, 4) with base_frame
    cross_validation: CrossValidation | None = None
    unidentifiable_text: list[str] = field(default_factory=list)

    @property
    def rms_mm(self) -> np.ndarray:
        """(3,) residual RMS per axis, mm."""
        return np.sqrt(np.mean(self.residuals**2, axis=0))

    @property
    def max_mm(self) -> np.ndarray:
        """(3,) largest |residual| per axis, mm."""
        return np.abs(self.residuals).max(axis=0)


@dataclass(frozen=True)
class _Subspace:
    scale: np.ndarray  # (n,) column RMS of the nominal Jacobian
    basis: np.ndarray  # (n, r) identifiable directions in scaled coordinates
    null: np.ndarray  # (n, k) unidentifiable directions in scaled coordinates (LAST_LINK held)
    singular: np.ndarray  # (n,)


def _subspace(jac: np.ndarray, rtol: float) -> _Subspace:
    flat = jac.reshape(-1, jac.shape[-1])
    scale = np.sqrt(np.mean(flat**2, axis=0))
    scale = np.where(scale > 1e-12 * scale.max(), scale, 1.0)
    scaled = flat / scale
    scaled[:, LAST_LINK] = 0.0  # the TCP takes their share (module docstring)
    if len(scaled) < len(scale):  # fewer equations than parameters: pad, same directions
        scaled = np.vstack([scaled, np.zeros((len(scale) - len(scaled), len(scale)))])
    _, sing, vt = np.linalg.svd(scaled, full_matrices=False)
    rank = int(np.sum(sing > rtol * sing[0]))
    basis = vt[:rank].T.copy()
    basis[LAST_LINK] = 0.0  # exactly: rounding leaves ~1e-17 there
    # the null space less the held parameters (their unit directions): what the data cannot see
    rest = vt[rank:].T.copy()
    rest[LAST_LINK] = 0.0
    u, size, _ = np.linalg.svd(rest, full_matrices=False)
    return _Subspace(scale, basis, u[:, size > 0.5], sing)


def select_poses(
    robot: Robot,
    q: np.ndarray,
    count: int,
    base_frame: bool = False,
    compliance: bool = False,
    harmonics: Terms = (),
    gravity: tuple[GravityTerm, ...] = (),
) -> tuple[np.ndarray, float]:
    """Greedy D-optimal choice of ``count`` of the candidate joints q (M, 6) rad: each step adds
    the candidate that most increases det(JᵀJ) of the column-scaled identification Jacobian in
    the robot's identifiable subspace (the structural directions of ``identify`` left out).
    Returns the chosen row indices (count,) in choice order and the set's O1 index."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if not 1 <= count <= len(q):
        raise InputError(f"cannot choose {count} poses from {len(q)} candidates")
    model = _Model(robot, base_frame, np.eye(4), compliance, harmonics, gravity)
    reference = _subspace(
        model.jacobian(np.zeros(model.n), reference_joints(robot, _REFERENCE_POSES)), RTOL
    )
    rank = reference.basis.shape[1]
    if count * 3 < rank:
        raise InputError(
            f"{count} poses cannot identify {rank} parameters: choose at least {-(-rank // 3)}"
        )
    # each candidate's 3 rows in the identifiable coordinates (M, 3, r)
    rows = (model.jacobian(np.zeros(model.n), q) / reference.scale) @ reference.basis
    info = 1e-9 * np.eye(rank) * np.mean(rows**2) * 3  # regularised start, tiny against a pose
    inverse = np.linalg.inv(info)
    chosen: list[int] = []
    free = np.ones(len(q), dtype=bool)
    for _ in range(count):
        # det(I + J A⁻¹ Jᵀ) = the factor by which adding a candidate multiplies det(A)
        gain = np.linalg.det(np.eye(3) + rows @ inverse @ np.swapaxes(rows, 1, 2))
        gain[~free] = -np.inf
        best = int(np.argmax(gain))
        chosen.append(best)
        free[best] = False
        j = rows[best]
        middle = np.linalg.inv(np.eye(3) + j @ inverse @ j.T)
        inverse = inverse - inverse @ j.T @ middle @ j @ inverse  # Woodbury
    return np.array(chosen), _o1(rows[chosen])


def pose_o1(
    robot: Robot,
    q: np.ndarray,
    compliance: bool = False,
    harmonics: Terms = (),
    gravity: tuple[GravityTerm, ...] = (),
) -> float:
    """Sun & Hollerbach's O1 of poses q (P, 6) rad for the model ``select_poses`` would choose
    them for: of the column-scaled identification Jacobian in the robot's identifiable subspace."""
    model = _Model(robot, False, np.eye(4), compliance, harmonics, gravity)
    reference = _subspace(
        model.jacobian(np.zeros(model.n), reference_joints(robot, _REFERENCE_POSES)), RTOL
    )
    q = np.atleast_2d(np.asarray(q, dtype=float))
    return _o1((model.jacobian(np.zeros(model.n), q) / reference.scale) @ reference.basis)


def _o1(rows: np.ndarray) -> float:
    """O1 = (σ1 … σr)^(1/r) / √P of the poses' rows (P, 3, r) in identifiable coordinates."""
    sing = np.linalg.svd(rows.reshape(-1, rows.shape[2]), compute_uv=False)
    return float(np.exp(np.mean(np.log(np.maximum(sing, 1e-300)))) / np.sqrt(len(rows)))


def identify(
    robot: Robot,
    data: PoseSet,
    base_frame: bool = False,
    compliance: bool = False,
    folds: int = 0,
    rtol: float = RTOL,
    harmonics: Terms = (),
    gravity: tuple[GravityTerm, ...] = (),
    selected: bool = False,
) -> Identification:
    """Identify the DH errors and TCP offset (and the tracker frame) from ``data``.

    ``robot``: the nominal model with the nominal tool (its own ``errors`` and joint errors
    are not used). ``compliance``: also the compliance of A2, A3 (rad/N·m) under the gravity
    torques of the robot's ``joint_errors.masses``. ``harmonics``: also the sine and cosine
    coefficients (rad) of these (axis 1..6, order) reducer harmonics. ``gravity``: also these
    mass-free gravity groups (``kinematics.candidates``). ``selected``: the joint terms were
    chosen by cross-validation (``kinematics.structure``), which bounds them itself: the poses
    need only outnumber the DH + TCP parameters and give more equations than parameters.
    ``folds`` >= 2 also runs k-fold cross-validation over the distinct poses. InputError for
    too few poses, poses in one plane or one orientation, or data that leave more directions
    unidentifiable than the robot's structural ones.
    """
    base_T0 = rigid_fit(data.commanded, data.measured) if base_frame else np.eye(4)
    target = _in_robot_frame(base_T0, data.measured)
    model = _Model(robot, base_frame, base_T0, compliance, harmonics, gravity)
    names = parameter_names(base_frame, compliance, harmonics, gravity)
    x0 = np.zeros(model.n)
    sub = _subspace(model.jacobian(x0, data.q), rtol)
    reference = _subspace(model.jacobian(x0, reference_joints(robot, _REFERENCE_POSES)), rtol)
    geometric = (
        _subspace(
            model.jacobian(x0, reference_joints(robot, _REFERENCE_POSES))[:, :, : model.i_comp],
            rtol,
        )
        if selected
        else None
    )
    _check_rank(sub, reference, data, names, geometric)
    x, residuals, sigma = _fit(model, sub, data.q, target)
    rows = len(data)
    rank = sub.basis.shape[1]
    a = (model.jacobian(x, data.q).reshape(-1, model.n) / sub.scale) @ sub.basis
    dof = max(3 * rows - rank, 1)
    variance = float(np.sum(residuals**2)) / dof
    cov_z = variance * np.linalg.pinv(a.T @ a)
    directions = sub.basis / sub.scale[:, None]
    std = np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", directions, cov_z, directions), 0.0))
    identifiable = np.linalg.norm(sub.null, axis=1) < 1e-6
    identifiable[LAST_LINK] = False
    kept = sub.singular[:rank]
    null = _readable_null(sub.null)
    outliers = _outliers(residuals, sigma, data.labels)
    tracker = None
    if base_frame:
        from scipy.spatial.transform import Rotation

        correction = np.eye(4)
        correction[:3, :3] = Rotation.from_rotvec(x[30:33]).as_matrix()
        correction[:3, 3] = x[27:30]
        tracker = base_T0 @ correction
    cv = _cross_validate(model, sub, data, target, folds, selected) if folds else None
    arm = model.arm(x)
    calibrated = Robot(
        f"{robot.name}-calibrated",
        robot.dh,
        robot.joint_limits_deg,
        arm.flange_T_tool,
        x[:24].reshape(6, 4).copy(),
        f"{robot.name} calibrated by accugrid identify from {data.poses} poses",
        arm.fk_joint_errors,
        validated_max_mm=np.abs(residuals).max(axis=0) if cv is None else cv.max_mm,
        controller=robot.controller,
    )
    return Identification(
        robot=calibrated,
        names=names,
        units=parameter_units(base_frame, compliance, harmonics, gravity),
        x=x,
        std=std,
        identifiable=identifiable,
        null_space=(null / sub.scale[:, None]).T,
        singular_values=sub.singular,
        rank=rank,
        condition_number=float(kept[0] / kept[-1]),
        o1=float(np.exp(np.mean(np.log(kept))) / np.sqrt(rows)),  # m: measured rows
        residuals=residuals,
        sigma_mm=sigma,
        outliers=outliers,
        poses=data.poses,
        rows=rows,
        tracker_T_robot=tracker,
        cross_validation=cv,
        unidentifiable_text=[_direction_text(v, names) for v in null.T] + [_HELD_TEXT],
    )


def _fit(model: _Model, sub: _Subspace, q: np.ndarray, target: np.ndarray):
    """Least squares, then Huber with the MAD scale: (x (n,), residuals (N, 3), sigma mm)."""
    from scipy.optimize import least_squares

    directions = sub.basis / sub.scale[:, None]  # (n, r): x = directions @ z

    def fun(z):
        return (target - model.positions(directions @ z, q)).ravel()

    def jac(z):
        return -(model.jacobian(directions @ z, q).reshape(-1, model.n) @ directions)

    z = np.zeros(directions.shape[1])
    tol = dict(xtol=1e-14, ftol=1e-14, gtol=1e-14, max_nfev=100)
    z = least_squares(fun, z, jac=jac, method="trf", **tol).x
    residuals = fun(z)
    sigma = max(_MAD * float(np.median(np.abs(residuals - np.median(residuals)))), 1e-9)
    z = least_squares(fun, z, jac=jac, method="trf", loss="huber", f_scale=_HUBER * sigma, **tol).x
    residuals = fun(z).reshape(-1, 3)
    sigma = max(_MAD * float(np.median(np.abs(residuals - np.median(residuals)))), 1e-9)
    return directions @ z, residuals, sigma


def _cross_validate(
    model: _Model, sub: _Subspace, data: PoseSet, target, folds: int, selected: bool = False
):
    """k-fold over the distinct poses (repeats stay together), fitted in the identifiable
    subspace of all data: the held-out residuals' RMS and max per axis (``CrossValidation``).
    A fold must keep as many poses as parameters (``selected``: more equations than them)."""
    if folds < 2 or folds > data.poses:
        raise InputError(f"--folds must be between 2 and the {data.poses} poses, got {folds}")
    fold = pose_folds(data.poses, folds)[data.group]
    rank = sub.basis.shape[1]
    held = np.empty_like(target)
    for k in range(folds):
        train = fold != k
        kept = len(np.unique(data.group[train]))
        if (3 * kept <= rank) if selected else (kept < rank):
            raise InputError(
                f"{folds}-fold cross-validation leaves fewer poses than the {rank} identifiable "
                "parameters per fit; use fewer folds"
            )
        x, _, _ = _fit(model, sub, data.q[train], target[train])
        held[~train] = target[~train] - model.positions(x, data.q[~train])
    return CrossValidation(folds, np.sqrt(np.mean(held**2, axis=0)), np.abs(held).max(axis=0))


def pose_folds(poses: int, folds: int, seed: int = 0) -> np.ndarray:
    """The fold (poses,) int 0..folds-1 of each distinct pose: a fixed permutation from
    ``numpy.random.default_rng(seed)`` dealt round-robin (sizes differ by at most one)."""
    order = np.random.default_rng(seed).permutation(poses)
    fold_of_pose = np.empty(poses, dtype=int)
    fold_of_pose[order] = np.arange(poses) % folds
    return fold_of_pose


def linearised(
    robot: Robot,
    data: PoseSet,
    result: Identification,
    base_frame: bool = False,
    compliance: bool = False,
    harmonics: Terms = (),
    candidates: Terms = (),
    gravity: tuple[GravityTerm, ...] = (),
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The identification of ``result`` (fitted with ``base_frame``, ``compliance``, ``harmonics``)
    linearised for a search over more terms: its residuals y (3N,) mm (row-major x, y, z), the
    Jacobian of its identifiable directions X (3N, r) and the columns (3N, m) of the candidate
    harmonics (two per (axis, order), sin then cos) then of the ``gravity`` groups (``size``
    each), all at the fitted parameters, mm per rad."""
    base_T0 = rigid_fit(data.commanded, data.measured) if base_frame else np.eye(4)
    every = tuple(harmonics) + tuple(candidates)
    model = _Model(robot, base_frame, base_T0, compliance, every, gravity)
    fitted = _Model(robot, base_frame, base_T0, compliance, harmonics)
    x = np.zeros(model.n)
    x[: fitted.i_grav] = result.x[: fitted.i_grav]
    x[model.i_harm : model.i_harm + 2 * len(harmonics)] = result.x[fitted.i_harm :]
    jac = model.jacobian(x, data.q).reshape(-1, model.n)
    base = np.r_[0 : fitted.i_grav, model.i_harm : model.i_harm + 2 * len(harmonics)]
    sub = _subspace(fitted.jacobian(np.zeros(fitted.n), data.q), RTOL)
    directions = sub.basis / sub.scale[:, None]
    extra = np.r_[model.i_harm + 2 * len(harmonics) : model.n, model.i_grav : model.i_harm]
    return result.residuals.reshape(-1), jac[:, base] @ directions, jac[:, extra]


def planned_columns(
    robot: Robot, q: np.ndarray, candidates: Terms, gravity: tuple[GravityTerm, ...]
) -> tuple[np.ndarray, np.ndarray]:
    """For poses not yet measured, joints q (N, 6) rad: the identifiable DH + TCP columns X
    (3N, r) of the nominal model and the candidate columns (3N, m) (harmonics, two each, then the
    gravity groups), as ``linearised`` gives them for measured data."""
    model = _Model(robot, False, np.eye(4), False, candidates, gravity)
    jac = model.jacobian(np.zeros(model.n), np.atleast_2d(q)).reshape(-1, model.n)
    sub = _subspace(jac[:, :27].reshape(len(q), 3, 27), RTOL)
    base = jac[:, :27] @ (sub.basis / sub.scale[:, None])
    extra = np.r_[model.i_harm : model.n, model.i_grav : model.i_harm]
    return base, jac[:, extra]


def _in_robot_frame(base_T0: np.ndarray, points: np.ndarray) -> np.ndarray:
    rot = base_T0[:3, :3]
    return (points - base_T0[:3, 3]) @ rot


def rigid_fit(robot_points: np.ndarray, tracker_points: np.ndarray) -> np.ndarray:
    """tracker_T_robot (4, 4) that best maps robot_points onto tracker_points (N, 3) mm."""
    from scipy.spatial.transform import Rotation

    a_mean, b_mean = robot_points.mean(axis=0), tracker_points.mean(axis=0)
    rot, _ = Rotation.align_vectors(tracker_points - b_mean, robot_points - a_mean)
    out = np.eye(4)
    out[:3, :3] = rot.as_matrix()
    out[:3, 3] = b_mean - out[:3, :3] @ a_mean
    return out


def _check_geometry(data: PoseSet) -> None:
    """InputError for poses in one plane or one orientation (before any fit)."""
    first = np.unique(data.group, return_index=True)[1]
    spread = np.linalg.svd(data.commanded[first] - data.commanded[first].mean(axis=0))[1]
    if len(first) >= 3 and spread[-1] < PLANE_RATIO * spread[0]:
        raise InputError(
            f"the {len(first)} commanded poses lie in one plane (spread across it "
            f"{spread[-1] / np.sqrt(len(first)):.3f} mm RMS): spread them in all three "
            "directions",
            data.path,
        )
    if (
        rotation_angle_deg(data.rotations[first], data.rotations[first[0]]).max()
        < ONE_ORIENTATION_DEG
    ):
        raise InputError(
            f"all {len(first)} commanded poses have one orientation (within "
            f"{ONE_ORIENTATION_DEG:g} deg): the TCP offset cannot be told from the arm; "
            "measure at several orientations",
            data.path,
        )


def _check_rank(
    sub: _Subspace,
    reference: _Subspace,
    data: PoseSet,
    names: list[str],
    geometric: _Subspace | None = None,
) -> None:
    """InputError for fewer poses than identifiable parameters (with ``geometric``, the
    reference subspace of the DH + TCP part: fewer poses than its parameters, or fewer equations
    than all), poses in one plane or one orientation, and data that lose directions a
    spread-out pose set identifies."""
    rank, wanted = sub.basis.shape[1], reference.basis.shape[1]
    if geometric is not None and 3 * data.poses <= wanted:
        raise InputError(
            f"{data.poses} distinct poses ({3 * data.poses} equations) for {wanted} identifiable "
            "parameters: measure more poses or fit fewer terms",
            data.path,
        )
    if data.poses < (wanted if geometric is None else geometric.basis.shape[1]):
        wanted = wanted if geometric is None else geometric.basis.shape[1]
        raise InputError(
            f"{data.poses} distinct poses for {wanted} identifiable parameters: measure at least "
            f"{wanted} poses (about twice that for a useful fit)",
            data.path,
        )
    _check_geometry(data)
    if rank < wanted:
        # directions lost beyond the structural ones: the data null space outside the reference's
        lost = sub.null - reference.null @ (reference.null.T @ sub.null)
        u = np.linalg.svd(lost, full_matrices=False)[0][:, : wanted - rank]
        text = "; ".join(_direction_text(v, names) for v in _readable_null(u).T[:_SHOW])
        raise InputError(
            f"the {data.poses} poses leave {wanted - rank} more parameter combinations "
            f"unidentifiable than a spread-out pose set ({text}): spread the poses over more "
            "positions, orientations and joint angles",
            data.path,
        )


def _readable_null(null: np.ndarray) -> np.ndarray:
    """The same subspace (n, k) in a sparser basis: reduced row echelon of its transpose (the
    largest component of each direction is a pivot, its other pivots are 0), columns unit, each
    with its first component above 5 % of its largest positive, in the order of those first
    components' parameters (the SVD's order of directions with singular values near 0, and which
    of two equal components becomes the pivot, are rounding noise that differs between CPUs)."""
    if null.size == 0:
        return null
    rows = null.T.copy()
    k = len(rows)
    used: list[int] = []
    for i in range(k):
        masked = np.abs(rows[i]).copy()
        masked[used] = 0.0
        pivot = int(np.argmax(masked))
        rows[i] /= rows[i, pivot]
        others = np.arange(k) != i
        rows[others] -= np.outer(rows[others, pivot], rows[i])
        used.append(pivot)
    rows /= np.linalg.norm(rows, axis=1, keepdims=True)
    first = np.argmax(np.abs(rows) > 0.05 * np.abs(rows).max(axis=1, keepdims=True), axis=1)
    rows *= np.sign(rows[np.arange(k), first])[:, None]
    return rows[np.argsort(first, kind="stable")].T


def _direction_text(v: np.ndarray, names: list[str]) -> str:
    """A direction in scaled coordinates as '+0.707 dd2 -0.707 dd3' (components above 0.05 of the
    largest, which is 1 in size; the sign as given)."""
    v = v / np.abs(v).max()
    keep = np.flatnonzero(np.abs(v) > 0.05 * np.abs(v).max())
    if len(keep) == 1:
        return names[keep[0]]
    return " ".join(f"{v[i]:+.3f} {names[i]}" for i in keep)


def _outliers(residuals: np.ndarray, sigma: float, labels: tuple[str, ...]) -> list[str]:
    centred = np.abs(residuals - np.median(residuals, axis=0))
    limit = max(OUTLIER_SIGMA * sigma, OUTLIER_FLOOR_MM)
    return [labels[r] for r in np.flatnonzero((centred > limit).any(axis=1))]
