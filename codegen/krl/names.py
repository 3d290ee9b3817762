"""KRL names (KUKA System Software 8 manual): a valid name is [A-Za-z_][A-Za-z0-9_]*, at most
24 characters, not a reserved word (``KRL_RESERVED``); ``krl_identifier`` makes one from user
text."""

from __future__ import annotations

import re
import unicodedata

__all__ = ["KRL_NAME_MAX", "KRL_RESERVED", "krl_identifier"]

KRL_NAME_MAX = 24
KRL_RESERVED = frozenset(
    """AND ANIN ANOUT AXIS B_AND B_EXOR B_NOT B_OR BOOL BRAKE C_DIS C_ORI C_PTP C_SPL C_VEL CASE
    CHAR CIRC CIRC_REL CONST CONTINUE DECL DEF DEFAULT DEFDAT DEFFCT DELAY DISTANCE DO E6AXIS
    E6POS ELSE END ENDDAT ENDFCT ENDFOR ENDIF ENDLOOP ENDSPLINE ENDSWITCH ENDWHILE ENUM EXIT EXOR
    EXT EXTFCT FALSE FOR FRAME GLOBAL GOTO HALT IF IMPORT IN INT INTERRUPT IS LIN LIN_REL LOOP
    MAXIMUM MINIMUM NOT OFF ON OR POS PRIO PTP PTP_REL PUBLIC REAL REPEAT RESUME RETURN SCIRC SEC
    SIGNAL SLIN SPL SPLINE SPTP STEP STRUC SWITCH THEN TIME_BLOCK TO TRIGGER TRUE UNTIL WAIT WHEN
    WHILE""".split()
)
"""KRL keywords and type names (KUKA System Software 8 manual): never a name we write."""
_NOT_IDENT = re.compile(r"[^A-Za-z0-9_]")


def krl_identifier(text: str, prefix: str = "P", limit: int = KRL_NAME_MAX) -> str:
    """A KRL identifier derived from user text: invalid characters become ``_``, a leading digit
    or a reserved word gets ``prefix``, and the result is cut to ``limit`` (24) characters."""
    name = _NOT_IDENT.sub("_", unicodedata.normalize("NFKD", str(text)))
    name = name.encode("ascii", "ignore").decode("ascii") or prefix
    if not (name[0].isalpha() or name[0] == "_") or name[:limit].upper() in KRL_RESERVED:
        name = prefix + name
    return name[:limit]
