"""FANUC TP program names: a letter, then letters, digits or ``_``, at most 36 characters (the
R-30iA/R-30iB limit; older controllers keep 8). The controller holds them in upper case: a name
is written upper-cased, so a file ``wing.ls`` holds ``/PROG WING``."""

from __future__ import annotations

from accugrid.codegen.program_text import identifier_problem

__all__ = ["PROGRAM_NAME_MAX", "program_name_problem"]

PROGRAM_NAME_MAX = 36


def program_name_problem(name: str) -> str | None:
    """Why the controller refuses ``name`` as a program name, None when it takes it."""
    return identifier_problem(name, PROGRAM_NAME_MAX, "a FANUC program name at most")
