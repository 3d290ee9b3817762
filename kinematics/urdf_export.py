"""URDF export of a DH robot (e.g. a calibrated model): what robot users ask vendors for.

Each DH row A_i = Rot(Z, θ_i)·Trans(0, 0, d_i)·Trans(a_i, 0, 0)·Rot(X, α_i) with
θ_i = sign_i·A_i + θ_offset_i becomes a revolute joint ``A{i}`` about the local axis
(0, 0, sign_i), so the URDF joint value is the KUKA axis angle A_i in rad, with the KUKA limits;
the fixed part Rot(Z, θ_offset_i)·Trans(0, 0, d_i)·Trans(a_i, 0, 0)·Rot(X, α_i) is the origin of
the next joint (xyz = Rot(Z, θ_offset_i)·(a_i, 0, d_i), rpy = (α_i, 0, θ_offset_i)), ending in the
fixed joints ``flange`` and ``tool`` (flange_T_tool) to the link ``tcp``. Lengths in metres,
angles in rad (URDF units), written in shortest round-trip form.
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

import numpy as np

from accugrid.kinematics.robot import Robot

__all__ = ["urdf_text"]

_M_PER_MM = 1e-3


def _numbers(values) -> str:
    return " ".join(repr(float(v)) for v in values)


def _rpy(rot: np.ndarray) -> np.ndarray:
    """URDF roll, pitch, yaw (rad) of a rotation matrix: R = Rz(yaw)·Ry(pitch)·Rx(roll)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(rot).as_euler("ZYX")[::-1]


def _origin(pose: np.ndarray) -> str:
    xyz = pose[:3, 3] * _M_PER_MM
    return f'<origin xyz="{_numbers(xyz)}" rpy="{_numbers(_rpy(pose[:3, :3]))}"/>'


def _fixed_part(robot: Robot, i: int) -> np.ndarray:
    """Rot(Z, θ_offset)·Trans(0, 0, d)·Trans(a, 0, 0)·Rot(X, α) of row i (4, 4) mm."""
    dh = robot.dh
    ct, st = np.cos(dh.theta_offset[i]), np.sin(dh.theta_offset[i])
    ca, sa = np.cos(dh.alpha[i]), np.sin(dh.alpha[i])
    out = np.eye(4)
    out[:3, :3] = [[ct, -st * ca, st * sa], [st, ct * ca, -ct * sa], [0.0, sa, ca]]
    out[:3, 3] = [dh.a[i] * ct, dh.a[i] * st, dh.d[i]]
    return out


def urdf_text(robot: Robot, name: str | None = None) -> str:
    """URDF of ``robot``'s true arm (its DH plus ``errors`` when it has them) and tool."""
    arm = robot.true_robot() or robot
    limits = np.radians(arm.joint_limits_deg)
    links = ["base_link"] + [f"link_{i}" for i in range(1, arm.dh.n + 1)] + ["flange", "tcp"]
    about = (arm.description or arm.name).replace("--", "- -")  # "--" may not be in a comment
    lines = [
        '<?xml version="1.0"?>',
        f"<!-- {about}: standard DH exported by accugrid; joint values are "
        "the controller's axis angles (rad); effort and velocity limits are not part of a "
        "kinematic model (0) -->",
        f"<robot name={quoteattr(name or robot.name)}>",
    ]
    lines += [f"  <link name={quoteattr(link)}/>" for link in links]
    origin = np.eye(4)
    for i in range(arm.dh.n):
        lo, hi = limits[i]
        lines += [
            f'  <joint name="A{i + 1}" type="revolute">',
            f"    <parent link={quoteattr(links[i])}/><child link={quoteattr(links[i + 1])}/>",
            f"    {_origin(origin)}",
            f'    <axis xyz="0 0 {int(arm.dh.sign[i])}"/>',
            f'    <limit lower="{float(lo)!r}" upper="{float(hi)!r}" effort="0" velocity="0"/>',
            "  </joint>",
        ]
        origin = _fixed_part(arm, i)
    for joint, parent, child, pose in (
        ("flange", links[-3], "flange", origin),
        ("tool", "flange", "tcp", arm.flange_T_tool),
    ):
        lines += [
            f'  <joint name="{joint}" type="fixed">',
            f'    <parent link="{parent}"/><child link="{child}"/>',
            f"    {_origin(pose)}",
            "  </joint>",
        ]
    lines.append("</robot>")
    return "\n".join(lines) + "\n"
