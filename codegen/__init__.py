"""File IO, the neutral program model, KRL and G-code emitters and parsers, and the CLI."""

from accugrid import __version__

__all__ = ["__version__"]
