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
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from codegen.program import Program
from codegen.render import environment, render, template_dir


class GcodeHole(NamedTuple):
    label: str
    app: tuple[float, float, float]
    clr: tuple[float, float, float]
    bot: tuple[float, float, float]
    ret: tuple[float, float, float]
    abc: tuple[float, float, float]
    feed_mm_min: float
    canned: bool
    retract_move: bool


def canned_holes(positions: np.ndarray, decimals: int) -> np.ndarray:
    """(N,) bool: holes whose four positions (N, 4, 3) share X, Y at ``decimals`` and go down in
    Z from approach over clearance to bottom (the drill axis is the program's -Z)."""
    scale = 10.0**decimals
    xy = np.round(positions[:, :, :2] * scale)
    same_xy = (xy == xy[:, :1]).all(axis=(1, 2))
    z = positions[:, :, 2]
    return same_xy & (z[:, 0] > z[:, 1]) & (z[:, 1] > z[:, 2]) & (z[:, 3] > z[:, 1])


def render_gcode(program: Program, header: list[str], templates=None) -> str:
    """The ``.ngc`` text of the job."""
    cell = program.cell
    env = environment(template_dir("gcode", templates))
    pos, abc = program.in_frame(cell.robot_T_program)
    canned = canned_holes(pos, cell.decimals) & cell.canned_cycles
    scale = 10.0**cell.decimals
    retract_move = np.round(pos[:, 3, 2] * scale) != np.round(pos[:, 0, 2] * scale)
    labels = program.labels()
    coords, angles = pos.tolist(), abc.tolist()
    feeds = (program.feed_mm_s * 60.0).tolist()
    holes = [
        GcodeHole(label, *coords[i], angles[i], feeds[i], bool(canned[i]), bool(retract_move[i]))
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
