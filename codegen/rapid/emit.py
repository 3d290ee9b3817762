"""ABB RAPID for a Program: one module ``NAME.mod`` (``templates/rapid/program.mod.j2``).

Every pose is a ``CONST robtarget p<n>_APP|CLR|BOT|RET`` (n: the hole's number in the file) in
the cell's work object (``rapid.wobj``, its user frame the cell's base frame), with the
orientation as a unit quaternion [q1, q2, q3, q4] (q1 the scalar part, q1 >= 0, 9 decimals:
|q| = 1 within 1e-9) and the confdata [cf1, cf4, cf6, cfx] of the joint angles the program's IK
check solved the pose with (``codegen.rapid.configuration.abb_confdata``); unused external axes are
9E+09. Each hole: MoveJ to the approach point (``vTravel``, ``zTravel``), MoveL to the clearance
point (``vApproach``, fine), MoveL at the hole's feed to the bottom (fine), WaitTime dwell, MoveL
to the retract point; the spindle output is set before the first hole and reset after the last.
Numbers go through ``textsafe`` (``fixed``) only; hole ids only into comments (sanitised).
Lengths mm, speeds mm/s, times s, as RAPID has them. The module name is a RAPID identifier of
at most 32 characters (``rapid.module``, else the output file's stem): an InputError otherwise.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from accugrid.codegen.program import STAGES, Program
from accugrid.codegen.program_text import stem_name
from accugrid.codegen.rapid.configuration import abb_confdata
from accugrid.codegen.rapid.names import rapid_name_problem
from accugrid.codegen.render import (
    environment,
    printed_plainly,
    render,
    render_around,
    template_dir,
)
from accugrid.infra.textsafe import comment_texts, fixed, fixed_texts
from accugrid.kinematics.robot import load_robot

__all__ = ["BLOCK", "QUATERNION_DECIMALS", "module_name", "quaternions", "render_rapid"]

BLOCK = 16384  # holes whose lines are made at a time
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
    return stem_name(out, "module", "rapid.module", rapid_name_problem)


def render_rapid(
    program: Program, header: list[str], templates=None, out: Path = Path("ACCUGRID.mod")
) -> dict[Path, Iterator[str]]:
    """{out: the module's text in pieces}: the frame rendered by Jinja around the robtarget and
    move lines, which follow in blocks of ``BLOCK`` holes as the pieces are taken (a template
    that does not print them plainly gets them whole). Waits for the program's IK check (the
    confdata needs its joint angles)."""
    cell = program.cell
    header = program.header(header)  # says what is not corrected
    section = cell.dialects["rapid"]
    places = section.decimals
    flange_T_tool, robot_T_wobj = cell.flange_T_tool, section.robot_T_wobj
    tool_q, wobj_q = quaternions(np.stack([flange_T_tool[:3, :3], robot_T_wobj[:3, :3]]))
    zone = section.zone_mm
    env = environment(template_dir("rapid", templates), newline=_NEWLINE)
    context = dict(
        module=module_name(section.module, out),
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
            fixed(v, places)
            for v in (zone, 1.5 * zone, 1.5 * zone, 0.15 * zone, 1.5 * zone, 0.15 * zone)
        ),
    )
    robot = load_robot(cell.robot_name)
    blocks = range(0, len(program), BLOCK)
    template = "program.mod.j2"
    if printed_plainly(env, template, "target_lines") and printed_plainly(
        env, template, "hole_lines"
    ):
        frame = render_around(env, template, "hole_lines", target_lines=_TARGETS, **context)
        if len(frame) == 2 and frame[0].count(_TARGETS) == 1:  # each printed once, in order
            head, between = frame[0].split(_TARGETS)
            return {out: _pieces(program, robot, places, head, between, frame[1])}
    targets = "".join(_target_lines(program, robot, lo, places) for lo in blocks)
    holes = "".join(_hole_lines(program, lo, places) for lo in blocks)
    text = render(
        env,
        template,
        target_lines=targets.removesuffix(_NEWLINE),
        hole_lines=holes.removesuffix(_NEWLINE),
        **context,
    )
    return {out: iter([text])}


_TARGETS = "\x00accugrid targets\x00"  # where the robtargets go (no program text holds a NUL)


def _pieces(program, robot, places, head, between, after) -> Iterator[str]:
    """The module: ``head``, the robtarget lines, ``between``, the move lines, ``after`` (the
    last line of each list without its line end: the template's own follows)."""
    blocks = range(0, len(program), BLOCK)
    yield head
    yield from _without_last_newline(_target_lines(program, robot, lo, places) for lo in blocks)
    yield between
    yield from _without_last_newline(_hole_lines(program, lo, places) for lo in blocks)
    yield after


def _without_last_newline(pieces: Iterator[str]) -> Iterator[str]:
    previous = None
    for piece in pieces:
        if previous is not None:
            yield previous
        previous = piece
    if previous is not None:
        yield previous.removesuffix(_NEWLINE)


def _names(lo: int, hi: int) -> np.ndarray:
    """Robtarget names (hi - lo, 4) of holes lo..hi-1: ``p<n>_<stage>``, n from 1."""
    return np.array(
        [f"p{h}_{s}" for h in range(lo + 1, hi + 1) for s in STAGES], dtype=object
    ).reshape(-1, 4)


def _target_lines(program: Program, robot, lo: int, places: int) -> str:
    """The CONST robtarget lines of holes lo..lo+BLOCK-1, four per hole."""
    hi = min(lo + BLOCK, len(program))
    q = program.joint_angles(lo, hi).reshape(-1, 6)
    table = np.empty(((hi - lo) * 4, 12), dtype=object)
    table[:, 0] = _names(lo, hi).ravel()
    table[:, 1:4] = fixed_texts(program.positions[lo:hi].reshape(-1, 3), places)
    quats = quaternions(program.rotations[lo:hi])  # one orientation per hole, every stage
    table[:, 4:8] = np.repeat(fixed_texts(quats, QUATERNION_DECIMALS), 4, axis=0)
    table[:, 8:12] = fixed_texts(abb_confdata(robot, q), 0, distinct=True)
    return (_TARGET * len(table)) % tuple(table.ravel().tolist())


_TARGET = (
    "    CONST robtarget %s:=[[%s,%s,%s],[%s,%s,%s,%s],[%s,%s,%s,%s],[" + _UNUSED + "]];"
) + _NEWLINE


def _hole_lines(program: Program, lo: int, places: int) -> str:
    """The moves of holes lo..lo+BLOCK-1: a comment, MoveJ, MoveL, MoveL at the feed,
    WaitTime, MoveL."""
    cell = program.cell
    section = cell.dialects["rapid"]
    hi = min(lo + BLOCK, len(program))
    move = f"{section.tool}\\WObj:={section.wobj};{_NEWLINE}"
    hole = (
        f"        ! %s{_NEWLINE}"
        f"        MoveJ %s, vTravel, zTravel, {move}"
        f"        MoveL %s, vApproach, fine, {move}"
        f"        MoveL %s, [%s,500,5000,1000], fine, {move}"
        f"        WaitTime {fixed(cell.drilling.dwell_s, 3)};{_NEWLINE}"
        f"        MoveL %s, vApproach, zTravel, {move}"
    )
    names = _names(lo, hi)
    table = np.empty((hi - lo, 6), dtype=object)
    table[:, 0] = comment_texts(program.labels(lo, hi), prefix="hole ")
    table[:, 1:4] = names[:, :3]
    table[:, 4] = fixed_texts(program.feed_mm_s[lo:hi], places, distinct=True)
    table[:, 5] = names[:, 3]
    return (hole * (hi - lo)) % tuple(table.ravel().tolist())
