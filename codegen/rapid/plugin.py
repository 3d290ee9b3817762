"""ABB RAPID as a dialect plug-in (``codegen.plugin.DialectPlugin``): ``PLUGIN``. Light to
import (the registry reads its name and suffixes): the emitter and the reader are imported when
first used."""

from __future__ import annotations

__all__ = ["PLUGIN", "RapidPlugin"]


class RapidPlugin:
    """ABB RAPID modules: ``.mod``, ``.modx`` (RobotWare 7), ``.prg`` (older RAPID programs),
    ``.sys`` (system modules). Members as ``DialectPlugin`` says."""

    name = "rapid"
    title = "ABB RAPID"
    suffixes = (".mod", ".modx", ".prg", ".sys")

    def render(self, program, header, templates, out):
        from accugrid.codegen.rapid.emit import render_rapid

        return render_rapid(program, header, templates, out)

    def scan(self, path, text, section, ignore_external_axes=False):
        from accugrid.codegen.rapid.rewrite import scan

        return scan(path, text, section, ignore_external_axes)

    def splice(self, text, positions, new_xyz, opts):
        from accugrid.codegen.rapid.rewrite import splice

        return splice(text, positions, new_xyz, opts)

    def rewrite(self, texts, opts, section):
        from accugrid.codegen.rapid.rewrite import rewrite_rapid

        return rewrite_rapid(texts, opts, section)

    def add_header(self, text, lines):
        from accugrid.codegen.rapid.rewrite import add_header

        return add_header(text, lines)


PLUGIN = RapidPlugin()
