"""RS274NGC / ISO G-code as a dialect plug-in (``codegen.plugin.DialectPlugin``): ``PLUGIN``.
Light to import (the registry reads its name and suffixes): the emitter and the reader are
imported when first used."""

from __future__ import annotations

from accugrid.codegen.plugin import DialectFolder, DialectHelp, Rendered

__all__ = ["GcodePlugin", "PLUGIN"]


HELP = DialectHelp(
    summary="corrected RS274NGC (LinuxCNC) drilling program from a points CSV",
    description="""Write a corrected RS274NGC (LinuxCNC) drilling program from a points CSV.

Positions are the tool centre point in the cell's program frame (program_frame, default the BASE
frame), mm; orientation as A B C words: the KUKA A, B, C of the tool in that frame, deg. Each hole:
G0 to the approach point on the drill axis; where the drill axis is the program's -Z, a canned
cycle (G81, G82 with the dwell, G83 with the cell's peck), else G1 moves along the drill axis at
approach speed and feed, G4 dwell, G1 retract. Every hole is corrected with the grid (its point
mapped to the robot frame, P' = P + e(P), and the same e applied to all its positions).

Units: mm, deg, mm/s in the inputs; F in mm/min (G94) in the program. Exit 2 on bad input, with
nothing written.
""",
    output=("FILE", "the .ngc to write"),
    report="G-code drilling program",
    rewrite="""\
G-code: positions are in the cell's program_frame (default: its base), G54 active; A, B, C
words are the tool orientation and stay as written. Left untouched: G55-G59/G92 offsets, unknown
motions, parameter words. A G-code arc (G2/G3) moves rigidly, start, centre and end by one shift
(the correction at its centre), where that shift holds along the whole arc to the program's
written resolution; otherwise the arc is left as written and reported. The Status of every
position is the cell's configuration.
""",
)


class GcodePlugin(DialectFolder):
    """G-code as LinuxCNC reads it, under the suffixes CAM posts and controllers use. A new
    program is one file, positions in the cell's program frame. Members as ``DialectPlugin``
    says."""

    name = "gcode"
    title = "RS274NGC / ISO G-code"
    help = HELP
    suffixes = (".ngc", ".nc", ".gcode", ".gc", ".cnc", ".tap", ".iso", ".mpf", ".spf", ".eia")
    exports = ("render_gcode",)

    def targets(self, cell, out):
        return [out]

    def render(self, program, header, templates, out, plan):
        from accugrid.codegen.gcode.emit import gcode_text

        return Rendered({out: gcode_text(program, header, templates)})

    def placement(self, cell, context):
        return cell.dialects[self.name]  # the program frame


PLUGIN = GcodePlugin()
