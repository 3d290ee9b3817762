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

from typing import NamedTuple

import numpy as np

from accugrid.codegen.program import Program
from accugrid.codegen.render import environment, fixed_texts, render, template_dir

__all__ = ["GcodeHole", "canned", "render_gcode"]


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


def canned(text: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Holes (N,) that allow a canned cycle, from their formatted positions ``text`` (N, 4, 3)
    (APP, CLR, BOT, RET) and heights ``z`` (N, 4): the same printed X and Y, and Z going down from
    approach over clearance to the bottom (the drill axis is the program's -Z), with the retract
    above the clearance."""
    same_xy = (text[:, :, :2] == text[:, :1, :2]).all(axis=(1, 2))
    return same_xy & (z[:, 0] > z[:, 1]) & (z[:, 1] > z[:, 2]) & (z[:, 3] > z[:, 1])


def render_gcode(program: Program, header: list[str], templates=None) -> str:
    """The ``.ngc`` text of the job."""
    cell = program.cell
    env = environment(template_dir("gcode", templates))
    pos, abc = program.in_frame(cell.robot_T_program)
    d = cell.decimals
    # RET is usually the APP position (same distance): format it once
    same_ret = (pos[:, 3] == pos[:, 0]).all(axis=1)
    text = np.empty(pos.shape, dtype=object)
    text[:, :3] = fixed_texts(pos[:, :3], d)
    text[:, 3] = text[:, 0]
    text[~same_ret, 3] = fixed_texts(pos[~same_ret, 3], d)
    cycle = canned(text, pos[:, :, 2]) if cell.canned_cycles else np.zeros(len(pos), bool)
    retract_move = text[:, 3, 2] != text[:, 0, 2]
    coords = [list(map(tuple, hole)) for hole in text.tolist()]
    holes = list(
        map(
            GcodeHole,
            program.labels(),
            *zip(*coords, strict=True),
            map(tuple, fixed_texts(abc, d, distinct=True).tolist()),
            fixed_texts(program.feed_mm_s * 60.0, 1, distinct=True).tolist(),
            cycle.tolist(),
            retract_move.tolist(),
        )
    )
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
