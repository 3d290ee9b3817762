"""RS274NGC / ISO G-code as a dialect plug-in (``codegen.plugin.DialectPlugin``): ``PLUGIN``.
Light to import (the registry reads its name and suffixes): the emitter and the reader are
imported when first used."""

from __future__ import annotations

from accugrid.codegen.plugin import DialectFolder, Rendered

__all__ = ["GcodePlugin", "PLUGIN"]


class GcodePlugin(DialectFolder):
    """G-code as LinuxCNC reads it, under the suffixes CAM posts and controllers use. A new
    program is one file, positions in the cell's program frame. Members as ``DialectPlugin``
    says."""

    name = "gcode"
    title = "RS274NGC / ISO G-code"
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
