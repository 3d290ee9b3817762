"""RAPID identifiers (RAPID reference manual, "Identifiers"): a letter, then letters, digits or
``_``, at most 32 characters, not a reserved word. RAPID is case-insensitive."""

from __future__ import annotations

from accugrid.codegen.program_text import identifier_problem

__all__ = ["RAPID_NAME_MAX", "RAPID_RESERVED", "is_rapid_name", "rapid_name_problem"]

RAPID_NAME_MAX = 32
RAPID_RESERVED = frozenset(
    """ALIAS AND BACKWARD CASE CONNECT CONST DEFAULT DIV DO ELSE ELSEIF ENDFOR ENDFUNC ENDIF
    ENDMODULE ENDPROC ENDRECORD ENDTEST ENDTRAP ENDWHILE ERROR EXIT FALSE FOR FROM FUNC GOTO IF
    INOUT LOCAL MOD MODULE NOSTEPIN NOT NOVIEW OR PERS PROC RAISE READONLY RECORD RETRY RETURN
    STEP SYSMODULE TEST THEN TO TRAP TRUE TRYNEXT UNDO VAR VIEWONLY WHILE WITH XOR""".split()
)


def rapid_name_problem(name: str) -> str | None:
    """Why ``name`` is not a RAPID identifier, None when it is one."""
    problem = identifier_problem(name, RAPID_NAME_MAX, "RAPID allows at most")
    if problem is None and name.upper() in RAPID_RESERVED:
        return "is a RAPID reserved word"
    return problem


def is_rapid_name(name: str) -> bool:
    return rapid_name_problem(name) is None
