"""Robots that are not in DH form: a URDF loaded through Pinocchio, with numeric IK.

A robot YAML names the URDF and the frame that is the flange::

    name: my-arm
    urdf: my_arm.urdf        # relative to the YAML file
    tip: tool0               # URDF link or frame used as the flange
    tool: {x: 0, y: 0, z: 250, a: 0, b: 0, c: 0}   # optional flange_T_tool, mm and deg

Joint angles are the URDF joint values in the URDF's order (rad); joint limits come from the URDF.
Poses are (N, 4, 4) in mm (the URDF's metres times 1000). FK and IK run one pose at a time through
Pinocchio (no closed form): IK is damped least squares on the 6D pose error with
``pinocchio.computeFrameJacobian``. KUKA Status and Turn are not defined for these robots.
"""

from __future__ import annotations

import contextlib
import os
import re
import sys
import tempfile
import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from accugrid.infra.errors import InputError
from accugrid.infra.inputfile import note_input
from accugrid.infra.yamlfile import Schema, YamlDoc
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.ik import wrap
from accugrid.kinematics.model import IKSolution

__all__ = ["URDF_ROBOT_SCHEMA", "UrdfRobot", "urdf_robot_from_doc"]

# A URDF robot file: every key ``urdf_robot_from_doc`` reads.
URDF_ROBOT_SCHEMA: Schema = {
    "name": None,
    "description": None,
    "controller": None,
    "urdf": None,
    "tip": None,
    "tool": dict.fromkeys("xyzabc"),
}

_MM = 1000.0
_DAMPING = 1e-6  # squared damping of the least-squares step (dimensionless, metres and rad)
_TOLERANCE = 1e-12  # |6D error| in metres / rad at which a solution is accepted
_ITERATIONS = 200
_MAX_STEP = 0.5  # largest joint change per iteration, rad or m
_RESTARTS = 8  # further deterministic starts when the first does not reach a pose within limits


@dataclass(frozen=True)
class UrdfRobot:
    """A serial robot from a URDF: ``fk``/``ik``/``with_tool`` as ``kinematics.robot.Robot``."""

    name: str
    model: object  # pinocchio.Model
    tip: int  # frame id of the flange
    flange_T_tool: np.ndarray = field(default_factory=lambda: np.eye(4))
    description: str = ""
    controller: str = ""  # the maker of its controller, lower case ("": not said)

    @property
    def joint_limits_deg(self) -> np.ndarray:
        """(n, 2) [min, max] from the URDF, degrees."""
        lo, hi = self.model.lowerPositionLimit, self.model.upperPositionLimit
        return np.degrees(np.column_stack([lo, hi]))

    @property
    def _revolute(self) -> np.ndarray:
        """(n,) bool: joints whose angle may be wrapped into (-pi, pi] (one-coordinate revolute)."""
        kinds = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")
        return np.array([j.shortname() in kinds for j in self.model.joints[1:]])

    def with_tool(self, flange_T_tool: np.ndarray) -> UrdfRobot:
        tool = np.array(flange_T_tool, dtype=float).reshape(4, 4)
        return replace(self, flange_T_tool=tool)

    def true_robot(self) -> None:
        """URDF robots carry no parameter errors."""
        return None

    def fk(self, q: np.ndarray) -> np.ndarray:
        """TCP poses (N, 4, 4) mm for joint vectors q (N, n) rad."""
        import pinocchio as pin

        q = np.atleast_2d(np.asarray(q, dtype=float))
        data = self.model.createData()
        out = np.empty((len(q), 4, 4))
        for k, qk in enumerate(q):
            pin.framesForwardKinematics(self.model, data, qk)
            out[k] = _to_mm(data.oMf[self.tip].homogeneous) @ self.flange_T_tool
        return out

    def ik(self, robot_T_tcp: np.ndarray, status=None, turn=None, reference=None):
        """Damped-least-squares IK for poses (N, 4, 4) mm from ``reference`` ((n,) or (N, n) rad,
        default the middle of the joint limits): an ``IKSolution`` with status and turn -1."""
        import pinocchio as pin

        if status is not None or turn is not None:
            raise InputError(f"robot {self.name} (URDF) has no KUKA Status/Turn")
        poses = np.asarray(robot_T_tcp, dtype=float).reshape(-1, 4, 4)
        n, dof = len(poses), self.model.nq
        lo, hi = self.model.lowerPositionLimit, self.model.upperPositionLimit
        start = (lo + hi) / 2 if reference is None else np.asarray(reference, dtype=float)
        start = np.broadcast_to(start, (n, dof))
        flange = poses @ np.linalg.inv(self.flange_T_tool)
        data = self.model.createData()
        q = np.full((n, dof), np.nan)
        reason = np.full(n, "", dtype=object)
        starts = np.concatenate(
            [start[:, None], np.broadcast_to(self._restarts(), (n, _RESTARTS, dof))], axis=1
        )
        for k in range(n):
            target = pin.SE3(_to_m(flange[k]))
            reason[k] = "unreachable (numeric IK did not converge)"
            for guess in starts[k]:
                qk = self._solve(data, target, guess)
                if qk is None:
                    continue
                outside = np.flatnonzero((qk < lo - 1e-9) | (qk > hi + 1e-9))
                if reason[k].startswith("unreachable") or not outside.size:
                    q[k] = qk
                    reason[k] = self._limit_reason(int(outside[0])) if outside.size else ""
                if not outside.size:
                    break
        ok = reason == ""
        minus = np.full(n, -1)
        return IKSolution(q, ok, reason, minus, minus)

    def _solve(self, data, target, guess: np.ndarray) -> np.ndarray | None:
        """Damped least squares from ``guess`` (n,) to the flange placement ``target`` (SE3, m)."""
        import pinocchio as pin

        qk = guess.copy()
        for _ in range(_ITERATIONS):
            pin.framesForwardKinematics(self.model, data, qk)
            error = pin.log6(data.oMf[self.tip].actInv(target)).vector
            if np.linalg.norm(error) < _TOLERANCE:
                return np.where(self._revolute, wrap(qk), qk)
            jac = pin.computeFrameJacobian(self.model, data, qk, self.tip, pin.LOCAL)
            step = jac.T @ np.linalg.solve(jac @ jac.T + _DAMPING * np.eye(6), error)
            step *= min(1.0, _MAX_STEP / max(np.abs(step).max(), 1e-300))
            qk = pin.integrate(self.model, qk, step)
        return None

    def _restarts(self) -> np.ndarray:
        """(_RESTARTS, n) fixed further start configurations inside the joint limits (seeded)."""
        lo, hi = self.model.lowerPositionLimit, self.model.upperPositionLimit
        u = np.random.default_rng(0).random((_RESTARTS, len(lo)))
        return lo + u * (hi - lo)

    def _limit_reason(self, i: int) -> str:
        lo, hi = (
            np.degrees(self.model.lowerPositionLimit[i]),
            np.degrees(self.model.upperPositionLimit[i]),
        )
        return f"{self.model.names[i + 1]} outside limits {lo:g}..{hi:g} deg"


@contextlib.contextmanager
def _native_stderr() -> Iterator[list[str]]:
    """Hold what native code (urdfdom, tinyxml) writes to file descriptor 2 while the block runs;
    the text is in the yielded list's only item afterwards."""
    said = [""]
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as held:
        os.dup2(held.fileno(), 2)
        try:
            yield said
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            held.seek(0)
            said[0] = held.read(64 * 1024).decode("utf-8", "replace")


def urdf_robot_from_doc(doc: YamlDoc, folder: Path) -> UrdfRobot:
    """The UrdfRobot a robot YAML describes (keys: name, urdf, tip, optional tool, description,
    controller)."""
    import pinocchio as pin

    doc.check_keys(URDF_ROBOT_SCHEMA)
    path = folder / doc.string("urdf")
    if not path.is_file():
        raise doc.error(f"{doc.keyname('urdf')}: URDF file not found: {path}", "urdf")
    note_input(path)  # read by Pinocchio, an input all the same
    with _native_stderr() as said:
        try:
            model = pin.buildModelFromUrdf(str(path))
        except (RuntimeError, ValueError) as exc:
            failure = f"cannot read the URDF: {exc}".splitlines()[0]
        else:
            failure = None
    if failure is not None:  # the parser's own words (tinyxml) locate the problem
        line = re.search(r"Line number=(\d+)", said[0])
        detail = re.search(r"Error=(\w+)", said[0])
        failure += f" ({detail.group(1)})" if detail else ""
        raise InputError(failure, path, int(line.group(1)) if line else None)
    if said[0].strip():  # warnings of a URDF that loaded: after our work, as library warnings
        warnings.warn(f"{path}: {said[0].strip()}", stacklevel=2)
    if model.nq == 0:
        raise InputError("the URDF has no movable joint (a robot needs at least one)", path)
    tip_name = doc.string("tip")
    if not model.existFrame(tip_name):
        names = ", ".join(f.name for f in model.frames if f.name != "universe")
        raise doc.error(f"{doc.keyname('tip')}: no frame {tip_name!r} in the URDF ({names})", "tip")
    tool = np.eye(4)
    if doc.has("tool"):
        tool = pose_from_xyzabc([doc.number("tool", k, default=0.0) for k in "xyzabc"])
    description = doc.string("description", default="")
    controller = doc.string("controller", default="").strip().lower()
    return UrdfRobot(
        doc.string("name"), model, model.getFrameId(tip_name), tool, description, controller
    )


def _to_mm(pose_m: np.ndarray) -> np.ndarray:
    out = np.array(pose_m, dtype=float)
    out[:3, 3] *= _MM
    return out


def _to_m(pose_mm: np.ndarray) -> np.ndarray:
    out = np.array(pose_mm, dtype=float)
    out[:3, 3] /= _MM
    return out
