"""RAPID identifiers (RAPID reference manual, "Identifiers"): a letter, then letters, digits or
``_``, at most 32 characters, not a reserved word. RAPID is case-insensitive."""

from __future__ import annotations

import re

__all__ = ["RAPID_NAME_MAX", "RAPID_RESERVED", "is_rapid_name", "rapid_name_problem"]

RAPID_NAME_MAX = 32
RAPID_RESERVED = frozenset(
    """ALIAS AND BACKWARD CASE CONNECT CONST DEFAULT DIV DO ELSE ELSEIF ENDFOR ENDFUNC ENDIF
    ENDMODULE ENDPROC ENDRECORD ENDTEST ENDTRAP ENDWHILE ERROR EXIT FALSE FOR FROM FUNC GOTO IF
    INOUT LOCAL MOD MODULE NOSTEPIN NOT NOVIEW OR PERS PROC RAISE READONLY RECORD RETRY RETURN
    STEP SYSMODULE TEST THEN TO TRAP TRUE TRYNEXT UNDO VAR VIEWONLY WHILE WITH XOR""".split()
)
_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*")


def rapid_name_problem(name: str) -> str | None:
    """Why ``name`` is not a RAPID identifier, None when it is one."""
    if not _NAME.fullmatch(name):
        return "must be a letter, then letters, digits or _"
    if len(name) > RAPID_NAME_MAX:
        return f"has {len(name)} characters, RAPID allows at most {RAPID_NAME_MAX}"
    if name.upper() in RAPID_RESERVED:
        return "is a RAPID reserved word"
    return None


def is_rapid_name(name: str) -> bool:
    return rapid_name_problem(name) is None
