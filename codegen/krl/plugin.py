"""KUKA KRL as a dialect plug-in (``codegen.plugin.DialectPlugin``): ``PLUGIN``. Light to import
(the registry reads its name and suffixes): the emitter and the reader are imported when first
used."""

from __future__ import annotations

import re

from accugrid.codegen.plugin import DialectFolder, Rendered

__all__ = ["PLUGIN", "KrlPlugin"]


class KrlPlugin(DialectFolder):
    """KUKA KRL: a program is a ``.src`` (what runs) and its ``.dat``; ``.sub`` for submit
    programs. A new program is ``NAME.src``/``NAME.dat`` in a folder, split into modules
    ``NAME_001``.. when long. Members as ``DialectPlugin`` says."""

    name = "krl"
    title = "KUKA KRL"
    suffixes = (".src", ".dat", ".sub")
    controllers = ("kuka",)  # the robots it drives
    pair = (".src", ".dat")
    exports = ("render_krl",)

    def targets(self, cell, out):
        name = cell.dialects[self.name].name
        return [out / f"{name}{suffix}" for suffix in reversed(self.pair)]  # .src renamed last

    def plan(self, cell, holes, header, templates):
        from accugrid.codegen.krl.emit import module_split

        return module_split(cell, holes, header, templates)

    def render(self, program, header, templates, out, plan):
        """The modules of an earlier job of this name are stale; ``NAME.src`` is written last
        (``NAME.dat`` before it)."""
        from accugrid.codegen.krl.emit import render_krl

        name = program.cell.dialects[self.name].name
        files = render_krl(program, header, templates, plan)
        module = re.compile(rf"{re.escape(name)}_[0-9]{{3,}}\.(src|dat)")
        stale = [p for p in out.glob(f"{name}_*") if module.fullmatch(p.name)]
        return Rendered(files.at(out), self.targets(program.cell, out), stale)

    def placement(self, cell, context):
        from accugrid.codegen.krl.rewrite import KrlPlacement

        return KrlPlacement(
            base_data=cell.base_data,
            base=context.base,
            trust_calls=context.trust_calls,
            ignore_external_axes=context.ignore_external_axes,
            config_dat=context.controller_data,
        )

    def measurement(self):
        """The laser-tracker measurement program (``krl.emit.KrlMeasurement``)."""
        from accugrid.codegen.krl.emit import MEASUREMENT

        return MEASUREMENT


PLUGIN = KrlPlugin()
