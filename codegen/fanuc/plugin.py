"""FANUC TP as a dialect plug-in (``codegen.plugin.DialectPlugin``): ``PLUGIN``. Light to import
(the registry reads its name and suffixes): the emitter and the reader are imported when first
used."""

from __future__ import annotations

from accugrid.codegen.plugin import EXTERNAL_AXES, DialectFolder, DialectHelp, Rendered

__all__ = ["PLUGIN", "FanucPlugin"]

HELP = DialectHelp(
    summary="corrected FANUC TP drilling program (.ls) from a points CSV",
    description="""Write a corrected FANUC TP drilling program (.ls, ASCII) from a points CSV.

Positions are Cartesian P[n] in the cell's user frame (base.number, 1..9: the cell's base frame)
and tool frame (tool.number, 1..10), X, Y, Z mm and W, P, R deg, CONFIG from the robot model's
IK (a cell whose robot is a FANUC arm, e.g. r2000ic-165f). Each hole: J to the approach point on
the drill axis, L at approach speed to the clearance point, L at the feed to the depth, WAIT
dwell, L back to the retract point; a DO switches the spindle. The program name is
fanuc.program, else the file's stem, upper-cased. Every hole is corrected with the grid and/or
the calibrated model (its point mapped to the robot frame, P' = P + e(P), and the same e applied
to all its positions).

Units: mm, deg, mm/s (whole mm/sec for linear moves), s in the inputs and in the program. Exit 2
on bad input, with nothing written.
""",
    output=("NAME.ls", "the TP program to write"),
    report="FANUC TP drilling program",
    rewrite="""\
FANUC TP (.ls, ASCII): Cartesian /POS positions of motion group 1 that only J/L/C/A moves reach,
in the cell's user frame (base.number) or the world frame (UF 0) with the cell's tool frame
(tool.number, or one of tool_data); never joint positions, remote-TCP positions, PR[] registers,
positions moved with Offset/Tool_Offset/INC, COORD or RTCP, read by other instructions, or in a
frame the program sets at run time, and positions with other motion groups or extended axes
unless --ignore-external-axes.
""",
)


class FanucPlugin(DialectFolder):
    """FANUC TP programs in their ASCII form (``.ls``). A new program is one file, its CONFIG
    from every pose's configuration. Members as ``DialectPlugin`` says."""

    name = "fanuc"
    title = "FANUC TP"
    help = HELP
    suffixes = (".ls",)
    controllers = ("fanuc",)  # the robots it drives
    exports = ("render_fanuc",)
    options = (EXTERNAL_AXES,)

    def targets(self, cell, out):
        from accugrid.codegen.fanuc.emit import program_name

        section = cell.dialects[self.name].check()  # frame numbers FANUC has not: before any work
        program_name(section.program, out)  # a name the controller refuses: before any work
        return [out]

    def render(self, program, header, templates, out, plan):
        from accugrid.codegen.fanuc.emit import render_fanuc

        return Rendered(render_fanuc(program, header, templates, out))

    def placement(self, cell, context):
        from accugrid.codegen.fanuc.rewrite import FanucPlacement

        return FanucPlacement(cell.dialects[self.name], bool(context["ignore_external_axes"]))


PLUGIN = FanucPlugin()
