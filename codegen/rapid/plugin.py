"""ABB RAPID as a dialect plug-in (``codegen.plugin.DialectPlugin``): ``PLUGIN``."""

from __future__ import annotations

from accugrid.codegen.rapid.emit import render_rapid
from accugrid.codegen.rapid.rewrite import add_header, rewrite_rapid, scan, splice

__all__ = ["PLUGIN", "RapidPlugin"]


class RapidPlugin:
    """ABB RAPID modules: ``.mod``, ``.modx`` (RobotWare 7), ``.prg`` (older RAPID programs),
    ``.sys`` (system modules)."""

    name = "rapid"
    title = "ABB RAPID"
    suffixes = (".mod", ".modx", ".prg", ".sys")
    render = staticmethod(render_rapid)
    scan = staticmethod(scan)
    splice = staticmethod(splice)
    rewrite = staticmethod(rewrite_rapid)
    add_header = staticmethod(add_header)


PLUGIN = RapidPlugin()
