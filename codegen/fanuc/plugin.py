"""FANUC TP as a dialect plug-in (``codegen.plugin.DialectPlugin``): ``PLUGIN``. Light to import
(the registry reads its name and suffixes): the emitter and the reader are imported when first
used."""

from __future__ import annotations

from accugrid.codegen.plugin import DialectFolder, Rendered

__all__ = ["PLUGIN", "FanucPlugin"]


class FanucPlugin(DialectFolder):
    """FANUC TP programs in their ASCII form (``.ls``). A new program is one file, its CONFIG
    from every pose's configuration. Members as ``DialectPlugin`` says."""

    name = "fanuc"
    title = "FANUC TP"
    suffixes = (".ls",)
    controllers = ("fanuc",)  # the robots it drives
    exports = ("render_fanuc",)

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

        return FanucPlacement(cell.dialects[self.name], context.ignore_external_axes)


PLUGIN = FanucPlugin()
