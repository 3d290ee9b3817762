"""The G-code dialect (RS274/NGC as LinuxCNC reads it), a plug-in (``plugin.PLUGIN``, the
interface of ``codegen.plugin``): emitter, parser and rewrite, the cell section. The names of
``__all__`` are imported on first use."""

from accugrid.infra.exports import lazy_namespace

_API = {
    "PLUGIN": "accugrid.codegen.gcode.plugin",
    "render_gcode": "accugrid.codegen.gcode.emit",
    "GcodeSection": "accugrid.codegen.gcode.section",
}
__all__ = list(_API)
__getattr__, __dir__ = lazy_namespace(__name__, _API)
