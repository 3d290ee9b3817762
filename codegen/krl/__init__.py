"""The KUKA KRL dialect: emitter (program model to .src/.dat text), parser and rewrite. The
names of ``__all__`` are imported on first use."""

from accugrid.infra.exports import lazy_namespace

_API = {
    "render_krl": "accugrid.codegen.krl.emit",
    "rewrite_krl": "accugrid.codegen.krl.rewrite",
    "KrlSection": "accugrid.codegen.krl.section",
}
__all__ = list(_API)
__getattr__, __dir__ = lazy_namespace(__name__, _API)
