"""KUKA KRL reader: every Cartesian position of a .src/.dat with the exact span of each number,
and the base frame ($BASE) in effect wherever a motion uses one.

Line-based and case-insensitive (KRL has one statement per line; ``;`` starts a comment, so
inline-form FOLD lines are comments). It finds:

- positions: ``DECL [GLOBAL] [CONST] E6POS|POS|FRAME|AXIS|E6AXIS name = {...}`` (a CONST one
  carries its reason), element or variable assignments ``name[3] = {...}``, the position members
  of user STRUC values (``gsCNC1[3] = {fCnC {X ..}, grFeedrate 95}`` gives ``gsCNC1[3].fCnC``),
  and aggregates inside motions (``PTP``, ``LIN``, ``CIRC aux, target``, ``SPTP``, ``SLIN``,
  ``SCIRC``, ``SPL``, the ``_REL`` forms);
- uses: motions that go to a named position (``PTP XP1``, ``LIN lfWorkPos[i]``,
  ``LIN gsCNC1[i].fCNC``); the target ends before ``C_DIS``/``C_VEL``/``WITH``;
- what is not a position: names used as frames (assigned to ``$TOOL``/``$BASE``/``$LOAD``/
  ``TOOL_DATA``/``BASE_DATA``, operands of ``:``), every declared name with its type (so a
  motion to a local variable is reported as such), FDATs (``BASE_NO``, ``TOOL_NO``,
  ``IPO_FRAME``);
- base frame context, followed in program order: ``$BASE = BASE_DATA[n]``, ``$BASE = {FRAME: ..}``,
  ``$BASE = $NULLFRAME``, ``BAS(#BASE, n)``, ``BAS(#INITMOV, ..)`` (base 0, tool 1),
  ``FDAT_ACT = Fname`` (``BASE_NO`` of the FDAT declaration), for one spline motion
  ``WITH $BASE = SBASE(Fname.BASE_NO)`` and for the segments of a ``SPLINE``/``PTP_SPLINE``
  block the block's own ``WITH $BASE = ...`` (until ``ENDSPLINE``). What cannot be decided is
  an ``unknown`` base with the reason: frame arithmetic ``:``, a variable, ``EK(...)``, the
  start of a routine (inherited from the caller), a call that may change it (``_Flow``: a call
  keeps it when ``scan_krl``'s ``calls`` says its routine does, or in an inline form that
  applied its own FDAT, ``_Form``), a jump target, a branch or loop that changes it.
- routines (``KrlScan.routines``): what each changes of $BASE and $TOOL and what it calls, for
  ``codegen.krl.routines``;
- tool context, followed with the base (``BaseRef.tool``): ``$TOOL = TOOL_DATA[n]``,
  ``$TOOL = $NULLFRAME`` (tool 0, the flange), ``BAS(#TOOL, n)``, an FDAT's ``TOOL_NO``,
  ``$TOOL = {FRAME: X .., C ..}`` (a ``ToolFrame``, matched against the cell's tools when the
  files are resolved), a motion's or spline block's own ``WITH $TOOL = ...``; any other
  ``$TOOL`` value, and a branch or loop that changes it, leaves
  the tool unknown with the reason.

Numbers are spans into the text given (character offsets), so a rewrite replaces only them.
Every pattern is linear in its input (see the note above ``NUMBER``).

Reading is whole-text first, a block of lines (``_CHUNK``) at a time, in two lanes: lines in
the exact layout a controller writes (``codegen.krl.rigid``: array operations on the bytes, no
regex; declarations with a flat aggregate and motions to a name) and every other line through
the statement reader. A rigid line reads as the statement reader reads it
(``tests/test_krl_fast_paths.py``), and rigid lines change no state, so a run of them takes the
base in effect. What is read is kept in columns (``codegen.krl.tables``);
``KrlScan.positions`` and ``KrlScan.uses`` build objects on demand.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field, replace
from typing import NamedTuple

import numpy as np

from accugrid.codegen.bytescan import distinct, text_bytes
from accugrid.codegen.krl.rigid import read_rigid
from accugrid.codegen.krl.tables import (
    ASSIGN,
    DECL,
    KIND_NAMES,
    MOTION,
    PositionTable,
    UseTable,
    position_columns,
    use_columns,
)
from accugrid.codegen.program_text import check_text, decimals_of, distinct_ints, split_lines
from accugrid.infra.errors import InputError

__all__ = [
    "CARTESIAN_KEYS",
    "JOINT_KEYS",
    "MOTIONS",
    "POSITION_TYPES",
    "BaseRef",
    "Declared",
    "Fdat",
    "FRAME_OPERAND",
    "FrameUse",
    "JOINT_TARGET",
    "KrlPosition",
    "KrlScan",
    "KrlUse",
    "Number",
    "RELATIVE",
    "Relative",
    "Routine",
    "ToolFrame",
    "code_part",
    "match_brace",
    "normalize_name",
    "parse_aggregate",
    "parse_krl",
    "position_reason",
    "scan_krl",
    "wildcard",
]

MOTIONS = frozenset(
    "PTP LIN CIRC SPTP SLIN SCIRC SPL PTP_REL LIN_REL CIRC_REL SPTP_REL SLIN_REL SCIRC_REL".split()
)
POSITION_TYPES = frozenset(("E6POS", "POS", "FRAME", "AXIS", "E6AXIS"))
CARTESIAN_KEYS = frozenset("X Y Z A B C S T E1 E2 E3 E4 E5 E6".split())
_JOINTS = frozenset(("A1", "A2", "A3", "A4", "A5", "A6"))
JOINT_KEYS = frozenset("A1 A2 A3 A4 A5 A6 E1 E2 E3 E4 E5 E6".split())
# the reason of an aggregate of joint angles: a target the robot reaches by its joints, never a
# Cartesian position to correct
JOINT_TARGET = "joint-space target (AXIS/E6AXIS): not a Cartesian position"
# how the reason of a relative motion's aggregate begins (``KrlScan.relative`` says more)
RELATIVE = "relative motion"
# how the reason of an operand of ':' before the last (a frame or an offset) begins: the motion's
# target is the last operand, which alone stands for the motion
FRAME_OPERAND = "the frame operand of ':'"
_NOT_CALLS = (
    frozenset(
        """IF ELSE ENDIF WHILE ENDWHILE FOR ENDFOR LOOP ENDLOOP REPEAT UNTIL SWITCH CASE DEFAULT
    ENDSWITCH RETURN WAIT HALT CONTINUE EXIT GOTO TRIGGER INTERRUPT ANOUT ANIN DIGIN PULSE BRAKE
    RESUME DEF DEFFCT END ENDFCT DECL EXT EXTFCT EXTP EXTFCTP GLOBAL SIGNAL STRUC ENUM CONST
    DEFDAT ENDDAT PUBLIC SPLINE ENDSPLINE PTP_SPLINE BAS NOT""".split()
    )
    | MOTIONS
)

# Every pattern is linear in its input: possessive quantifiers (no backtracking into a number or
# a run of spaces), no lazy scan followed by an optional tail, and no pattern that a search would
# restart at every character of a long run (the flat-aggregate item starts at a word start only).
NUMBER = r"[-+]?+(?:\d++(?:\.\d*+)?+|\.\d++)(?:[eE][-+]?+\d++)?+"
_END = r"(?=\s*+(?:,|$))"
_FLAT_RE = re.compile(
    r"(?<![\w$])([A-Za-z_]\w*+)(\s++)(?:("
    + NUMBER
    + ")"
    + _END
    + "|('[^']*+')"
    + _END
    + r"|([^,]*+))(\s*+(?:,\s*+|$))"
)
_ITEM_RE = re.compile(
    r"\s*+([A-Za-z_]\w*+)\s++(?:("
    + NUMBER
    + ")"
    + _END
    + "|('[^']*+')"
    + _END
    + r"|([^,]*+))\s*+(?:,|$)"
)
# a component whose value holds commas: a "string" (CHAR array: NAME[] "text"; KRL strings have
# no escape, a string ends at the next quote) or a nested aggregate {...}
_NESTED_ITEM_RE = re.compile(r'\s*+([A-Za-z_]\w*+)(?:\s*+\[\s*+\])?+\s*+(?:("[^"]*+")|(?=\{))')
_TYPE_PREFIX_RE = re.compile(r"\s*+([A-Za-z_]\w*+)\s*+:")
_LABEL_RE = re.compile(r"\s*+([A-Za-z_]\w*+)\s*+:(?!:)\s*+")
_WORD_RE = re.compile(r"\s*+([A-Za-z_$]\w*+)")
_DECL_RE = re.compile(
    r"\s*+(?:GLOBAL\s++)?(?:DECL\s++)?(?:GLOBAL\s++)?(CONST\s++)?([A-Za-z_]\w*+)\s++"
    r"([A-Za-z_$]\w*+)\s*+(\[[^\]]*+\])?+\s*+",
    re.I,
)
_GLOBAL_DECL_RE = re.compile(r"\s*+GLOBAL\s++DECL\b", re.I)
_NAME = r"([A-Za-z_$][\w$]*+)\s*+(\[[^\]]*+\])?+((?:\s*+\.\s*+\w++)*+)"
_TARGET_NAME_RE = re.compile(_NAME)
_ASSIGN_RE = re.compile(r"\s*+" + _NAME + r"\s*+=(?!=)\s*+")
_INT_RE = re.compile(r"\s*+\+?(\d++)\s*+$")
_BAS_RE = re.compile(r"\s*+BAS\s*+\(\s*+#\s*+(\w++)", re.I)
_BASE_DATA_RE = re.compile(r"\s*+BASE_DATA\s*+\[\s*+(\d++)\s*+\]\s*+$", re.I)
_TOOL_DATA_RE = re.compile(r"\s*+TOOL_DATA\s*+\[\s*+(\d++)\s*+\]\s*+$", re.I)
_CALL_RE = re.compile(r"\s*+([A-Za-z_]\w*+)\s*+\(")
_DO_RE = re.compile(r"\bDO\s++([A-Za-z_]\w*+)\s*+\(", re.I)  # what a trigger or interrupt runs
_CALLED_RE = re.compile(r"(?<![\w$#.])([A-Za-z_]\w*+)\s*+\(")  # a name called anywhere
# statements whose "name(" are declarations or asynchronous calls (a trigger's, an interrupt's)
_NO_EXPRESSION_CALLS = frozenset(
    "DEF DEFFCT GLOBAL EXT EXTFCT EXTP EXTFCTP DECL TRIGGER INTERRUPT SIGNAL STRUC ENUM".split()
)
_ROUTINE_RE = re.compile(
    r"\s*+(?:GLOBAL\s++)?(DEF|DEFFCT)\s++(?:\w++\s++)?([A-Za-z_]\w*+)\s*+\(", re.I
)
_WITH_RE = re.compile(r"\bWITH\b", re.I)
_BASE_SET_RE = re.compile(r"\$BASE\s*+=\s*+", re.I)
_NEXT_SYSVAR_RE = re.compile(r",\s*+\$")
_APPROXIMATION_RE = re.compile(r"\s(?:C_(?:DIS|PTP|ORI|VEL|SPL)|WITH)\b", re.I)
_INDEX_RE = re.compile(r"\[\s*+(\d++)\s*+\]")
_TOOL_FRAME_RE = re.compile(r"#\s*+TOOL\b", re.I)  # a relative motion in the tool frame
_WITH_TOOL_RE = re.compile(r"\bWITH\b.*\$TOOL\s*+=", re.I)
_PARTIAL = "partial aggregate"
_IDENT_RE = re.compile(r"[A-Za-z_]\w*+")


class Number(NamedTuple):
    """One literal in a program: ``text[start:end]`` is ``literal``, the number as written."""

    key: str  # component, upper case: "X", "A", "S", "E1", "A1"
    value: float
    start: int  # character offset in the text given to the parser
    end: int
    literal: str

    @property
    def decimals(self) -> int:
        """Digits after the decimal point as written (-1 for an S/T bit string)."""
        return -1 if self.literal[:1] == "'" else decimals_of(self.literal)


class ToolFrame(NamedTuple):
    """A tool set as a literal frame (``$TOOL = {FRAME: X -30, ...}``): its X, Y, Z mm and A, B,
    C deg as written, half a unit of each one's last written decimal (the same order), the line."""

    xyzabc: tuple[float, ...]
    half_units: tuple[float, ...]
    line: int


_new_number = tuple.__new__  # a Number without the NamedTuple constructor's Python frame


@dataclass(frozen=True)
class BaseRef:
    """The base frame in effect at a place in a program.

    kind: "number" (BASE_DATA[number]), "literal" (xyzabc given in the program), "fdat" (the
    BASE_NO of FDAT ``fdat``, resolved once every file is read), "unknown" (``reason`` says why).
    tool: the TOOL_DATA number set with it (0: $NULLFRAME, the flange), a ``ToolFrame`` (a
    literal frame), a str: why the tool is not known, None: not set (an FDAT's TOOL_NO for kind
    "fdat", else the cell's tool).
    """

    kind: str
    line: int = 0  # where it was set (0: before the file)
    number: int | None = None
    xyzabc: tuple[float, ...] | None = None
    fdat: str | None = None
    reason: str = ""
    label: str | None = None  # set when the state was carried across a jump target
    tool: int | ToolFrame | str | None = None
    tool_label: str | None = None  # the jump target the tool was carried across (``label``)
    # the state whose base this one keeps, only its tool changed (None: its own base)
    origin: BaseRef | None = field(default=None, compare=False, repr=False)

    def describe(self) -> str:
        if self.kind == "number":
            return f"BASE_DATA[{self.number}]"
        if self.kind == "literal":
            return "$BASE literal"
        if self.kind == "fdat":
            return f"FDAT {self.fdat}"
        return self.reason


@dataclass(slots=True)
class KrlPosition:
    """A position aggregate found in a program (values in mm / deg as written)."""

    path: str | None
    line: int
    column: int
    kind: str  # "decl" | "assign" | "motion"
    type: str  # E6POS, POS, FRAME, AXIS, E6AXIS; "" when not declared
    name: str  # variable as written ("XP1", "lfWorkPos[3]") or the motion keyword ("LIN")
    numbers: dict[str, Number]
    base: BaseRef | None = None  # for motion aggregates: the base in effect there
    reason: str = ""  # why this aggregate is not a placeable Cartesian position by itself
    _key: str | None = field(default=None, repr=False, compare=False)

    @property
    def key(self) -> str:
        """Normalized variable name (upper case, no spaces) used to match motions to it."""
        if self._key is None:
            self._key = normalize_name(self.name)
        return self._key

    @property
    def values(self) -> dict[str, float]:
        return {k: n.value for k, n in self.numbers.items()}

    def _get(self, key: str) -> float | None:
        number = self.numbers.get(key)
        return None if number is None else number.value

    x = property(lambda self: self._get("X"))
    y = property(lambda self: self._get("Y"))
    z = property(lambda self: self._get("Z"))
    a = property(lambda self: self._get("A"))
    b = property(lambda self: self._get("B"))
    c = property(lambda self: self._get("C"))
    s = property(lambda self: self._get("S"))
    t = property(lambda self: self._get("T"))


@dataclass(slots=True)
class KrlUse:
    """A motion that goes to a named position, or to something that is not a literal."""

    path: str | None
    line: int
    column: int
    motion: str
    name: str  # normalized target ("XP1", "LFWORKPOS[3]", "LFWORKPOS[*]"; "" if not a name)
    text: str  # the target as written
    base: BaseRef
    reason: str = ""  # non-empty: the motion's target cannot be a stored position as is


class Fdat(NamedTuple):
    """An FDAT (``DECL FDAT FP1={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE}``) as far as it places a
    position: the base (None with ``reason`` when it is not a BASE_DATA number, e.g. an external
    TCP) and the tool (None when not given, a str: why it is not known)."""

    base_no: int | None
    tool_no: int | str | None
    line: int
    reason: str = ""


class Relative(NamedTuple):
    """A relative motion's aggregate (``LIN_REL {Z -50} #TOOL``): an increment from the position
    the robot is at, in the base frame (``#BASE``, the default) or the tool frame at the start
    (``#TOOL``). ``since`` and ``why``: the line of the last statement before it after which the
    robot's position does not follow from the motions written before (a routine's start, a jump
    target, a branch or loop, a call, a change of $BASE or $TOOL), and what it is."""

    tool: bool  # #TOOL: the increment is in the tool frame at the start
    since: int
    why: str


class Declared(NamedTuple):
    """A variable declaration: its type (upper case) and line."""

    type: str
    line: int


class FrameUse(NamedTuple):
    """A name used as a frame, not as a position (``$TOOL = T1``, ``BASE_DATA[1]:P1``)."""

    line: int
    reason: str


@dataclass
class Routine:
    """A routine (``DEF``/``DEFFCT``) of a file as far as $BASE and $TOOL go: its name (upper
    case), line, whether other modules can call it (``GLOBAL``, or the module's main routine,
    the first of its .src), what in it changes $BASE or $TOOL itself ("" when nothing; the
    first such statement), the routines it calls as statements and the names it calls in
    expressions (functions, built-in ones too), each (name as written, line)."""

    name: str
    line: int
    public: bool
    sets: str = ""
    calls: list[tuple[str, int]] = field(default_factory=list)
    uses: list[tuple[str, int]] = field(default_factory=list)


@dataclass
class KrlScan:
    """Everything read from one file. Positions and uses are kept column by column
    (``table``, ``use_table``, their bases in ``bases``); ``positions`` and ``uses`` give them as
    objects (built on first use: for small programs and tests)."""

    path: str | None
    text: str = ""
    table: PositionTable = field(default=None, repr=False)  # type: ignore[assignment]
    use_table: UseTable = field(default=None, repr=False)  # type: ignore[assignment]
    bases: list[BaseRef] = field(default_factory=list)  # table.base / use_table.base -> BaseRef
    fdats: dict[str, Fdat] = field(default_factory=dict)  # FDAT name (upper case) -> its values
    base_data: dict[int, tuple[tuple[float, ...], int]] = field(default_factory=dict)
    # BASE_DATA[n] = {..} in this file -> (xyzabc, line)
    tool_data: dict[int, tuple[tuple[float, ...] | None, int]] = field(default_factory=dict)
    # TOOL_DATA[n] (or a member of it) set in this file -> (xyzabc, None: not a literal; line)
    assigned: dict[str, int] = field(default_factory=dict)
    # names given a non-literal value at run time -> first line
    frame_uses: dict[str, FrameUse] = field(default_factory=dict)  # normalized name -> first use
    relative: dict[int, Relative] = field(default_factory=dict)  # table row of a _REL aggregate
    routines: list[Routine] = field(default_factory=list)  # in file order
    # every call (name upper case, line, the base in effect there), and the routines a TRIGGER
    # or an INTERRUPT runs (names upper case): they run wherever the robot is
    call_sites: list[tuple[str, int, BaseRef]] = field(default_factory=list)
    async_calls: set[str] = field(default_factory=set)
    _declared: dict[str, Declared] = field(default_factory=dict, repr=False)  # statement reader
    _fast_decls: list[tuple[list, list, np.ndarray]] = field(default_factory=list, repr=False)
    # (names, types, lines) of each block of plain declarations the whole-text scanner read
    _fast_index: dict[str, Declared] = field(default_factory=dict, repr=False)
    _fast_indexed: int = field(default=0, repr=False)
    _positions: list[KrlPosition] | None = field(default=None, repr=False)
    _rows: _Rows | None = field(default=None, repr=False)  # while reading
    _uses: list[KrlUse] | None = field(default=None, repr=False)

    def declared_get(self, key: str) -> Declared | None:
        """The first declaration of variable ``key`` (upper case, no index) read so far."""
        for names, types, lines in self._fast_decls[self._fast_indexed :]:
            index = self._fast_index
            for name, type_name, line in zip(names, types, lines.tolist(), strict=True):
                index.setdefault(name.upper(), Declared(type_name, line))
        self._fast_indexed = len(self._fast_decls)
        slow, fast = self._declared.get(key), self._fast_index.get(key)
        if slow is None or (fast is not None and fast.line < slow.line):
            return fast
        return slow

    @property
    def declared(self) -> dict[str, Declared]:
        """Every declared variable (upper case, no index) -> its first declaration."""
        keys = set(self._declared)
        for names, _, _ in self._fast_decls:
            keys.update(map(str.upper, names))
        return {k: self.declared_get(k) for k in sorted(keys)}

    @property
    def positions(self) -> list[KrlPosition]:
        """The position aggregates as objects, in file order."""
        if self._positions is None:
            t, path, bases = self.table, self.path, self.bases
            self._positions = [
                KrlPosition(
                    path,
                    line,
                    column,
                    KIND_NAMES[kind],
                    t.type[i],
                    t.name[i],
                    parse_aggregate(self.text, agg, 0, path, line)[1],
                    bases[base] if base >= 0 else None,
                    t.reason[i],
                )
                for i, (line, column, kind, agg, base) in enumerate(
                    zip(
                        t.line.tolist(),
                        t.column.tolist(),
                        t.kind.tolist(),
                        t.agg.tolist(),
                        t.base.tolist(),
                        strict=True,
                    )
                )
            ]
        return self._positions

    @property
    def uses(self) -> list[KrlUse]:
        """The motions to a named target as objects, in file order."""
        if self._uses is None:
            u, path, bases = self.use_table, self.path, self.bases
            self._uses = [
                KrlUse(path, line, column, u.motion[i], u.name[i], u.text[i], bases[b], u.reason[i])
                for i, (line, column, b) in enumerate(
                    zip(u.line.tolist(), u.column.tolist(), u.base.tolist(), strict=True)
                )
            ]
        return self._uses


def normalize_name(name: str) -> str:
    """``lfWorkPos[ 3 ]`` -> ``LFWORKPOS[3]``; a non-integer index becomes ``[*]``; a member path
    is kept (``gsCNC1[i].fCNC`` -> ``GSCNC1[*].FCNC``)."""
    if "[" not in name and " " not in name and "\t" not in name:
        return name.upper()
    name = re.sub(r"\s++", "", name).upper()
    head, bracket, rest = name.partition("[")
    if not bracket:
        return head
    index, _, member = rest.partition("]")
    index = index if index.isascii() and index.isdigit() else "*"
    return f"{head}[{index}]{member}"


def wildcard(key: str) -> str:
    """The key a use with a variable index has: ``P[3].F`` -> ``P[*].F`` (the key itself when it
    has no index)."""
    head, bracket, rest = key.partition("[")
    if not bracket:
        return key
    return f"{head}[*]{rest.partition(']')[2]}"


def code_part(line: str, path: str | None, lineno: int) -> str:
    """The line up to its ``;`` comment (a ``;`` inside a "string" does not count)."""
    if '"' not in line:
        cut = line.find(";")
        return line if cut < 0 else line[:cut]
    in_string = False
    for i, ch in enumerate(line):
        if ch == '"':
            in_string = not in_string
        elif ch == ";" and not in_string:
            return line[:i]
    if in_string:
        raise InputError("unterminated string", path, lineno, line.find('"') + 1)
    return line


def match_brace(code: str, start: int, path: str | None, lineno: int) -> int:
    """Index just past the ``}`` matching the ``{`` at ``start``; InputError when unbalanced."""
    close = code.find("}", start)
    if close > 0 and code.find("{", start + 1, close) < 0 and code.find('"', start, close) < 0:
        return close + 1
    depth = 0
    in_string = False
    for i in range(start, len(code)):
        ch = code[i]
        if ch == '"':
            in_string = not in_string
        elif in_string:
            continue
        elif ch == "{":
            depth += 1
        elif ch == "}":
            depth -= 1
            if depth == 0:
                return i + 1
    raise InputError("unbalanced '{' (no closing '}' on this line)", path, lineno, start + 1)


def parse_aggregate(
    code: str, start: int, offset: int, path: str | None, lineno: int
) -> tuple[str, dict[str, Number], str, int]:
    """Read the aggregate ``{...}`` at ``code[start]``.

    Returns (type prefix or "", numbers by key, reason when a component is not a literal, end).
    ``offset`` is the text offset of ``code[0]``.
    """
    end = match_brace(code, start, path, lineno)
    body_start = start + 1
    body = code[body_start : end - 1]
    type_name = ""
    m = _TYPE_PREFIX_RE.match(body)
    if m:
        type_name = m.group(1).upper()
        body_start += m.end()
        body = code[body_start : end - 1]
    numbers: dict[str, Number] = {}
    reason = ""
    if "{" in body or '"' in body or "[" in body:
        items = _split_top(body)  # nested aggregates or strings (NAME[] "text"): item by item
    else:
        items = None
    stop = end - 1
    if items is None:  # the common flat aggregate: one C-level scan, spans by arithmetic
        cursor = body_start + len(body) - len(body.lstrip())  # items start at a word
        for key, gap, number, bits, other, trail in _FLAT_RE.findall(code, cursor, stop):
            key = key.upper()
            vstart = cursor + len(key) + len(gap)
            if key in numbers:
                raise InputError(f"component {key} given twice", path, lineno, vstart + 1)
            if number:
                cursor = vstart + len(number)
                value = float(number)
                if value - value:  # inf - inf is NaN: a literal beyond the float range
                    _out_of_range(key, number, path, lineno, vstart)
                numbers[key] = _new_number(
                    Number, (key, value, offset + vstart, offset + cursor, number)
                )
            elif bits:
                cursor = vstart + len(bits)
                numbers[key] = _bits(key, bits, vstart, offset, path, lineno)
            else:
                cursor = vstart + len(other)
                if key in CARTESIAN_KEYS or key in JOINT_KEYS:
                    reason = reason or f"component {key} is {other.strip()!r}, not a number"
            cursor += len(trail)
        if cursor != stop and code[body_start:stop].strip():
            _refuse_item(code, body_start, stop, path, lineno)
        return type_name, numbers, reason, end
    pos = 0
    for item in items:
        item_start = body_start + pos
        pos += len(item) + 1
        if not item.strip():
            continue
        m = _ITEM_RE.fullmatch(code, item_start, item_start + len(item))
        if m is None:
            key = _nested_item(code, item_start, item_start + len(item), path, lineno)
            if key in numbers:
                raise InputError(f"component {key} given twice", path, lineno, item_start + 1)
            if key in CARTESIAN_KEYS or key in JOINT_KEYS:
                reason = reason or f"component {key} is {item.strip()!r}, not a number"
            continue
        key = m.group(1).upper()
        if key in numbers:
            raise InputError(f"component {key} given twice", path, lineno, m.start(2) + 1)
        if m.group(2) is not None:
            if float(m.group(2)) - float(m.group(2)):
                _out_of_range(key, m.group(2), path, lineno, m.start(2))
            numbers[key] = Number(
                key,
                float(m.group(2)),
                offset + m.start(2),
                offset + m.end(2),
                m.group(2),
            )
        elif m.group(3) is not None:
            numbers[key] = _bits(key, m.group(3), m.start(3), offset, path, lineno)
        elif key in CARTESIAN_KEYS or key in JOINT_KEYS:
            reason = reason or f"component {key} is {m.group(4).strip()!r}, not a number"
    return type_name, numbers, reason, end


def _nested_item(code: str, start: int, stop: int, path: str | None, lineno: int) -> str:
    """The key of the component ``code[start:stop]`` whose value is a "string" or a nested
    aggregate (skipped: not a position of its own); InputError when it is neither."""
    m = _NESTED_ITEM_RE.match(code, start, stop)
    end = m.end() if m else start
    if m and m.group(2) is None:
        end = match_brace(code, m.end(), path, lineno)
    if m is None or end > stop or code[end:stop].strip():
        item = code[start:stop].strip()
        raise InputError(f"cannot read aggregate component {item!r}", path, lineno, start + 1)
    return m.group(1).upper()


def _out_of_range(key: str, number: str, path: str | None, lineno: int, at: int) -> None:
    shown = number if len(number) <= 20 else number[:20] + "..."
    raise InputError(f"component {key} {shown}: number out of range", path, lineno, at + 1)


def _small_int(digits: str) -> int | None:
    """A base or BASE_DATA number as written (ASCII digits), None when it has over 6 digits."""
    return int(digits) if len(digits) <= 6 else None


def _refuse_item(code: str, start: int, stop: int, path: str | None, lineno: int) -> None:
    """InputError at the first part of an aggregate body that is not ``NAME value``."""
    expected = start
    while True:  # anchored matches: a search would restart at every character
        m = _ITEM_RE.match(code, expected, stop)
        if m is None or m.end() == expected:
            break
        expected = m.end()
    col = expected + len(code[expected:stop]) - len(code[expected:stop].lstrip())
    item = code[col:stop].split(",")[0].strip()
    raise InputError(f"cannot read aggregate component {item!r}", path, lineno, col + 1)


def _bits(key: str, value: str, start: int, offset: int, path, lineno: int) -> Number:
    """A Status/Turn literal 'B010' or 'H1F' at ``start`` as a Number (decimals -1)."""
    kind = value[1:2]
    base = 2 if kind in "Bb" else 16 if kind in "Hh" else 0
    try:
        number = int(value[2:-1].replace(" ", ""), base) if base and kind else None
    except ValueError:
        number = None
    if number is None:
        raise InputError(f"bad literal {value} for {key}", path, lineno, start + 1)
    return _new_number(
        Number, (key, float(number), offset + start, offset + start + len(value), value)
    )


def _split_top(body: str) -> list[str]:
    """Split an aggregate body at top-level commas."""
    if "{" not in body and '"' not in body:
        return body.split(",")
    items, depth, in_string, last = [], 0, False, 0
    for i, ch in enumerate(body):
        if ch == '"':
            in_string = not in_string
        elif in_string:
            continue
        elif ch == "{":
            depth += 1
        elif ch == "}":
            depth -= 1
        elif ch == "," and depth == 0:
            items.append(body[last:i])
            last = i + 1
    items.append(body[last:])
    return items


def position_reason(type_name: str, numbers: dict[str, Number]) -> str:
    """Why an aggregate is not a complete Cartesian position ("" when it is one)."""
    if "X" in numbers and "Y" in numbers and "Z" in numbers and "A1" not in numbers:
        if type_name != "AXIS" and type_name != "E6AXIS" and _JOINTS.isdisjoint(numbers):
            return ""
    keys = set(numbers)
    if type_name in ("AXIS", "E6AXIS") or keys & _JOINTS:
        return JOINT_TARGET
    missing = [k for k in "XYZ" if k not in keys]
    if missing:
        given = ",".join(k for k in "XYZABC" if k in keys) or "none"
        return (
            f"{_PARTIAL} (gives {given}; missing {','.join(missing)}): "
            "the correction would need components the program does not give"
        )
    return ""


class _Rows:
    """The rows being read into a scan's tables, the BaseRef index of ``scan.bases`` and the
    base changes to apply to ranges of rows once the file is read."""

    def __init__(self, scan: KrlScan, lines: int) -> None:
        self.scan = scan  # ``lines``: of the text; about one row a line at most, in most programs
        self.positions = position_columns(lines)
        self.uses = use_columns(lines)
        self.external: dict[int, tuple[str, float]] = {}
        self._ids: dict[int, int] = {}
        self.ops: list[tuple] = []  # ("swap", marks, start, changed) | ("label[_tool]", marks)
        self.sites: list[int] = []  # the base id at each call, and the name called and line
        self.site_names: list[tuple[str, int]] = []

    def base_id(self, base: BaseRef | None) -> int:
        if base is None:
            return -1
        found = self._ids.get(id(base))
        if found is None:
            found = self._ids[id(base)] = len(self.scan.bases)
            self.scan.bases.append(base)
        return found

    def mark(self) -> tuple[int, int, int]:
        return self.positions.count, self.uses.count, len(self.sites)

    def site(self, name: str, line: int, base: BaseRef) -> None:
        """A call of ``name`` (upper case) at ``line`` under ``base``."""
        self.sites.append(self.base_id(base))
        self.site_names.append((name, line))

    def add_position(
        self, lineno, column, kind, agg, base, numbers: dict[str, Number], type_name, name, reason
    ) -> int:
        nan = math.nan
        xyz, abc, span, places = [nan, nan, nan], [nan, nan, nan], [-1] * 6, -1
        for i, k in enumerate("XYZ"):
            n = numbers.get(k)
            if n is not None:
                xyz[i], span[2 * i], span[2 * i + 1] = n.value, n.start, n.end
                places = max(places, min(decimals_of(n.literal), 32767))
        for i, k in enumerate("ABC"):
            n = numbers.get(k)
            if n is not None:
                abc[i] = n.value
        index = self.positions.add(
            line=lineno,
            column=column,
            kind=kind,
            agg=agg,
            base=self.base_id(base),
            xyz=xyz,
            abc=abc,
            span=span,
            places=places,
            type=type_name,
            name=name,
            reason=reason,
        )
        for k in _EXTERNAL_AXES:
            n = numbers.get(k)
            if n is not None and n.value != 0.0:
                self.external[index] = (k, n.value)
                break
        return index

    def pop_position(self) -> None:
        self.positions.pop()
        self.external.pop(self.positions.count, None)

    def finish(self) -> None:
        """The tables of ``scan``, with the base changes applied in the order they were made."""
        scan = self.scan
        p = self.positions.finish()
        u = self.uses.finish()
        sites = np.array(self.sites, np.int64)
        for op in self.ops:
            (pa, ua, sa), (pb, ub, sb) = op[1]
            for column, lo, hi in ((p["base"], pa, pb), (u["base"], ua, ub), (sites, sa, sb)):
                part = column[lo:hi]
                if op[0] == "swap":
                    part[part == self.base_id(op[2])] = self.base_id(op[3])
                    continue
                for old in distinct_ints(part[part >= 0]):
                    ref = scan.bases[old]
                    if op[0] == "label_tool":
                        if ref.tool_label and not isinstance(ref.tool, str):  # known so far
                            why = f"after jump target {ref.tool_label}: $TOOL depends on the path"
                            part[part == old] = self.base_id(_tool_changed(ref, why + " taken"))
                    elif ref.label:
                        changed = BaseRef(
                            "unknown",
                            ref.line,
                            reason=f"after jump target {ref.label}: $BASE depends on the path "
                            "taken to it",
                        )
                        part[part == old] = self.base_id(changed)
        scan.table = PositionTable(external=self.external, **p)
        scan.use_table = UseTable(**u)
        bases = scan.bases
        names, ids = self.site_names, sites.tolist()
        scan.call_sites = [(n, at, bases[b]) for (n, at), b in zip(names, ids, strict=True)]
        scan._rows = None


@dataclass(slots=True)
class _Block:
    """An open IF/SWITCH/loop: the base when it opened, at the end of each branch so far, and
    where its rows start."""

    keyword: str
    line: int
    start: BaseRef
    mark: tuple[int, int, int]
    ends: list[BaseRef] = field(default_factory=list)
    has_else: bool = False


class _Flow:
    """$BASE through a routine: conditionals, loops, jump targets and calls; what each routine
    of the file changes of $BASE and $TOOL and which routines it calls (``KrlScan.routines``).

    A call keeps $BASE and $TOOL when ``trust_calls``, when ``calls`` (called name, upper case
    -> why it may change them, "" when it keeps them: ``codegen.krl.routines``) says so, and in
    a KUKA inline form that has set its own FDAT (``_Form``)."""

    def __init__(
        self,
        initial: BaseRef,
        trust_calls: bool,
        rows: _Rows,
        routines: list[Routine],
        calls: dict[str, str] | None = None,
        starts: dict[str, BaseRef] | None = None,
    ) -> None:
        self.initial = initial
        self.trust_calls = trust_calls
        self.calls = calls or {}
        self.starts = starts or {}
        self.rows = rows
        self.routines = routines
        self.routine: Routine | None = None  # the routine being read
        self.folds: list[_Form | None] = []  # the open ;FOLDs, inline forms as _Form
        self.state = initial
        self.blocks: list[_Block] = []
        self.sets_base = False
        self.sets_tool = False
        self.since = rows.mark()  # where the routine's rows start
        self.before_spline: BaseRef | None = None  # the base outside an open spline block
        # the last statement after which the robot's position is not the last motion's target
        self.moved: tuple[int, str] = (0, "the start of the file")

    def start_routine(self, name: str, line: int, public: bool) -> None:
        """``DEF``/``DEFFCT name`` at ``line``; ``public``: GLOBAL (the module's main routine,
        the first of the file, is public whatever it says)."""
        self.finish_routine()
        self.routine = Routine(name.upper(), line, public or not self.routines)
        self.routines.append(self.routine)
        start = self.starts.get(self.routine.name)
        if start is not None:  # the base every call of this local routine has
            self.state = replace(start, line=line)
        elif self.initial.kind == "unknown":
            self.state = BaseRef(
                "unknown",
                line,
                reason=f"start of routine {name} (line {line}): $BASE is inherited from the caller "
                "(--base N states it)",
            )
        else:
            self.state = self.initial
        self.blocks = []
        self.sets_base = self.sets_tool = False
        self.since = self.rows.mark()
        self.before_spline = None
        self.moved = (line, f"the start of routine {name} (line {line}), reached from its caller")

    def finish_routine(self) -> None:
        """A jump target makes the base (the tool) path-dependent when the routine sets the base
        (the tool) anywhere."""
        if self.sets_base:
            self.rows.ops.append(("label", (self.since, self.rows.mark())))
        elif self.sets_tool:
            self.rows.ops.append(("label_tool", (self.since, self.rows.mark())))

    def end_routine(self) -> None:
        self.finish_routine()
        self.routine = None
        self.sets_base = self.sets_tool = False
        self.since = self.rows.mark()

    def changes(self, line: int, what: str) -> None:
        """The routine being read changes $BASE or $TOOL at ``line`` (``what`` says how)."""
        if self.routine is not None and not self.routine.sets:
            self.routine.sets = f"{what} at line {line}"

    def set(self, base: BaseRef) -> None:
        """A new base; the tool set before stays, unless an FDAT sets both."""
        self.state = _with_tool(base, self.state)
        self.sets_base = True
        self.changes(base.line, "$BASE set")
        self.moved = (base.line, f"$BASE set at line {base.line}")

    def breaks(self, line: int, why: str) -> None:
        """After line ``line`` the robot's position does not follow from the motions before."""
        self.moved = (line, why)

    def set_tool(self, tool: int | ToolFrame | str, line: int) -> None:
        """``$TOOL`` set at ``line``: TOOL_DATA number, literal frame, or why it is not known."""
        self.state = replace(
            _tool_changed(self.state, f"{tool} (line {line})" if isinstance(tool, str) else tool),
            tool_label=None,
        )
        self.sets_tool = True
        self.changes(line, "$TOOL set")

    def open_spline(self, base: BaseRef | None) -> None:
        """A SPLINE/PTP_SPLINE block: its segments move in ``base`` (None: the base in effect)."""
        self.before_spline = self.state
        if base is not None:
            self.state = _with_tool(base, self.state)

    def close_spline(self) -> None:
        """ENDSPLINE: the base in effect before the block again."""
        if self.before_spline is not None:
            self.state, self.before_spline = self.before_spline, None

    def label(self, name: str, line: int) -> None:
        self.moved = (line, f"the jump target {name} (line {line})")
        where = f"{name} (line {line})"
        self.state = replace(self.state, label=where, tool_label=where)

    def call(self, name: str, line: int, frames_passed: bool) -> None:
        """A call of routine ``name`` as a statement; ``frames_passed``: $BASE or $TOOL is
        among its arguments (an ``:OUT`` parameter may change it)."""
        self.moved = (line, f"the call {name}() at line {line}, which may move the robot")
        self.rows.site(name.upper(), line, self.state)
        if self.routine is not None:
            self.routine.calls.append((name, line))
        if self.trust_calls:
            return
        why = self.calls.get(name.upper())
        form = self.form()
        if why is None and form is not None and form.applied is self.state:
            why = ""  # a routine not given, in KUKA's own statements of an inline form
        if frames_passed:
            why = "has $BASE or $TOOL among its arguments"
        if why != "":
            self.state = BaseRef(
                "unknown",
                line,
                reason=f"after the call {name}() at line {line}, which {why or 'may change $BASE'}",
            )

    def expression_calls(self, code: str, start: int, line: int) -> None:
        """The names called in the expressions of a statement (``code[start:]``, without its
        own call): recorded for the routine; a function of the given files that changes $BASE
        or $TOOL (``calls``) makes them unknown."""
        for m in _CALLED_RE.finditer(code, start):
            name = m.group(1)
            if name.upper() in _NOT_CALLS:
                continue
            if self.routine is not None:
                self.routine.uses.append((name, line))
            self.rows.site(name.upper(), line, self.state)
            why = self.calls.get(name.upper())
            if why and not self.trust_calls:
                self.state = BaseRef(
                    "unknown", line, reason=f"after the call {name}() at line {line}, which {why}"
                )

    def form(self) -> _Form | None:
        """The innermost open inline form."""
        for fold in reversed(self.folds):
            if fold is not None:
                return fold
        return None

    def open_fold(self, comment: str) -> None:
        """A ``;FOLD`` line (``comment``: from its ``;``)."""
        self.folds.append(_inline_form(comment))

    def close_fold(self) -> None:
        """A ``;ENDFOLD`` line."""
        if self.folds:
            self.folds.pop()

    def activate(self, fdat: str) -> None:
        """``FDAT_ACT = fdat`` has set the state: an inline form's own FDAT, if it is."""
        form = self.form()
        if form is not None and fdat in form.fdats:
            form.own = self.state

    def apply_fdat(self) -> None:
        """``BAS(#PTP_PARAMS|#CP_PARAMS|#FRAMES, ..)``: $BASE and $TOOL from FDAT_ACT."""
        form = self.form()
        if form is not None and form.own is self.state:
            form.applied = self.state

    def open(self, keyword: str, line: int) -> None:
        self.moved = (line, f"{keyword} at line {line}")
        self.blocks.append(_Block(keyword, line, self.state, self.rows.mark()))

    def branch(self, line: int) -> None:
        if self.blocks:
            block = self.blocks[-1]
            self.moved = (line, f"a branch of {block.keyword} at line {block.line}")
            block.ends.append(self.state)
            block.has_else = True
            self.state = block.start

    def close(self, line: int) -> None:
        if not self.blocks:
            return
        block = self.blocks.pop()
        start = block.start
        where = f"{block.keyword} at line {block.line}"
        self.moved = (line, f"the end of {where} (line {line})")
        if block.keyword in ("IF", "SWITCH"):
            ends = block.ends + [self.state]
            if not block.has_else:
                ends.append(start)
            if all(e is start for e in ends):
                self.state = start
            elif all(e is ends[0] for e in ends):
                self.state = ends[0]
            elif all(_same_base(e, ends[0]) for e in ends):
                self.state = _tool_changed(ends[0], f"$TOOL set in one branch of {where} only")
            else:
                self.state = BaseRef(
                    "unknown", line, reason=f"$BASE set in one branch of {where} only"
                )
            return
        if self.state is not start:  # a loop body that changes the base
            changed = BaseRef("unknown", line, reason=f"$BASE changes inside the loop {where}")
            if _same_base(self.state, start):
                changed = _tool_changed(start, f"$TOOL changes inside the loop {where}")
            self.rows.ops.append(("swap", (block.mark, self.rows.mark()), start, changed))
            if block.keyword != "REPEAT":
                self.state = changed


@dataclass(slots=True)
class _Form:
    """An open KUKA inline form of a motion (``;FOLD PTP P1 CONT Vel=100 % PDAT1 Tool[1]
    Base[2];%{PE}..`` up to its ``;ENDFOLD``): the FDAT names that are its own (``FP1`` of the
    point ``P1`` or ``XP1``), the state its ``FDAT_ACT = FP1`` set (``own``) and that state once
    its ``BAS(#PTP_PARAMS, ..)`` or ``BAS(#CP_PARAMS, ..)`` applied it (``applied``).

    KUKA's BAS.SRC: ``#PTP_PARAMS`` and ``#CP_PARAMS`` call ``FRAMES()``, which sets $TOOL
    (``TOOL(FDAT_ACT.TOOL_NO)``) and $BASE (``BASE(FDAT_ACT.BASE_NO)``: BASE_DATA[n]) from
    FDAT_ACT (public copy: github.com/HugoDanielson/ChinaMilling, KRC/R1/System/bas.src). What
    the controller writes after it in the form, before the motion (``SET_CD_PARAMS (0)`` on
    KSS 8.3, as github.com/zserub/TeachPos-Generator reproduces the form; triggers of technology
    packages) sets neither: a call there keeps the state."""

    fdats: frozenset[str]
    own: BaseRef | None = None
    applied: BaseRef | None = None


_FORM_RE = re.compile(r";\s*+FOLD\s++(?:PTP|LIN|CIRC)\s++([^;]*+);?%\{PE\}", re.I)


def _inline_form(line: str) -> _Form | None:
    """The inline form a ``;FOLD`` line opens (None: another fold). Its points are the names
    after the motion word, up to ``Vel=``; ``XP1`` or ``P1`` has the FDAT ``FP1``."""
    m = _FORM_RE.match(line)
    if m is None:
        return None
    fdats = set()
    for word in m.group(1).split():
        if "=" in word or word.upper().startswith("VEL"):
            break
        if _IDENT_RE.fullmatch(word):
            word = word.upper()
            fdats.add("F" + word)
            if word.startswith("X"):
                fdats.add("F" + word[1:])
    return _Form(frozenset(fdats))


def _with_tool(base: BaseRef | None, before: BaseRef) -> BaseRef:
    """``base`` set where ``before`` was in effect (``before`` when None), with the tool set
    before unless it sets one itself (an FDAT sets both)."""
    if base is None:
        return before
    if base.tool is None and base.kind != "fdat" and before.tool is not None:
        return replace(base, tool=before.tool)
    return base


def _tool_changed(state: BaseRef, tool: int | str) -> BaseRef:
    """``state`` with another tool: the same base (``_same_base``)."""
    return replace(state, tool=tool, origin=state.origin or state)


def _same_base(a: BaseRef, b: BaseRef) -> bool:
    """Whether two states have the same base, set at the same place (their tools may differ)."""
    return (a.origin or a) is (b.origin or b)


_OPENERS = {"IF", "SWITCH", "FOR", "WHILE", "LOOP", "REPEAT"}
_CLOSERS = {"ENDIF", "ENDSWITCH", "ENDFOR", "ENDWHILE", "ENDLOOP", "UNTIL"}
_BRANCHES = {"ELSE", "CASE", "DEFAULT"}
_EXTERNAL_AXES = ("E1", "E2", "E3", "E4", "E5", "E6")

_CHUNK = 1 << 20  # characters per whole-text pass (bounds the per-line tuples held at once)
_NOT_IN_TAIL = frozenset("X Y Z A B C".split()) | _JOINTS


def _tail_info(tail: str) -> tuple[bool, tuple[str, float] | None]:
    """Whether the components after X..C of a plain aggregate (``,S 'B010',E1 0``) read as the
    statement reader would read them without a reason, and its first moving external axis."""
    if not tail:
        return True, None
    try:
        _, numbers, reason, _ = parse_aggregate("{" + tail.lstrip(" \t")[1:] + "}", 0, 0, None, 0)
    except InputError:
        return False, None
    if reason or not _NOT_IN_TAIL.isdisjoint(numbers):
        return False, None
    for k in _EXTERNAL_AXES:
        if k in numbers and numbers[k].value != 0.0:
            return True, (k, numbers[k].value)
    return True, None


def scan_krl(
    text: str,
    path: str | os.PathLike[str] | None = None,
    *,
    initial_base: BaseRef | None = None,
    trust_calls: bool = False,
    calls: dict[str, str] | None = None,
    starts: dict[str, BaseRef] | None = None,
) -> KrlScan:
    """Read one KRL file (.src, .dat or $config.dat text).

    ``initial_base``: the base in effect at the start of each routine (default: unknown, it is
    the caller's). ``trust_calls``: assume a call to another routine does not change $BASE.
    ``calls``: what the routines this file calls do to $BASE and $TOOL (name, upper case ->
    "" when they keep both, else why not; ``codegen.krl.routines``); a call of a routine not in
    it may change them. ``starts``: the base at the start of local routines (name, upper case ->
    the base of every call of it, ``codegen.krl.routines``), over ``initial_base``.
    """
    path = None if path is None else os.fspath(path)
    check_text(text, path)
    scan = KrlScan(path, text)
    rows = scan._rows = _Rows(scan, text.count("\n") + 1)
    initial = initial_base or BaseRef("unknown", 0, reason="no $BASE set")
    flow = _Flow(initial, trust_calls, rows, scan.routines, calls, starts)
    if "\n" not in text:  # one line, or lone CR line endings: line by line
        offset = 0
        for lineno, line in enumerate(split_lines(text), start=1):
            _line(line, offset, lineno, scan, flow)
            offset += len(line) + 1
    else:
        start, lineno = 0, 1
        while start <= len(text):
            stop = text.find("\n", min(start + _CHUNK, len(text)))
            stop = len(text) if stop < 0 else stop + 1
            lineno = _chunk(text, start, stop, lineno, scan, flow)
            start = stop
            if stop == len(text):
                break
    flow.finish_routine()
    rows.finish()
    return scan


def _line(line: str, offset: int, lineno: int, scan: KrlScan, flow: _Flow) -> None:
    """One line of any kind (``offset``: of its first character in the text)."""
    code = code_part(line, scan.path, lineno)
    if not code or code.isspace() or code.lstrip()[:1] == "&":
        if len(code) < len(line):  # a comment: ;FOLD and ;ENDFOLD open and close folds
            comment = line[len(code) :]
            word = comment[1:8].upper()
            if word == "ENDFOLD":
                flow.close_fold()
            elif word[:4] == "FOLD" and word[4:5] in (" ", "\t", ""):
                flow.open_fold(comment)
        return
    if code.count("{") != code.count("}"):
        col = code.find("{") if code.count("{") > code.count("}") else code.find("}")
        raise InputError("unbalanced braces", scan.path, lineno, col + 1)
    _statement(code, offset, lineno, scan, flow)


@dataclass
class _Plain:
    """The plain lines among n lines of a chunk: ``plain`` (n,) bool.

    Their aggregates (k rows): ``line`` (k,) index among the n lines, ``decl`` (k,) bool (else a
    motion), ``brace`` and ``column`` (k,) text offset and line column of the ``{``, ``xyz`` and
    ``abc`` (k, 3) (``abc`` NaN when not given), ``span`` (k, 3, 2) text offsets of the X, Y, Z
    literals, ``places`` (k,) the most decimals among them, ``types`` and
    ``names`` (k) str, ``external`` row -> first moving external axis.
    Their motions to a name (m rows): ``use_line``, ``use_column`` (m,), ``motions``, ``texts``."""

    plain: np.ndarray
    line: np.ndarray
    decl: np.ndarray
    brace: np.ndarray
    column: np.ndarray
    xyz: np.ndarray
    abc: np.ndarray
    span: np.ndarray
    places: np.ndarray
    types: list[str]
    names: list[str]
    external: dict[int, tuple[str, float]]
    use_line: np.ndarray
    use_column: np.ndarray
    motions: list[str]
    texts: list[str]


_TAIL_REFUSED = re.compile(r"[{}\";\n]")


def _rigid_plain(
    buf: np.ndarray, text: str, starts: np.ndarray, ends: np.ndarray, count: int
) -> _Plain:
    """The lines ``text[starts[i]:ends[i]]`` (without CR LF) in the rigid layouts
    (``codegen.krl.rigid``) as plain lines, their tails read as the statement reader reads them."""
    r = read_rigid(buf, starts, ends, text)
    external = {}
    if len(r.tail):
        tails, which = distinct(buf, r.tail, text)
        info = [
            (False, None) if _TAIL_REFUSED.search(t) else _tail_info(t) if t else (True, None)
            for t in tails
        ]
        ok = np.array([good for good, _ in info], bool)
        if not ok.all():
            keep = ok[which]
            r, which = r.select(keep), which[keep]
        if any(moving is not None for _, moving in info):
            moving = np.array([m is not None for _, m in info], bool)
            for k in np.flatnonzero(moving[which]).tolist():
                external[k] = info[which[k]][1]
    plain = np.zeros(count, bool)
    plain[r.decl_line] = True
    plain[r.use_line] = True
    return _Plain(
        plain=plain,
        line=r.decl_line,
        decl=np.ones(len(r.decl_line), bool),
        brace=r.brace,
        column=r.brace - starts[r.decl_line] + 1,
        xyz=r.xyz,
        abc=r.abc,
        span=r.span,
        places=r.places,
        types=r.types,
        names=r.names,
        external=external,
        use_line=r.use_line,
        use_column=r.use_at - starts[r.use_line] + 1,
        motions=r.motions,
        texts=r.targets,
    )


def _chunk(text: str, start: int, stop: int, lineno: int, scan: KrlScan, flow: _Flow) -> int:
    """Read the lines of ``text[start:stop]`` (whole lines); the number of the next line.

    Offsets are read in the chunk (``part``) and moved to the text's when the rows are added."""
    part = text[start:stop]
    buf = text_bytes(part)  # None: beyond latin-1
    data = buf[: len(part)] if buf is not None else None
    if data is None:
        data = np.frombuffer(part.encode("latin-1", "replace"), np.uint8)
    newlines = np.flatnonzero(data == 10)
    count = len(newlines) + (stop == len(text))
    if not count:
        return lineno
    starts = np.concatenate(([0], newlines + 1))[:count]
    ends = np.append(newlines, len(part))[:count]
    if buf is None:  # beyond latin-1: every line to the statement reader
        for i in range(count):
            _line(part[starts[i] : ends[i]], start + int(starts[i]), lineno + i, scan, flow)
        return lineno + count
    bare = ends - ((buf[np.maximum(ends - 1, 0)] == 13) & (ends > starts))
    found = _rigid_plain(buf, part, starts, bare, count)
    del buf, data
    plain = found.plain
    aggs, targets = found.line, found.use_line
    moving_rows = np.array(sorted(found.external), dtype=np.int64)
    decl_blocks = scan._fast_decls
    rows = flow.rows

    def flush(lo: int, hi: int) -> None:
        """The plain lines lo..hi-1 of the chunk, under the base in effect."""
        pa, pb = np.searchsorted(aggs, (lo, hi))
        if pb > pa:
            decls = found.decl[pa:pb]
            base = np.where(decls, -1, rows.base_id(flow.state))
            ka, kb = np.searchsorted(moving_rows, (pa, pb))
            for k in moving_rows[ka:kb].tolist():
                rows.external[rows.positions.count + k - pa] = found.external[k]
            names = found.names[pa:pb]
            types = found.types[pa:pb]
            rows.positions.extend(
                pb - pa,
                line=lineno + aggs[pa:pb],
                column=found.column[pa:pb],
                kind=np.where(decls, DECL, MOTION),
                agg=found.brace[pa:pb] + start,
                base=base,
                xyz=found.xyz[pa:pb],
                abc=found.abc[pa:pb],
                span=found.span[pa:pb] + start,
                places=found.places[pa:pb],
                type=types,
                name=names,
                reason=[""] * (pb - pa),
            )
            if decls.all():  # the same lists as the table's
                decl_blocks.append((names, types, lineno + aggs[pa:pb]))
            elif decls.any():
                where = np.flatnonzero(decls).tolist()
                decl_blocks.append(
                    (
                        [names[k] for k in where],
                        [types[k] for k in where],
                        lineno + aggs[pa:pb][decls],
                    )
                )
        ua, ub = np.searchsorted(targets, (lo, hi))
        if ub > ua:
            texts = found.texts[ua:ub]
            rows.uses.extend(
                ub - ua,
                line=lineno + targets[ua:ub],
                column=found.use_column[ua:ub],
                base=np.full(ub - ua, rows.base_id(flow.state)),
                motion=found.motions[ua:ub],
                name=_upper(texts),
                text=texts,
                reason=[""] * (ub - ua),
            )

    last = 0
    for i in np.flatnonzero(~plain).tolist():
        if i > last:
            flush(last, i)
        _line(part[starts[i] : ends[i]], start + int(starts[i]), lineno + i, scan, flow)
        last = i + 1
    if count > last:
        flush(last, count)
    return lineno + count


def _upper(names: list[str]) -> list[str]:
    """``normalize_name`` of plain names: upper case, the name itself when it is upper case
    already (one str, not two)."""
    joined = "\n".join(names)
    if joined.upper() == joined:
        return names
    return [u if u != t else t for u, t in zip(map(str.upper, names), names, strict=True)]


def parse_krl(text: str, path: str | os.PathLike[str] | None = None) -> list[KrlPosition]:
    """Every position aggregate of a KRL file, in file order (see ``scan_krl`` for the rest)."""
    return scan_krl(text, path).positions


def _statement(code: str, off: int, lineno: int, scan: KrlScan, flow: _Flow) -> None:
    pos = 0
    label = _LABEL_RE.match(code)
    if label and label.group(1).upper() not in _NOT_CALLS:
        flow.label(label.group(1), lineno)
        pos = label.end()
        if pos >= len(code.rstrip()):
            return
    word_m = _WORD_RE.match(code, pos)
    if word_m is None:
        return
    word = word_m.group(1).upper()
    rest_at = word_m.end()

    if word in ("TRIGGER", "INTERRUPT", "GLOBAL"):
        run = _DO_RE.search(code, rest_at)
        if run is not None:
            scan.async_calls.add(run.group(1).upper())
    if word in ("DEF", "DEFFCT", "GLOBAL") and not _GLOBAL_DECL_RE.match(code, pos):
        routine = _ROUTINE_RE.match(code, pos)
        if routine:
            flow.start_routine(routine.group(2), lineno, word == "GLOBAL")
        return
    if word in ("END", "ENDFCT", "DEFDAT", "ENDDAT"):
        flow.end_routine()
        return
    if "(" in code and word not in _NO_EXPRESSION_CALLS:
        call = _CALL_RE.match(code, pos) if word not in _NOT_CALLS else None
        flow.expression_calls(code, call.end() if call else rest_at, lineno)
    if word in _OPENERS:
        flow.open(word, lineno)
        return
    if word in _BRANCHES:
        flow.branch(lineno)
        return
    if word in _CLOSERS:
        flow.close(lineno)
        return
    if word in MOTIONS:
        _motion(code, rest_at, word, off, lineno, scan, flow)
        return
    if word in ("SPLINE", "PTP_SPLINE"):
        base = _spline_base(code, word, lineno)
        flow.open_spline(base)
        own = _with_tool_value(code, lineno, flow.state) if "$" in code else None
        if own is not None:  # the block's segments move that tool (until ENDSPLINE)
            flow.state = _tool_changed(flow.state, own)
        if base is not None or own is not None:
            flow.changes(lineno, f"{word} WITH $BASE or $TOOL")
        return
    if word == "ENDSPLINE":
        flow.close_spline()
        return
    if (
        word == "DECL"
        or (word == "GLOBAL" and _GLOBAL_DECL_RE.match(code, pos))
        or (word in POSITION_TYPES or word == "FDAT")
        and _DECL_RE.match(code, pos)
    ):
        _decl(code, pos, off, lineno, scan)
        return
    if word == "BAS":
        _bas(code, pos, lineno, flow)
        return
    assign = _ASSIGN_RE.match(code, pos)
    if assign:
        _assignment(code, assign, off, lineno, scan, flow)
        return
    call = _CALL_RE.match(code, pos)
    if call and word not in _NOT_CALLS:
        args = code[call.end() :].upper()
        flow.call(call.group(1), lineno, "$BASE" in args or "$TOOL" in args)
    elif word not in _NOT_CALLS and _DECL_RE.match(code, pos):
        _declare(code, pos, lineno, scan)  # a local declaration: "INT i", "sCNC1 gs[4]"


# The BAS commands that set neither $BASE nor $TOOL (KUKA's BAS.SRC: velocities, accelerations,
# approximation, outputs, the axis group; public copy: github.com/HugoDanielson/ChinaMilling,
# KRC/R1/System/bas.src). #INITMOV turns the base and tool corrections off and, on a robot
# ($KINCLASS not #NONE), sets $BASE = $WORLD (BASE(0)) and $TOOL = TOOL_DATA[1]; #FRAMES,
# #PTP_PARAMS and #CP_PARAMS set both from FDAT_ACT; #BASE, #TOOL, #EX_BASE set them.
_BAS_KEEPS = frozenset(
    "ACC_CP ACC_GLUE ACC_PTP VEL_CP VEL_PTP CP_DAT PTP_DAT OUT_SYNC OUT_ASYNC GROUP".split()
)
_BAS_FDAT = frozenset(("FRAMES", "PTP_PARAMS", "CP_PARAMS"))  # $BASE, $TOOL from FDAT_ACT


def _bas(code: str, pos: int, lineno: int, flow: _Flow) -> None:
    """``BAS(#BASE, n)`` sets BASE_DATA[n], ``BAS(#TOOL, n)`` TOOL_DATA[n], ``BAS(#INITMOV, ..)``
    base 0 ($WORLD) and TOOL_DATA[1]; other BAS commands leave them in the flow (``FDAT_ACT = F``
    sets the FDAT's), but a routine that runs one of them other than ``_BAS_KEEPS`` changes
    them."""
    m = _BAS_RE.match(code, pos)
    command = m.group(1).upper() if m is not None else ""
    if command not in _BAS_KEEPS:
        flow.changes(lineno, f"BAS(#{command}, ..)" if command else "BAS() of a variable command")
    if command in _BAS_FDAT:
        flow.apply_fdat()
    if command == "INITMOV":  # BAS.SRC INITMOV: BASE(0) with the base corrections off, tool 1
        flow.set(BaseRef("number", lineno, number=0, tool=1))
        return
    if m is not None and m.group(1).upper() == "TOOL":
        flow.breaks(lineno, f"the tool set at line {lineno}")
    if m is None or m.group(1).upper() not in ("BASE", "TOOL"):
        return
    rest = code[m.end() :].strip()
    if not rest.endswith(")"):
        return
    inner = rest[:-1].strip()
    if inner and not inner.startswith(","):
        return
    arg = inner[1:].strip()
    n = _INT_RE.match(arg)
    number = _small_int(n.group(1)) if n else None
    if m.group(1).upper() == "TOOL":
        flow.set_tool(number if number is not None else f"BAS(#TOOL, {arg}): not a number", lineno)
    elif number is not None:
        flow.set(BaseRef("number", lineno, number=number))
    else:
        flow.set(BaseRef("unknown", lineno, reason=f"BAS(#BASE, {arg}): not a number"))


def _declare(code: str, pos: int, lineno: int, scan: KrlScan) -> tuple[re.Match, str] | None:
    """Record every name a declaration declares (``E6POS a, b[4]``); (its match, type)."""
    m = _DECL_RE.match(code, pos)
    if m is None:
        return None
    type_name = m.group(2).upper()
    names = [m.group(3)]
    if "=" not in code[m.end() :]:  # no value: more names may follow, "E6POS a, b"
        for part in _split_top(code[m.end() :].lstrip(",")):
            more = _IDENT_RE.match(part.strip())
            if more:
                names.append(more.group())
    for name in names:
        scan._declared.setdefault(name.upper(), Declared(type_name, lineno))
    return m, type_name


def _decl(code: str, pos: int, off: int, lineno: int, scan: KrlScan) -> None:
    found = _declare(code, pos, lineno, scan)
    if found is None:
        return
    m, type_name = found
    name = m.group(3)
    rest = code[m.end() :]
    if not rest.startswith("="):
        return
    value_at = m.end() + 1
    while value_at < len(code) and code[value_at] in " \t":
        value_at += 1
    if type_name == "FDAT":
        scan.fdats[name.upper()] = _fdat_values(code, value_at, scan.path, lineno)
        return
    if code[value_at : value_at + 1] != "{":
        return
    full = name + (m.group(4) or "")
    if type_name not in POSITION_TYPES:
        _struc_positions(code, value_at, off, lineno, scan, DECL, full)
        return
    row, _, reason, _ = _add_position(
        code, value_at, off, lineno, scan, DECL, type_name, full, None
    )
    if m.group(1) and not reason:
        reason = f"{full} is declared CONST: a constant, not a taught position"
        scan._rows.positions.set(row, "reason", reason)


def _fdat_values(code: str, at: int, path: str | None, lineno: int) -> Fdat:
    """The FDAT aggregate at ``code[at]``: BASE_NO (unless IPO_FRAME is not #BASE), TOOL_NO."""
    if code[at : at + 1] != "{":
        return Fdat(None, None, lineno, "FDAT is not a literal")
    body = code[at + 1 : match_brace(code, at, path, lineno) - 1]
    fields = {}
    for item in _split_top(body):
        parts = item.split(None, 1)
        if len(parts) == 2:
            fields[parts[0].upper().rstrip(":")] = parts[1].strip()
    tool = fields.get("TOOL_NO", "")
    tool_no: int | str | None = None
    if tool.isascii() and tool.isdigit() and len(tool) <= 3:
        tool_no = int(tool)
    elif tool:
        tool_no = f"FDAT TOOL_NO {tool[:40]} (line {lineno}): not a number"
    ipo = fields.get("IPO_FRAME", "#BASE").replace(" ", "").upper()
    if ipo != "#BASE":
        return Fdat(
            None, tool_no, lineno, f"IPO_FRAME {ipo}: a fixed tool (external TCP), not a base frame"
        )
    base_no = fields.get("BASE_NO")
    if base_no is None or not (base_no.isascii() and base_no.isdigit() and len(base_no) <= 3):
        return Fdat(None, tool_no, lineno, f"FDAT BASE_NO is {base_no!r}, not a number")
    return Fdat(int(base_no), tool_no, lineno)


def _add_position(
    code: str,
    at: int,
    off: int,
    lineno: int,
    scan: KrlScan,
    kind: int,
    type_name: str,
    name: str,
    base: BaseRef | None,
) -> tuple[int, dict[str, Number], str, int]:
    """Add the aggregate at ``code[at]`` as a position: (its row, its numbers, reason, end)."""
    prefix, numbers, reason, end = parse_aggregate(code, at, off, scan.path, lineno)
    type_name = type_name or prefix
    reason = reason or position_reason(type_name, numbers)
    row = scan._rows.add_position(
        lineno, at + 1, kind, off + at, base, numbers, type_name, name, reason
    )
    return row, numbers, reason, end


_MAX_NESTING = 8


def _struc_positions(
    code: str, at: int, off: int, lineno: int, scan: KrlScan, kind: int, name: str, depth: int = 0
) -> None:
    """The position members of a user STRUC value ``{fCNC {X ..}, grFeedrate 95}`` at
    ``code[at]``, named ``name.member`` (``gsCNC1[3].fCnC``); other members are not positions."""
    if depth > _MAX_NESTING:
        raise InputError(f"aggregates nested more than {_MAX_NESTING} deep", scan.path, lineno)
    end = match_brace(code, at, scan.path, lineno)
    body_start = at + 1
    prefix = _TYPE_PREFIX_RE.match(code, body_start, end - 1)
    if prefix:
        body_start = prefix.end()
    item_start = body_start
    for item in _split_top(code[body_start : end - 1]):
        start, item_start = item_start, item_start + len(item) + 1
        member = _IDENT_RE.match(item, len(item) - len(item.lstrip()))
        if member is None:
            continue
        value = member.end() + len(item[member.end() :]) - len(item[member.end() :].lstrip())
        if item[value : value + 1] != "{":
            continue
        value_at = start + value
        full = f"{name}.{member.group()}"
        inner_end = match_brace(code, value_at, scan.path, lineno)
        if "{" in code[value_at + 1 : inner_end]:
            _struc_positions(code, value_at, off, lineno, scan, kind, full, depth + 1)
            continue
        _, numbers, _, _ = _add_position(code, value_at, off, lineno, scan, kind, "", full, None)
        if not set(numbers) & (CARTESIAN_KEYS | JOINT_KEYS):
            scan._rows.pop_position()  # an aggregate of some other structure type


def _colon_operands(text: str) -> list[str]:
    """The names among the operands of a top-level ``:`` expression (``BASE_DATA[1]:P1``)."""
    parts, depth, in_string, last = [], 0, False, 0
    for i, ch in enumerate(text):
        if ch == '"':
            in_string = not in_string
        elif in_string:
            continue
        elif ch in "{[(":
            depth += 1
        elif ch in "}])":
            depth -= 1
        elif ch == ":" and depth == 0:
            parts.append(text[last:i])
            last = i + 1
    if not parts:
        return []
    parts.append(text[last:])
    names = []
    for part in parts:
        m = _TARGET_NAME_RE.fullmatch(part.strip())
        if m:
            names.append(normalize_name(part.strip()))
    return names


def _frame_use(scan: KrlScan, name: str, lineno: int, reason: str) -> None:
    scan.frame_uses.setdefault(name, FrameUse(lineno, reason))


_FRAME_TARGETS = ("$TOOL", "$BASE", "$LOAD", "TOOL_DATA", "BASE_DATA", "LOAD_DATA", "$NULLFRAME")


def _assignment(
    code: str,
    m: re.Match,
    off: int,
    lineno: int,
    scan: KrlScan,
    flow: _Flow,
) -> None:
    target = m.group(1).upper()
    index = m.group(2) or ""
    member = re.sub(r"\s++", "", m.group(3) or "").upper()
    value_at = m.end()
    value = code[value_at:].strip()
    if ":" in value:
        for name in _colon_operands(value):
            _frame_use(
                scan,
                name,
                lineno,
                f"an operand of ':' at line {lineno} ({value}): a frame or an offset, not a "
                "position by itself",
            )
    if target in _FRAME_TARGETS and _TARGET_NAME_RE.fullmatch(value):
        _frame_use(
            scan,
            normalize_name(value),
            lineno,
            f"assigned to {m.group(1)}{index} at line {lineno}: a frame, not a drilling position",
        )
    if target == "$TOOL":
        flow.breaks(lineno, f"the tool set at line {lineno}")
    if target == "$BASE" and not member:
        flow.set(_base_value(code, value_at, off, lineno, scan))
        return
    if target == "$TOOL":
        flow.set_tool(_tool_value(code, value_at, off, lineno, scan, member), lineno)
        return
    if target == "$BASE" or (target == "FDAT_ACT" and member):
        flow.set(BaseRef("unknown", lineno, reason=f"{code.strip()}: changes part of the base"))
        return
    if target == "FDAT_ACT":
        if value.startswith("{"):
            fdat = _fdat_values(code, value_at, scan.path, lineno)
            flow.set(
                BaseRef("number", lineno, number=fdat.base_no, tool=fdat.tool_no)
                if fdat.base_no is not None
                else BaseRef("unknown", lineno, reason=fdat.reason)
            )
        elif _IDENT_RE.fullmatch(value):
            flow.set(BaseRef("fdat", lineno, fdat=value.upper()))
            flow.activate(value.upper())
        else:
            flow.set(BaseRef("unknown", lineno, reason=f"FDAT_ACT = {value}: not a name"))
        return
    if target == "BASE_DATA" and not member:
        n = _INDEX_RE.fullmatch(index)
        number = _small_int(n.group(1)) if n else None
        if number is not None and value.startswith("{") and ":" not in value.replace("FRAME:", ""):
            prefix, numbers, reason, _ = parse_aggregate(code, value_at, off, scan.path, lineno)
            if not reason and all(k in numbers for k in "XYZABC"):
                xyzabc = tuple(numbers[k].value for k in "XYZABC")
                scan.base_data[number] = (xyzabc, lineno)
        return
    if target == "TOOL_DATA":
        n = _INDEX_RE.fullmatch(index)
        number = _small_int(n.group(1)) if n else None
        if number is not None:
            xyzabc = None
            if not member and value.startswith("{") and ":" not in value.replace("FRAME:", ""):
                _, numbers, reason, _ = parse_aggregate(code, value_at, off, scan.path, lineno)
                if not reason and all(k in numbers for k in "XYZABC"):
                    xyzabc = tuple(numbers[k].value for k in "XYZABC")
            scan.tool_data[number] = (xyzabc, lineno)
        return
    if target in _FRAME_TARGETS:
        return
    name = m.group(1) + index
    if not member and code[value_at : value_at + 1] == "{":
        end = match_brace(code, value_at, scan.path, lineno)
        if not code[end:].strip():
            declared = scan.declared_get(target)
            type_name = declared.type if declared else ""
            nested = "{" in code[value_at + 1 : end - 1]
            if nested or type_name and type_name not in POSITION_TYPES:
                _struc_positions(code, value_at, off, lineno, scan, ASSIGN, name)
                return
            _, numbers, _, _ = _add_position(
                code, value_at, off, lineno, scan, ASSIGN, type_name, name, None
            )
            if not numbers or not set(numbers) & (CARTESIAN_KEYS | JOINT_KEYS):
                scan._rows.pop_position()  # an aggregate of some other structure type
            return
    # a member assigned changes the element (``fp[2].Y = 25``: fp[2], not fp[1]); a variable
    # index is ``[*]`` already, which stands for every element
    scan.assigned.setdefault(normalize_name(name), lineno)


def _base_value(code: str, at: int, off: int, lineno: int, scan: KrlScan) -> BaseRef:
    value = code[at:].strip()
    upper = value.upper()
    if value.startswith("{"):
        end = match_brace(code, at, scan.path, lineno)
        if code[end:].strip():
            return BaseRef("unknown", lineno, reason=f"$BASE = {value}: frame arithmetic")
        _, numbers, reason, _ = parse_aggregate(code, at, off, scan.path, lineno)
        if reason or not all(k in numbers for k in "XYZABC"):
            return BaseRef("unknown", lineno, reason="$BASE literal without all of X,Y,Z,A,B,C")
        return BaseRef("literal", lineno, xyzabc=tuple(numbers[k].value for k in "XYZABC"))
    if ":" in value:
        return BaseRef("unknown", lineno, reason=f"$BASE = {value}: frame arithmetic ':'")
    if upper.startswith("EK"):
        return BaseRef("unknown", lineno, reason=f"$BASE = {value}: external kinematics EK()")
    if upper == "$NULLFRAME":
        return BaseRef("literal", lineno, xyzabc=(0.0,) * 6)
    n = _BASE_DATA_RE.match(value)
    if n:
        return _base_data_ref(n.group(1), lineno, "$BASE = ")
    return BaseRef("unknown", lineno, reason=f"$BASE = {value}: set from a variable")


def _tool_value(
    code: str, at: int, off: int, lineno: int, scan: KrlScan, member: str
) -> int | ToolFrame | str:
    """The tool ``$TOOL[.member] = value`` (the value at ``code[at:]``) sets: a TOOL_DATA number
    (0: $NULLFRAME), a literal frame, or why it is not known."""
    value = code[at:].strip()
    if member:
        return f"$TOOL{member} = {value}: changes part of the tool"
    if value.startswith("{"):
        end = match_brace(code, at, scan.path, lineno)
        if code[end:].strip():
            return f"$TOOL = {value[:40]}: frame arithmetic"
        _, numbers, reason, _ = parse_aggregate(code, at, off, scan.path, lineno)
        if reason or not all(k in numbers for k in "XYZABC"):
            return "$TOOL literal without all of X,Y,Z,A,B,C"
        written = [numbers[k] for k in "XYZABC"]
        half = tuple(0.5 * 10.0 ** -max(n.decimals, 0) for n in written)
        return ToolFrame(tuple(n.value for n in written), half, lineno)
    number = _tool_number(value)
    if number is not None:
        return number
    return f"$TOOL = {value[:40]}: not a TOOL_DATA number"


def _tool_number(value: str) -> int | None:
    """The TOOL_DATA number a ``$TOOL`` value names (0: ``$NULLFRAME``, the flange); None when
    it is not ``TOOL_DATA[n]`` or ``$NULLFRAME``."""
    if value.upper() == "$NULLFRAME":
        return 0
    n = _TOOL_DATA_RE.match(value)
    return _small_int(n.group(1)) if n else None


def _base_data_ref(digits: str, lineno: int, what: str) -> BaseRef:
    number = _small_int(digits)
    if number is None:
        return BaseRef(
            "unknown", lineno, reason=f"{what}BASE_DATA[{digits[:8]}...]: not a BASE_DATA number"
        )
    return BaseRef("number", lineno, number=number)


_SBASE_RE = re.compile(r"SBASE\s*+\(\s*+([A-Za-z_]\w*+)\s*+\.\s*+BASE_NO\s*+\)$", re.I)


def _with_base(code: str, lineno: int) -> BaseRef | None:
    """The base a spline motion sets for itself: ``WITH ..., $BASE = SBASE(FP1.BASE_NO)`` (the
    KSS 8 inline form) or ``$BASE = BASE_DATA[n]``; None when the WITH part does not set it."""
    with_m = _WITH_RE.search(code)
    if with_m is None:
        return None
    base_m = _BASE_SET_RE.search(code, with_m.end())
    if base_m is None:
        return None
    stop = _NEXT_SYSVAR_RE.search(code, base_m.end())
    value = code[base_m.end() : stop.start() if stop else len(code)].strip()
    sbase = _SBASE_RE.match(value)
    if sbase:
        return BaseRef("fdat", lineno, fdat=sbase.group(1).upper())
    n = _BASE_DATA_RE.match(value)
    if n:
        return _base_data_ref(n.group(1), lineno, "WITH $BASE = ")
    return BaseRef("unknown", lineno, reason=f"WITH $BASE = {value}: not a BASE_DATA number")


_TOOL_SET_RE = re.compile(r"\$TOOL\s*+=\s*+", re.I)
_STOOL_RE = re.compile(r"STOOL2\s*+\(\s*+([A-Za-z_]\w*+)\s*+\)$", re.I)
_APPROX_TAIL_RE = re.compile(r"\s++C_\w++$", re.I)


def _with_tool_value(code: str, lineno: int, base: BaseRef) -> int | str | None:
    """The tool a motion (a spline block) sets for itself with ``WITH $TOOL = ...``, ``base``
    the base it moves in: a TOOL_DATA number (0: $NULLFRAME); None when the WITH part does not
    set it, or sets ``STOOL2(F)`` of the FDAT F whose base it takes (F's TOOL_NO); else why it
    is not known."""
    with_m = _WITH_RE.search(code)
    tool_m = _TOOL_SET_RE.search(code, with_m.end()) if with_m else None
    if tool_m is None:
        return None
    stop = _NEXT_SYSVAR_RE.search(code, tool_m.end())
    value = code[tool_m.end() : stop.start() if stop else len(code)].strip()
    value = _APPROX_TAIL_RE.sub("", value)
    number = _tool_number(value)
    if number is not None:
        return number
    stool = _STOOL_RE.match(value)
    if stool and base.kind == "fdat" and base.fdat == stool.group(1).upper():
        return None
    return f"WITH $TOOL = {value[:40]} (line {lineno}): not a TOOL_DATA number"


def _spline_base(code: str, word: str, lineno: int) -> BaseRef | None:
    """The base a SPLINE/PTP_SPLINE block sets for its segments (``SPLINE WITH $BASE =
    BASE_DATA[2]``, ``$BASE = SBASE(FS1.BASE_NO)``); None when the block does not set it."""
    base = _with_base(code, lineno) if "$" in code else None
    if base is None or base.kind != "unknown":
        return base
    return BaseRef("unknown", lineno, reason=f"{word} block at line {lineno}: {base.reason}")


def _operands(code: str, at: int, path: str | None, lineno: int) -> tuple[list, int]:
    """The operands of one motion target at ``code[at]`` joined by ``:``: ("agg"|"name"|"other",
    start, end) each, and where the target ends (before C_DIS/C_VEL/WITH...)."""
    operands: list[tuple[str, int, int]] = []
    while True:
        if code[at] == "{":
            end = match_brace(code, at, path, lineno)
            operands.append(("agg", at, end))
        else:
            m = _TARGET_NAME_RE.match(code, at)
            if m is None or m.end() == at or code[m.end() : m.end() + 1] == "(":
                clause = _APPROXIMATION_RE.search(code, at)
                end = clause.start() if clause else len(code)
                operands.append(("other", at, end))
            else:
                end = m.end()
                operands.append(("name", at, end))
        at = end
        while at < len(code) and code[at] in " \t":
            at += 1
        if code[at : at + 1] == ":":
            at += 1
            while at < len(code) and code[at] in " \t":
                at += 1
            if at < len(code):
                continue
        return operands, at


def _motion(
    code: str,
    at: int,
    word: str,
    off: int,
    lineno: int,
    scan: KrlScan,
    flow: _Flow,
) -> None:
    count = 2 if word in ("CIRC", "SCIRC", "CIRC_REL", "SCIRC_REL") else 1
    relative = word.endswith("_REL")
    tool = relative and _TOOL_FRAME_RE.search(code) is not None
    own_tool = relative and "$" in code and _WITH_TOOL_RE.search(code) is not None
    base = flow.state
    if "$" in code and "WITH" in code.upper():
        with_base = _with_base(code, lineno)
        base = _with_tool(with_base, base)
        own = _with_tool_value(code, lineno, base)
        if own is not None:
            base = _tool_changed(base, own)
        if with_base is not None or own is not None:
            flow.changes(lineno, f"{word} WITH $BASE or $TOOL")
    for _ in range(count):
        while at < len(code) and code[at] in " \t,":
            at += 1
        if at >= len(code):
            return
        start = at
        operands, at = _operands(code, at, scan.path, lineno)
        target_text = code[start:at].strip()
        arith = len(operands) > 1
        for k, (kind, s, e) in enumerate(operands):
            if kind == "agg":
                if relative:
                    why = f"{RELATIVE} {word}: an offset, not a position"
                elif arith and k < len(operands) - 1:
                    why = f"{FRAME_OPERAND} in {target_text}: an offset, not the target"
                elif arith:
                    why = f"frame arithmetic ':' in {target_text}: computed at run time"
                else:
                    why = ""
                row, _, own, _ = _add_position(code, s, off, lineno, scan, MOTION, "", word, base)
                if why and own != JOINT_TARGET:  # a joint target stays one, relative or not
                    scan._rows.positions.set(row, "reason", why)
                    if relative and not arith and (not own or own.startswith(_PARTIAL)):
                        since, why = flow.moved[0], f"{flow.moved[1]} comes before it"
                        if own_tool:
                            since, why = lineno, f"it sets its own tool (WITH $TOOL, line {lineno})"
                        scan.relative[row] = Relative(tool, since, why)
            else:
                operand = code[s:e].strip()
                name = normalize_name(operand) if kind == "name" else ""
                if kind == "name" and name.startswith("$"):
                    why = f"system variable {operand}: the position is only known at run time"
                elif kind != "name":
                    why = f"target {operand!r} is an expression"
                elif relative:
                    why = f"{RELATIVE} {word}: an offset, not a position"
                elif arith:
                    why = f"frame arithmetic ':' in {target_text}: computed at run time"
                    if k < len(operands) - 1:
                        why = f"{FRAME_OPERAND} in {target_text}: an offset, not the target"
                    _frame_use(
                        scan,
                        name,
                        lineno,
                        f"an operand of ':' at line {lineno} ({target_text}): a frame or an "
                        "offset, not a position by itself",
                    )
                else:
                    why = ""
                flow.rows.uses.add(
                    line=lineno,
                    column=s + 1,
                    base=flow.rows.base_id(base),
                    motion=word,
                    name=name,
                    text=operand,
                    reason=why,
                )
