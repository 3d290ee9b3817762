"""RS274NGC parameters and expressions, evaluated before run time where that is decidable.

A program read top to bottom keeps a parameter table (``Parameters``): numbered (``#1``) and
named (``#<depth>``, ``#<_clearance>``) parameters assigned in straight-line code. A word's
value (``X#1``, ``X[1+2]``, ``x sin[30]``, ``Z-#<_z>``, ``X[#1*2]``) is evaluated as LinuxCNC
evaluates it: brackets, unary functions (ABS ACOS ASIN COS EXP FIX FUP ROUND LN SIN SQRT TAN in
degrees, ``ATAN[y]/[x]``, ``EXISTS[#<name>]``), binary operators by precedence (``**``; ``*``
``/`` ``MOD``; ``+`` ``-``; ``EQ NE GT GE LT LE``; ``AND OR XOR``, left to right within one),
``#`` of a value (``##1``, ``#[1+2]``). The assignments of a line take effect after the whole
line is read (``#1=5 G0 X#1`` moves to the old ``#1``).

Not decidable, with the reason (``Undecided``): a numbered parameter above 5000 (system: work
offsets, probe results, current position, tool data), a name starting with ``_`` that the
program never assigned (LinuxCNC's read-only run-time values such as ``#<_x>``), a parameter not
assigned before the line (its value is the controller's), an operation LinuxCNC refuses (square
root of a negative number, division by zero). O-word control flow is not followed here: the
reader stops placing positions after the first O-word.
"""

from __future__ import annotations

import math
import re

__all__ = ["SYSTEM_FROM", "Parameters", "Undecided"]

SYSTEM_FROM = 5001  # numbered parameters from here on are the controller's (offsets, probe, ...)
_NUMBER_RE = re.compile(r"(?:\d++(?:\.\d*+)?+|\.\d++)")
_NAME_RE = re.compile(r"[a-z]++")
_BINARY = (  # (operators, precedence): higher binds tighter
    (("**",), 4),
    (("*", "/", "mod"), 3),
    (("+", "-"), 2),
    (("eq", "ne", "gt", "ge", "lt", "le"), 1),
    (("and", "xor", "or"), 0),
)
_PRECEDENCE = {op: p for ops, p in _BINARY for op in ops}
_WORD_OPERATORS = sorted((op for op in _PRECEDENCE if op.isalpha()), key=len, reverse=True)
_CLOSE_EQUAL = 1e-4  # LinuxCNC's tolerance of EQ and NE, and of an integer parameter index
_MAX_DEPTH = 64  # values nested in one another (brackets, #, signs) read before giving up


class Undecided(Exception):
    """A value that is only known at run time (or not at all); ``str`` is the reason."""


def _degrees(f):
    return lambda v: f(math.radians(v))


def _inverse(f, what: str):
    def apply(v: float) -> float:
        if not -1.0 <= v <= 1.0:
            raise Undecided(f"{what}[{v:g}] is outside [-1, 1]")
        return math.degrees(f(v))

    return apply


def _checked(f, what: str, ok):
    def apply(v: float) -> float:
        if not ok(v):
            raise Undecided(f"{what}[{v:g}] is not defined")
        return f(v)

    return apply


def _round(v: float) -> float:
    """LinuxCNC's ROUND: half away from zero."""
    return float(math.floor(abs(v) + 0.5)) * (1.0 if v >= 0 else -1.0)


_FUNCTIONS = {
    "abs": abs,
    "acos": _inverse(math.acos, "ACOS"),
    "asin": _inverse(math.asin, "ASIN"),
    "cos": _degrees(math.cos),
    "exp": math.exp,
    "fix": lambda v: float(math.floor(v)),
    "fup": lambda v: float(math.ceil(v)),
    "round": _round,
    "ln": _checked(math.log, "LN", lambda v: v > 0),
    "sin": _degrees(math.sin),
    "sqrt": _checked(math.sqrt, "SQRT", lambda v: v >= 0),
    "tan": _degrees(math.tan),
}


def _binary(op: str, a: float, b: float) -> float:
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if op == "/":
        if b == 0:
            raise Undecided("division by zero")
        return a / b
    if op == "mod":
        if b == 0:
            raise Undecided("MOD by zero")
        r = math.fmod(a, b)
        return r + abs(b) if r < 0 else r
    if op == "**":
        if a < 0 and b != int(b):
            raise Undecided(f"{a:g}**{b:g} is not a real number")
        if a == 0 and b < 0:
            raise Undecided("0 to a negative power")
        return a**b
    if op == "eq":
        return float(abs(a - b) < _CLOSE_EQUAL)
    if op == "ne":
        return float(abs(a - b) >= _CLOSE_EQUAL)
    if op == "gt":
        return float(a > b)
    if op == "ge":
        return float(a >= b)
    if op == "lt":
        return float(a < b)
    if op == "le":
        return float(a <= b)
    if op == "and":
        return float(a != 0 and b != 0)
    if op == "or":
        return float(a != 0 or b != 0)
    return float((a != 0) != (b != 0))  # xor


class _Expression:
    """One expression's text (lower case, blanks removed) read by recursive descent; each
    character is looked at once, so a hostile line cannot make it backtrack."""

    def __init__(self, text: str, table: Parameters) -> None:
        self.s = "".join(text.split()).lower()
        self.i = 0
        self.table = table
        self.depth = 0

    def fail(self) -> ValueError:
        return ValueError(f"cannot read {self.s!r} at character {self.i + 1}")

    def expect(self, ch: str) -> None:
        if not self.s.startswith(ch, self.i):
            raise self.fail()
        self.i += len(ch)

    def whole(self) -> float:
        value = self.value()
        if self.i != len(self.s):
            raise self.fail()
        return value

    def value(self) -> float:
        """A real value: a number, ``#`` parameter, ``[expression]`` or a function, with an
        optional sign."""
        self.depth += 1
        if self.depth > _MAX_DEPTH:
            raise Undecided(f"nested more than {_MAX_DEPTH} deep")
        try:
            return self._value()
        finally:
            self.depth -= 1

    def _value(self) -> float:
        s, i = self.s, self.i
        if i >= len(s):
            raise self.fail()
        ch = s[i]
        if ch in "+-":
            self.i += 1
            v = self.value()
            return -v if ch == "-" else v
        if ch == "[":
            self.i += 1
            v = self.binary(0)
            self.expect("]")
            return v
        if ch == "#":
            self.i += 1
            return self.table.get(self.key())
        m = _NUMBER_RE.match(s, i)
        if m is not None:
            self.i = m.end()
            return float(m.group())
        m = _NAME_RE.match(s, i)
        if m is None:
            raise self.fail()
        name, self.i = m.group(), m.end()
        if name == "atan":
            y = self.bracket()
            self.expect("/")
            x = self.bracket()
            return math.degrees(math.atan2(y, x))
        if name == "exists":
            self.expect("[#<")
            close = s.find(">", self.i)
            if close < 0:
                raise self.fail()
            key, self.i = s[self.i : close], close + 1
            self.expect("]")
            return float(key in self.table.values)
        if name not in _FUNCTIONS:
            raise self.fail()
        return _FUNCTIONS[name](self.bracket())

    def bracket(self) -> float:
        self.expect("[")
        v = self.binary(0)
        self.expect("]")
        return v

    def key(self) -> int | str:
        """The parameter after a ``#``: a name (``<name>``) or a number (a value)."""
        s = self.s
        if s.startswith("<", self.i):
            close = s.find(">", self.i)
            if close < 0:
                raise self.fail()
            key, self.i = s[self.i + 1 : close], close + 1
            return key
        index = self.value()
        if abs(index - round(index)) >= _CLOSE_EQUAL:
            raise Undecided(f"#{index:g}: a parameter number is an integer")
        return int(round(index))

    def operator(self) -> str | None:
        s, i = self.s, self.i
        if s.startswith("**", i):
            return "**"
        if i < len(s) and s[i] in "*/+-":
            return s[i]
        for op in _WORD_OPERATORS:
            if s.startswith(op, i):
                return op
        return None

    def binary(self, lowest: int) -> float:
        """Operators of precedence ``lowest`` and tighter, left to right."""
        left = self.value()
        while True:
            op = self.operator()
            if op is None or _PRECEDENCE[op] < lowest:
                return left
            self.i += len(op)
            right = self.binary(_PRECEDENCE[op] + 1)
            left = _binary(op, left, right)


class Parameters:
    """The parameter table while a program is read: ``values`` key (int, or a lower-case name
    without blanks) -> value, or the reason it is not known (str)."""

    def __init__(self) -> None:
        self.values: dict[int | str, float | str] = {}
        self.unknown = ""  # why a parameter not set since is not known ("": see ``get``)

    def forget(self, why: str) -> None:
        """Every parameter is unknown from here on (an assignment may have set any), ``why``."""
        self.values.clear()
        self.unknown = why

    def get(self, key: int | str) -> float:
        """The value of ``#key``; Undecided with the reason when it is not known here."""
        found = self.values.get(key)
        if isinstance(found, float):
            return found
        shown = f"#<{key}>" if isinstance(key, str) else f"#{key}"
        if found is not None:
            raise Undecided(f"{shown} {found}")
        if self.unknown:
            raise Undecided(f"{shown} {self.unknown}")
        if isinstance(key, int) and key >= SYSTEM_FROM:
            raise Undecided(f"{shown} is a system parameter, read at run time")
        if isinstance(key, str) and key.startswith("_"):
            raise Undecided(f"{shown} is a system parameter or not set: read at run time")
        raise Undecided(f"{shown} is not set before this line (its value is the controller's)")

    def evaluate(self, text: str) -> float:
        """The value of a word's text after its letter (``#1``, ``[1+2]``, ``sin[30]``, ``-#<a>``);
        Undecided with the reason, ValueError when the text is not an expression."""
        return _Expression(text, self).whole()

    def key_of(self, text: str) -> int | str:
        """The parameter an assignment's left side (``#1``, ``#<name>``, ``##2``) names."""
        expression = _Expression(text, self)
        expression.expect("#")
        key = expression.key()
        if expression.i != len(expression.s):
            raise expression.fail()
        return key
