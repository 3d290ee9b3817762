"""Infrastructure every layer may use: located input errors, guarded reading of input files, the
YAML and CSV table readers, bulk decimal reading, number text, SHA-256 digests, whole-job atomic
writes, safe text for programs, independent blocks on a few threads, one BLAS thread for small
solves and lazily imported public names. It imports nothing from the other rooms. The names of
``__all__`` are imported on first use."""

from accugrid.infra.exports import lazy_namespace

_API = {
    "InputError": "accugrid.infra.errors",
    "TableFormat": "accugrid.infra.csvtable",
    "read_table": "accugrid.infra.csvtable",
}
__all__ = list(_API)
__getattr__, __dir__ = lazy_namespace(__name__, _API)
