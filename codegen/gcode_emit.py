"""RS274NGC (LinuxCNC dialect) for a Program: one ``.ngc`` from ``templates/gcode/program.ngc.j2``.

Positions are the TCP in the program frame (``cell.robot_T_program``, default the BASE frame), mm;
orientation as A B C words = the KUKA A, B, C of the tool in that frame, deg (stated in the file
header). Per hole: ``G0`` to the approach point with A B C; where the drill axis is the program's
-Z (all four positions of the hole share X and Y at the printed precision) and
``gcode.canned_cycles`` is on, a canned cycle from the clearance plane R: ``G83`` with peck Q when
``drilling.peck`` > 0, else ``G82`` with the dwell P, else ``G81``; ``G98`` returns to the approach
height, then ``G0 Z`` to the retract point if that differs. Otherwise explicit moves along the
drill axis: ``G1`` to the clearance point at approach speed, ``G1`` to the bottom at the feed,
``G4`` dwell, ``G1`` back to the retract point at approach speed. Feeds are mm/min (``G94``).

Numbers go through ``fixed`` only: per-hole numbers are formatted once in Python
(``program.decimals`` for mm and deg, 1 decimal for F) and reach the template as text; the
template formats its scalar settings with the ``fixed`` filter.
"""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

from codegen.program import Program
from codegen.render import environment, render, template_dir
from codegen.textsafe import fixed


class GcodeHole(NamedTuple):
    """One hole; coordinates (X, Y, Z), A B C and the feed already formatted by ``fixed``."""

    label: str
    app: tuple[str, str, str]
    clr: tuple[str, str, str]
    bot: tuple[str, str, str]
    ret: tuple[str, str, str]
    abc: tuple[str, str, str]
    feed: str  # mm/min
    canned: bool
    retract_move: bool


def canned(coords: list[tuple[str, str, str]], z: list[float]) -> bool:
    """A hole's four formatted positions (APP, CLR, BOT, RET) allow a canned cycle: the same
    printed X and Y, and Z going down from approach over clearance to the bottom (the drill axis
    is the program's -Z), with the retract above the clearance."""
    xy = {c[:2] for c in coords}
    return len(xy) == 1 and z[0] > z[1] > z[2] and z[3] > z[1]


def render_gcode(program: Program, header: list[str], templates=None) -> str:
    """The ``.ngc`` text of the job."""
    cell = program.cell
    env = environment(template_dir("gcode", templates))
    pos, abc = program.in_frame(cell.robot_T_program)
    labels = program.labels()
    d = cell.decimals
    number = lru_cache(maxsize=4096)(fixed)  # feeds repeat
    # RET is usually the APP position (same distance): format it once
    same_ret = (pos[:, 3] == pos[:, 0]).all(axis=1).tolist()
    coords = []
    for hole, same in zip(pos.tolist(), same_ret, strict=True):
        text = [tuple(fixed(v, d) for v in p) for p in (hole[:3] if same else hole)]
        coords.append(text + [text[0]] if same else text)
    angles = [tuple(fixed(v, d) for v in a) for a in abc.tolist()]
    feeds = [number(f, 1) for f in (program.feed_mm_s * 60.0).tolist()]
    heights = pos[:, :, 2].tolist()
    holes = [
        GcodeHole(
            label,
            *coords[i],
            angles[i],
            feeds[i],
            cell.canned_cycles and canned(coords[i], heights[i]),
            coords[i][3][2] != coords[i][0][2],
        )
        for i, label in enumerate(labels)
    ]
    return render(
        env,
        "program.ngc.j2",
        header=header,
        holes=holes,
        decimals=cell.decimals,
        spindle_rpm=cell.spindle_rpm,
        approach_mm_min=cell.approach_mm_s * 60.0,
        dwell=cell.dwell_s,
        peck=cell.peck_mm,
    )
