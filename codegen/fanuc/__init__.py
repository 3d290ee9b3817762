"""The FANUC TP dialect (ASCII ``.ls`` programs), a plug-in (``plugin.PLUGIN``, the interface of
``codegen.plugin``): the drilling program (``emit``), the reader (``parse``) and rewrite of
existing programs (``rewrite``), the cell section (``section``), program names (``names``) and
the position configuration (``config``). The names of ``__all__`` are imported on first use."""

from accugrid.infra.exports import lazy_namespace

_API = {
    "PLUGIN": "accugrid.codegen.fanuc.plugin",
    "render_fanuc": "accugrid.codegen.fanuc.emit",
    "FanucPlacement": "accugrid.codegen.fanuc.rewrite",
    "FanucSection": "accugrid.codegen.fanuc.section",
}
__all__ = list(_API)
__getattr__, __dir__ = lazy_namespace(__name__, _API)
