"""The one exception type for bad user input, shared by every layer.

It lives in the lowest layer so that kinematics, compensation and codegen can all raise it; the CLI
turns it into a one-line message and exit code 2.
"""

from __future__ import annotations

import os

__all__ = ["InputError", "printable"]

MESSAGE_MAX = 400  # characters of a message, and of the file name in it


def printable(text: object, limit: int = MESSAGE_MAX) -> str:
    """``text`` made safe for one terminal line: control, format and separator characters (newline,
    ANSI escape, NUL, U+202E, U+2028 ...) become ``\\xNN``/``\\uNNNN`` escapes, and the result is
    cut to ``limit`` characters with ``...``."""
    text = str(text)
    out: list[str] = []
    size = 0
    for ch in text:
        if ch.isprintable() or ch == " ":
            piece = ch
        elif ord(ch) < 0x100:
            piece = f"\\x{ord(ch):02x}"
        else:
            piece = f"\\u{ord(ch):04x}" if ord(ch) < 0x10000 else f"\\U{ord(ch):08x}"
        out.append(piece)
        size += len(piece)
        if size > limit:
            break
    result = "".join(out)
    return result if len(result) <= limit else result[: limit - 3] + "..."


class InputError(ValueError):
    """Bad input from a user file or argument, located as precisely as we know.

    ``str(err)`` is ``"file:line:column: message"`` with the parts that are known, on one
    printable line of bounded length (user text in it is escaped, see ``printable``).
    """

    def __init__(
        self,
        message: str,
        path: str | os.PathLike[str] | None = None,
        line: int | None = None,
        column: int | None = None,
    ) -> None:
        self.message = message
        self.path = None if path is None else os.fspath(path)
        self.line = line
        self.column = column
        super().__init__(str(self))

    def __str__(self) -> str:
        where = [printable(self.path)] if self.path is not None else []
        where += [str(p) for p in (self.line, self.column) if p is not None]
        return ":".join(where) + (": " if where else "") + printable(self.message)
