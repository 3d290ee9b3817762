"""Programs: the points and cell files, the neutral program model and the dialects (one folder
each, registered in ``codegen.dialects``). The names of ``__all__`` besides ``__version__`` are
imported on first use; the names a dialect's plug-in exports (``EXPORTS``, its renderer)
through the registry."""

from accugrid import __version__
from accugrid.codegen.dialects import EXPORTS
from accugrid.infra.exports import lazy_namespace

_API = {
    "Points": "accugrid.codegen.points",
    "read_points": "accugrid.codegen.points",
    "parse_points": "accugrid.codegen.points",
    "Cell": "accugrid.codegen.cell",
    "load_cell": "accugrid.codegen.cell",
    "Program": "accugrid.codegen.program",
    "build_program": "accugrid.codegen.program",
    **dict.fromkeys(EXPORTS, "accugrid.codegen.dialects"),
}
__all__ = ["__version__", *_API]
__getattr__, __dir__ = lazy_namespace(__name__, _API)
