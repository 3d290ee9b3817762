"""ABB RAPID as a dialect plug-in (``codegen.plugin.DialectPlugin``): ``PLUGIN``. Light to
import (the registry reads its name and suffixes): the emitter and the reader are imported when
first used."""

from __future__ import annotations

from accugrid.codegen.plugin import DialectFolder, Rendered

__all__ = ["PLUGIN", "RapidPlugin"]


class RapidPlugin(DialectFolder):
    """ABB RAPID modules: ``.mod``, ``.modx`` (RobotWare 7), ``.prg`` (older RAPID programs),
    ``.sys`` (system modules). A new program is one module, its confdata from every pose's
    joint angles. Members as ``DialectPlugin`` says."""

    name = "rapid"
    title = "ABB RAPID"
    suffixes = (".mod", ".modx", ".prg", ".sys")
    controllers = ("abb",)  # the robots it drives
    joints = True  # confdata comes from the joint angles

    def targets(self, cell, out):
        from accugrid.codegen.rapid.emit import module_name

        module_name(cell.dialects[self.name].module, out)  # a name RAPID refuses: before any work
        return [out]

    def render(self, program, header, templates, out, plan):
        from accugrid.codegen.rapid.emit import render_rapid

        return Rendered(render_rapid(program, header, templates, out))

    def placement(self, cell, context):
        from accugrid.codegen.rapid.rewrite import RapidPlacement

        return RapidPlacement(cell.dialects[self.name], context.ignore_external_axes)


PLUGIN = RapidPlugin()
