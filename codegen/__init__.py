"""File IO, the neutral program model, KRL and G-code emitters and parsers, and the CLI."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("accugrid")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0.0.0+source"
