"""The application: the ``accugrid`` command (``app.cli``, one module per subcommand in
``app.commands``), each job as one call (``app.jobs``), the reports and plots (``app.reports``).
It uses every other room; nothing imports it. ``main(argv)`` runs the command in this process
and returns its exit code; it is imported on first use."""

from accugrid.infra.exports import lazy_namespace

_API = {"main": "accugrid.app.cli"}
__all__ = list(_API)
__getattr__, __dir__ = lazy_namespace(__name__, _API)
