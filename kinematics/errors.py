"""The one exception type for bad user input, shared by every layer.

It lives in the lowest layer so that kinematics, compensation and codegen can all raise it; the CLI
turns it into a one-line message and exit code 2.
"""

from __future__ import annotations

import os


class InputError(ValueError):
    """Bad input from a user file or argument, located as precisely as we know.

    ``str(err)`` is ``"file:line:column: message"`` with the parts that are known.
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
        where = [str(p) for p in (self.path, self.line, self.column) if p is not None]
        return ":".join(where) + (": " if where else "") + self.message
