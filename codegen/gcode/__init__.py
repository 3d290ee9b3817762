"""The G-code dialect (RS274/NGC as LinuxCNC reads it): emitter, parser and rewrite. The names
of ``__all__`` are imported on first use."""

from accugrid.infra.exports import lazy_namespace

_API = {
    "render_gcode": "accugrid.codegen.gcode.emit",
    "rewrite_gcode": "accugrid.codegen.gcode.rewrite",
    "GcodeSection": "accugrid.codegen.gcode.section",
}
__all__ = list(_API)
__getattr__, __dir__ = lazy_namespace(__name__, _API)
