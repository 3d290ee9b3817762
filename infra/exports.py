"""Package namespaces whose public names are imported on first use.

``import accugrid`` (and the CLI's start-up) must not import Pinocchio, SciPy or Jinja: a package
lists its public names with the module that defines each, and ``lazy_namespace`` gives it the
module-level ``__getattr__`` and ``__dir__`` that import that module when a name is first asked
for (PEP 562). A name is cached in the package once loaded.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping
from importlib import import_module

__all__ = ["lazy_namespace"]


def lazy_namespace(
    package: str, api: Mapping[str, str]
) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for ``package`` whose public name -> defining module is
    ``api``; ``__all__`` is the package's own list of the same names."""

    def __getattr__(name: str) -> object:
        if name not in api:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(api[name]), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(api))

    return __getattr__, __dir__
