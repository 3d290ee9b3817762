"""The KUKA KRL dialect, a plug-in (``plugin.PLUGIN``, the interface of ``codegen.plugin``):
emitter (program model to .src/.dat text), parser and rewrite, the cell section. The names of
``__all__`` are imported on first use."""

from accugrid.infra.exports import lazy_namespace

_API = {
    "PLUGIN": "accugrid.codegen.krl.plugin",
    "render_krl": "accugrid.codegen.krl.emit",
    "KrlPlacement": "accugrid.codegen.krl.rewrite",
    "KrlSection": "accugrid.codegen.krl.section",
}
__all__ = list(_API)
__getattr__, __dir__ = lazy_namespace(__name__, _API)
