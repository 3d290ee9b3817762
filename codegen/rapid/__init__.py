"""The ABB RAPID dialect, a plug-in (``plugin.PLUGIN``, the interface of ``codegen.plugin``): the
drilling module (``emit``), the reader and rewrite of existing modules (``rewrite``), the cell
section (``section``) and RAPID names (``names``). The names of ``__all__`` are imported on
first use."""

from accugrid.infra.exports import lazy_namespace

_API = {
    "PLUGIN": "accugrid.codegen.rapid.plugin",
    "render_rapid": "accugrid.codegen.rapid.emit",
    "RapidPlacement": "accugrid.codegen.rapid.rewrite",
    "RapidSection": "accugrid.codegen.rapid.section",
}
__all__ = list(_API)
__getattr__, __dir__ = lazy_namespace(__name__, _API)
