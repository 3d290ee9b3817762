"""What the jobs show besides their files: the self-contained HTML page (``html``), the pages of
the correction, identify and compare jobs (``correction``, ``identify``, ``comparison``, which also
holds compare's text and CSV), and every picture as PNG bytes (``plots``). The names of
``__all__`` are imported on first use."""

from accugrid.infra.exports import lazy_namespace

_API = {
    "report_html": "accugrid.app.reports.html",
    "correction_report": "accugrid.app.reports.correction",
    "identify_report": "accugrid.app.reports.identify",
    "html_report": "accugrid.app.reports.comparison",
}
__all__ = list(_API)
__getattr__, __dir__ = lazy_namespace(__name__, _API)
