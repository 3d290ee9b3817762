"""Programs: the points and cell files, the neutral program model and the dialects (one folder
each: KRL, G-code, RAPID). The names of ``__all__`` besides ``__version__`` are imported on
first use; a dialect's renderer (``render_krl``, ``render_gcode``: its plug-in's ``exports``)
through the registry, ``codegen.dialects``."""

from accugrid import __version__
from accugrid.infra.exports import lazy_namespace

_API = {
    "Points": "accugrid.codegen.points",
    "read_points": "accugrid.codegen.points",
    "parse_points": "accugrid.codegen.points",
    "Cell": "accugrid.codegen.cell",
    "load_cell": "accugrid.codegen.cell",
    "Program": "accugrid.codegen.program",
    "build_program": "accugrid.codegen.program",
    "render_krl": "accugrid.codegen.dialects",
    "render_gcode": "accugrid.codegen.dialects",
}
__all__ = ["__version__", *_API]
__getattr__, __dir__ = lazy_namespace(__name__, _API)
