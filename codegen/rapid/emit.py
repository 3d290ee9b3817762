"""ABB RAPID for a Program: one module ``NAME.mod`` (``templates/rapid/program.mod.j2``).

Every pose is a ``CONST robtarget p<n>_APP|CLR|BOT|RET`` (n: the hole's number in the file) in
the cell's work object (``rapid.wobj``, its user frame the cell's base frame), with the
orientation as a unit quaternion [q1, q2, q3, q4] (q1 the scalar part, q1 >= 0, 9 decimals:
|q| = 1 within 1e-9) and the confdata [cf1, cf4, cf6, cfx] of the joint angles the program's IK
check solved the pose with (``kinematics.configuration.abb_confdata``); unused external axes are
9E+09. Each hole: MoveJ to the approach point (``vTravel``, ``zTravel``), MoveL to the clearance
point (``vApproach``, fine), MoveL at the hole's feed to the bottom (fine), WaitTime dwell, MoveL
to the retract point; the spindle output is set before the first hole and reset after the last.
Numbers go through ``textsafe`` (``fixed``) only; hole ids only into comments (sanitised).
Lengths mm, speeds mm/s, times s, as RAPID has them. The module name is a RAPID identifier of
at most 32 characters (``rapid.module``, else the output file's stem): an InputError otherwise.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from accugrid.codegen.program import STAGES, Program
from accugrid.codegen.rapid.names import rapid_name_problem
from accugrid.codegen.render import environment, render, template_dir
from accugrid.codegen.textsafe import comment_texts, fixed, fixed_texts
from accugrid.kinematics.configuration import abb_confdata
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.robot import load_robot

__all__ = ["QUATERNION_DECIMALS", "module_name", "quaternions", "render_rapid"]

QUATERNION_DECIMALS = 9  # as RobotStudio writes them: the written quaternion is unit to 1e-9
_UNUSED = ",".join(["9E+09"] * 6)  # external axes a..f not in use
_NEWLINE = "\r\n"


def quaternions(rotations: np.ndarray) -> np.ndarray:
    """RAPID orientations (N, 4) [q1, q2, q3, q4] = [w, x, y, z] of rotation matrices (N, 3, 3):
    unit, q1 >= 0 (of the two signs of a rotation, the one RobotStudio writes)."""
    xyzw = Rotation.from_matrix(np.asarray(rotations, dtype=float).reshape(-1, 3, 3)).as_quat()
    wxyz = np.roll(xyzw, 1, axis=1)
    wxyz *= np.where(wxyz[:, :1] < 0, -1.0, 1.0)
    return wxyz / np.linalg.norm(wxyz, axis=1, keepdims=True)


def module_name(section_module: str | None, out: Path) -> str:
    """The MODULE name: the cell's ``rapid.module`` (validated when the cell was read), else the
    stem of the output file; InputError naming the file when that is not a RAPID identifier."""
    if section_module is not None:
        return section_module
    problem = rapid_name_problem(out.stem)
    if problem:
        raise InputError(
            f"the module name {out.stem!r} (the file's stem) {problem}: rename the output or set "
            "rapid.module in the cell file",
            os.fspath(out),
        )
    return out.stem


def render_rapid(
    program: Program, header: list[str], templates=None, out: Path = Path("ACCUGRID.mod")
) -> dict[Path, str]:
    """{out: text} of the module; waits for the program's IK check (the confdata needs its
    joint angles)."""
    cell = program.cell
    section = cell.dialects["rapid"]
    name = module_name(section.module, out)
    n, places = len(program), section.decimals
    q = program.joint_angles().reshape(-1, 6)
    confdata = abb_confdata(load_robot(cell.robot_name), q).reshape(n, 4, 4)
    quats = quaternions(program.rotations)  # one orientation per hole, every stage
    names = [f"p{h}_{s}" for h in range(1, n + 1) for s in STAGES]
    table = np.empty((n * 4, 12), dtype=object)
    table[:, 0] = names
    table[:, 1:4] = fixed_texts(program.positions.reshape(-1, 3), places)
    table[:, 4:8] = np.repeat(fixed_texts(quats, QUATERNION_DECIMALS), 4, axis=0)
    table[:, 8:12] = fixed_texts(confdata.reshape(-1, 4), 0, distinct=True)
    target = (
        "    CONST robtarget %s:=[[%s,%s,%s],[%s,%s,%s,%s],[%s,%s,%s,%s],[" + _UNUSED + "]];"
    ) + _NEWLINE
    target_lines = (target * len(table)) % tuple(table.ravel().tolist())
    move = f"{section.tool}\\WObj:={section.wobj};{_NEWLINE}"
    hole = (
        "        ! %s"
        + _NEWLINE
        + "        MoveJ %s, vTravel, zTravel, "
        + move
        + "        MoveL %s, vApproach, fine, "
        + move
        + "        MoveL %s, [%s,500,5000,1000], fine, "
        + move
        + "        WaitTime "
        + fixed(cell.drilling.dwell_s, 3)
        + ";"
        + _NEWLINE
        + "        MoveL %s, vApproach, zTravel, "
        + move
    )
    holes = np.empty((n, 6), dtype=object)
    holes[:, 0] = comment_texts(program.labels(), prefix="hole ")
    holes[:, 1:3] = np.array(names, dtype=object).reshape(n, 4)[:, :2]
    holes[:, 3] = np.array(names, dtype=object).reshape(n, 4)[:, 2]
    holes[:, 4] = fixed_texts(program.feed_mm_s, places, distinct=True)
    holes[:, 5] = np.array(names, dtype=object).reshape(n, 4)[:, 3]
    hole_lines = (hole * n) % tuple(holes.ravel().tolist())
    flange_T_tool, robot_T_wobj = cell.flange_T_tool, section.robot_T_wobj
    tool_q, wobj_q = quaternions(np.stack([flange_T_tool[:3, :3], robot_T_wobj[:3, :3]]))
    zone = section.zone_mm
    env = environment(template_dir("rapid", templates), newline=_NEWLINE)
    text = render(
        env,
        "program.mod.j2",
        module=name,
        header=header,
        tool=section.tool,
        wobj=section.wobj,
        spindle=section.spindle,
        tcp=",".join(fixed(v, places) for v in flange_T_tool[:3, 3]),
        tcp_quaternion=",".join(fixed(v, QUATERNION_DECIMALS) for v in tool_q),
        tool_mass=fixed(section.tool_mass, 3),
        uframe=",".join(fixed(v, places) for v in robot_T_wobj[:3, 3]),
        uframe_quaternion=",".join(fixed(v, QUATERNION_DECIMALS) for v in wobj_q),
        travel=fixed(cell.drilling.travel_mm_s, places),
        approach=fixed(cell.drilling.approach_mm_s, places),
        # zonedata: TCP zone, then orientation, external-axis zones (mm) and angles (deg), the
        # proportions of ABB's predefined z5 .. z200
        zone=",".join(
            fixed(v, places) for v in (zone, 1.5 * zone, 1.5 * zone, 0.15 * zone, 1.5 * zone)
        )
        + ","
        + fixed(0.15 * zone, places),
        target_lines=target_lines.removesuffix(_NEWLINE),
        hole_lines=hole_lines.removesuffix(_NEWLINE),
    )
    return {out: text}
