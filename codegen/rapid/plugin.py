"""ABB RAPID as a dialect plug-in (``codegen.plugin.DialectPlugin``): ``PLUGIN``. Light to
import (the registry reads its name and suffixes): the emitter and the reader are imported when
first used."""

from __future__ import annotations

from accugrid.codegen.plugin import EXTERNAL_AXES, DialectFolder, DialectHelp, Rendered

__all__ = ["PLUGIN", "RapidPlugin"]


HELP = DialectHelp(
    summary="corrected ABB RAPID drilling module (.mod) from a points CSV",
    description="""Write a corrected ABB RAPID drilling module (.mod) from a points CSV.

Positions are CONST robtargets in the cell's work object (rapid.wobj: the cell's base frame),
orientation as unit quaternions, confdata from the robot model's IK (a cell whose robot is an
ABB arm, e.g. irb6700). Each hole: MoveJ to the approach point on the drill axis, MoveL at
approach speed to the clearance point, MoveL at the feed to the depth, WaitTime dwell, MoveL
back to the retract point; SetDO switches the spindle. Every hole is corrected with the grid
and/or the calibrated model (its point mapped to the robot frame, P' = P + e(P), and the same e
applied to all its positions).

Units: mm, deg, mm/s, s in the inputs and in the program. Exit 2 on bad input, with nothing
written.
""",
    output=("FILE.mod", "the module to write"),
    report="ABB RAPID drilling program",
    rewrite="""\
RAPID (.mod/.modx/.prg/.sys): robtargets moved only by MoveL/MoveJ (and their DO/AO/GO/Sync
forms, TriggL/TriggJ) with the cell's rapid.tool in its rapid.wobj (the base frame) or wobj0 (the
robot frame); never tooldata, wobjdata, jointtarget, loaddata, pose, Offs/RelTool operands or
robtargets changed at run time, and external axes in use (eax values other than 9E+09) unless
--ignore-external-axes.
""",
)


class RapidPlugin(DialectFolder):
    """ABB RAPID modules: ``.mod``, ``.modx`` (RobotWare 7), ``.prg`` (older RAPID programs),
    ``.sys`` (system modules). A new program is one module, its confdata from every pose's
    joint angles. Members as ``DialectPlugin`` says."""

    name = "rapid"
    title = "ABB RAPID"
    help = HELP
    suffixes = (".mod", ".modx", ".prg", ".sys")
    controllers = ("abb",)  # the robots it drives
    joints = True  # confdata comes from the joint angles
    options = (EXTERNAL_AXES,)

    def targets(self, cell, out):
        from accugrid.codegen.rapid.emit import module_name

        module_name(cell.dialects[self.name].module, out)  # a name RAPID refuses: before any work
        return [out]

    def render(self, program, header, templates, out, plan):
        from accugrid.codegen.rapid.emit import render_rapid

        return Rendered(render_rapid(program, header, templates, out))

    def placement(self, cell, context):
        from accugrid.codegen.rapid.rewrite import RapidPlacement

        return RapidPlacement(cell.dialects[self.name], bool(context["ignore_external_axes"]))


PLUGIN = RapidPlugin()
