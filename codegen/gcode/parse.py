"""RS274NGC reader: every move of a G-code program with its absolute target and the exact span of
each number, for pre-flight correction.

Follows the modal state a CAM post relies on: motion mode (G0/G1/G2/G3, canned cycles G73/G81-G89
with G98/G99 (G98 back to the initial level, the Z where the run of cycle blocks began), sticky Z
and R and, under G91, X and Y from the tool, R from the initial level, Z from R and L repeats, as
LinuxCNC reads them; in G18 and G19 the cycle's axis is Y and X), arcs (their centre, plane and
turns, ``codegen.gcode.arc``; G90.1/G91.1), G90/G91 (incremental targets are made absolute),
G20/G21 (targets in mm; ``scale`` converts back), G17/G18/G19, N-numbers, ``( )`` and ``;``
comments, words in any order and case, with or without spaces, parameter assignments (``#1 = 5``,
``#<_z> = 0.4``) and words written as parameters or expressions (``X#1``, ``X[#1*2]``,
``x sin[30]``), evaluated where decidable before run time (``expressions``; a Word then holds
the value and the expression's text and span), LinuxCNC's polar words ``@`` (radius) and ``^``
(angle) in the XY plane (``polar_xy``; ``GcodeMoves.polar`` keeps their words), and ``%`` tape
marks (``N890 %`` too). G54 is the program frame (the power-on default). Reported instead of
guessed: anything that moves the program frame in a way the cell does not describe (G55-G59.3
until G54, G92/G52/G92.3 on X, Y or Z until G92.1/G92.2 (on A/B/C/U/V/W or E only they do not
move X, Y, Z), G10, an assigned work offset parameter, G68/G51 until G69/G50, cutter
compensation until G40), a motion whose geometry is not known (G5 splines, G33 threading, G38
probing, any other G-code), a word whose parameter or expression is not decidable before run
time (with the reason; that axis is unknown until written again), a polar move with one word
(the other is where the tool is), a position left unknown (G28/G30, G53) and O-word control
flow.

The tool each move is programmed with (``GcodeMoves.tool_spans``), as LinuxCNC applies it: ``T n``
selects, ``M6`` loads the selected tool (``M61 Q n`` sets the loaded one), ``G43`` applies the
length offset of the loaded tool and ``G43 H n`` that of tool n, so the programmed point is that
tool's tip; ``G49`` (or ``G43 H0``) cancels the offset (-1: the programmed point is the cell's
tool). Left unknown, with the reason: ``G43.1``/``G43.2``, a G43 with no tool loaded in the
program, a tool loaded while the offset of another one stays in effect (LinuxCNC keeps the old
offset until the next G43), T or H from an expression.

Every pattern is linear in its input (possessive quantifiers; comments and expressions are
scanned by hand), so a hostile line cannot make the reader backtrack.
"""

from __future__ import annotations

import math
import os
import re
import string
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from accugrid.codegen.gcode.arc import Arc, arc_of
from accugrid.codegen.gcode.expressions import Parameters, Undecided
from accugrid.codegen.gcode.numbers import NUMBER_BYTES, literal_values
from accugrid.codegen.program_text import check_text, decimals_of, split_lines
from accugrid.infra.errors import InputError

__all__ = [
    "AXES",
    "CYCLES",
    "CYCLE_AXIS",
    "RESETS",
    "INCH_MM",
    "POLAR",
    "ROTARY",
    "WORD_LETTERS",
    "GcodeMove",
    "GcodeMoves",
    "Word",
    "gcode_moves",
    "modal_fill",
    "parse_gcode",
    "polar_xy",
]

_NUMBER = r"[-+]?+(?:\d++(?:\.\d*+)?+|\.\d++)"
_NUMBER_RE = re.compile(_NUMBER)
# The whole-text scanner's line match, once per shape of line (``_Shapes``). A plain line is
# ``[N..] [G98|G99] [G0|G1|G73|G81..G89] X.. Y.. Z.. [R..] [F..] [(comment)]`` where any one or two
# of X, Y, Z may be left out, with single spaces between the position words. Its G-codes and first
# letter are one group (never empty for a plain line); any other line matches the last branch
# with the group empty. Where the numbers are is found from the bytes (``_number_spans``): before
# the comment the letters X, Y, Z, R appear only as words, and each number ends at the first byte
# that is not in one.
_ROW_RE = re.compile(
    r"^(?:[ \t]*+(?:N\d++[ \t]++)?+((?:G9[89][ \t]++)?+(?:G(?:0?+[01]|0|8[1-9]|73)[ \t]++)?+[XYZ])"
    r"(?:(?<=X)" + _NUMBER + "(?: Y" + _NUMBER + ")?+(?: Z" + _NUMBER + ")?+"
    r"|(?<=Y)" + _NUMBER + "(?: Z" + _NUMBER + ")?+|(?<=Z)" + _NUMBER + ")"
    r"(?: R" + _NUMBER + r")?+(?:[ \t]++F" + _NUMBER + r")?+[ \t]*+(?:\([^()\n;]*+\)[ \t]*+)?+"
    r"\r?+$|[^\n]*+)",
    re.M,
)
_CODES_RE = re.compile(r"(?:G(9[89])[ \t]++)?+(?:G(\d++)[ \t]++)?+[XYZ]")
_NOT_IN_NUMBER = np.ones(256, bool)
_NOT_IN_NUMBER[list(NUMBER_BYTES)] = False
_DIGIT = np.zeros(256, bool)
_DIGIT[48:58] = True
_NINES = bytes.maketrans(b"0123456789", b"9" * 10)  # every digit as a 9
_SHAPES_KEPT = 1 << 22  # characters of line shapes a reader keeps for the next chunks
_CHUNK = 1 << 20  # characters per whole-text pass (bounds the per-line tuples held at once)
_DIGITS_RE = re.compile(r"\d++")
# a "%" tape mark after a sequence number (``N890 %``), read as a bare "%" line is
_NUMBERED_PERCENT_RE = re.compile(r"[Nn]\s*+\d++\s*+%[^\n]*+")
_FUNCTION_RE = re.compile(r"([A-Za-z]++)\s*+\[")  # a function's name and its opening bracket
_OWORD_RE = re.compile(
    r"\s*+[Oo]\s*+(?:\d++|<[^>]*+>)\s*+(sub|endsub|if|elseif|else|endif|while|endwhile|do|call|"
    r"return|repeat|endrepeat|break|continue)\b",
    re.I,
)
# a line _OWORD_RE may match: the first, or one after a "\n" (searched for as a literal, which
# is faster than ^ in MULTILINE mode)
_OWORD_FIRST_RE = re.compile(r"[^\S\n]*+[Oo]")
_OWORD_NEXT_RE = re.compile(r"\n[^\S\n]*+[Oo]")
_LETTERS = frozenset(string.ascii_letters)
_BOMS = ("\xef\xbb\xbf", "\ufeff")  # UTF-8 byte-order mark read as latin-1, or decoded
AXES = "XYZ"
ROTARY = "ABCUVW"
CYCLES = frozenset(("73", "81", "82", "83", "84", "85", "86", "87", "88", "89"))
MOTION_MODES = frozenset(("0", "1", "2", "3", "80")) | CYCLES
_BULK_MOTIONS = CYCLES | {"0", "1"}  # the motion modes a run of plain lines is taken in
_MOTION_NAMES = np.array(["G" + str(g) for g in range(100)], dtype=object)  # code -> name
_RETRACT_NAMES = np.full(100, "", dtype=object)  # code -> a cycle's retract ("": not a cycle)
_RETRACT_NAMES[[98, 99]] = "G98", "G99"
_NAME_OBJECTS = [*_MOTION_NAMES.tolist(), *_RETRACT_NAMES[[0, 98, 99]].tolist()]  # those str
INCH_MM = 25.4
_ROTARY_SET = frozenset(ROTARY)
POLAR = "@^"  # LinuxCNC's polar radius and angle (degrees) in the XY plane
_POLAR_SET = frozenset(POLAR)
_KEPT = frozenset(AXES + ROTARY + POLAR + "RLTHQIJKP")  # the Words a move, G10 or a tool needs
_TOOL_WORDS = frozenset(("T", "H", "M6", "M61"))  # a block that may change the tool
_TOOL_CODES = frozenset(("43", "43.1", "43.2", "49"))
_POSITION_LETTERS = frozenset(AXES + ROTARY + POLAR + "R")
# the axis words a G92/G52 offset may name: one on X, Y or Z (or a polar word) moves the program
# frame; one on A, B, C, U, V, W (or a printer's extruder E) does not
_OFFSET_LETTERS = frozenset(AXES + ROTARY + POLAR + "E")
_FRAME_LETTERS = frozenset(AXES + POLAR)
_ORIENTATION = frozenset("ABC")
# numbered parameters that hold the G92 offsets and the work offset tables (#5211-#5390):
# assigning one changes the program frame
_OFFSET_PARAMETERS = range(5211, 5391)
_NONMODAL = frozenset("4 10 28 28.1 30 30.1 52 53 92 92.1 92.2 92.3".split())
_PARAMETER_CODES = frozenset("10 28.1 30.1 52 92 92.1 92.2 92.3".split())
# G-codes that neither move nor change where a programmed position lands (or whose effect is
# followed above); any other G-code is a motion this reader does not know
_HARMLESS = frozenset(
    "17 18 19 20 21 40 43 43.1 49 54 61 61.1 64 80 90 90.1 91 91.1 93 94 95 96 97 98 99".split()
)
_KNOWN_MOTIONS = {
    "2": "arc G2",
    "3": "arc G3",
    "5": "spline G5",
    "5.1": "quadratic spline G5.1",
    "5.2": "NURBS G5.2",
    "33": "spindle-synchronized motion G33",
    "33.1": "rigid tapping G33.1",
    "38.2": "probe G38.2",
    "38.3": "probe G38.3",
    "38.4": "probe G38.4",
    "38.5": "probe G38.5",
    "76": "threading cycle G76",
}
_ARC_WORDS = frozenset("IJK")  # an arc's centre: a G2/G3 block with them and no axis moves
_WCS = frozenset(("55", "56", "57", "58", "59", "59.1", "59.2", "59.3"))
_G_NAMES = {float(g): g for g in (str(i) for i in range(100))}
_new_word = tuple.__new__  # a Word without the NamedTuple constructor's Python frame
_NAN3 = (math.nan, math.nan, math.nan)
MAX_REPEATS = 10_000  # a canned cycle's L beyond this is reported (each hole is checked)
WORD_LETTERS = "XYZR"  # the words a move keeps, in the order its ``words`` dict lists them
RESETS = frozenset(("G28", "G30", "G53"))  # moves after which the position is not known
_F_INCREMENTAL, _F_CYCLE, _F_RESETS, _F_G99, _F_FIRST = 1, 2, 4, 8, 16  # ``GcodeMoves`` flags
_F_G18, _F_G19 = 32, 64  # a canned cycle in the XZ plane (its axis Y) or the YZ plane (X)
CYCLE_AXIS = {"17": 2, "18": 1, "19": 0}  # a canned cycle's axis (depth, R) in each plane


class Word(NamedTuple):
    """One word's number: ``text[start:end]`` is ``literal`` (without the letter)."""

    letter: str
    value: float
    start: int
    end: int
    literal: str

    @property
    def decimals(self) -> int:
        """Digits after the decimal point as written."""
        return decimals_of(self.literal)


@dataclass(slots=True)
class GcodeMove:
    """One move (or cycle hole). Positions are absolute, in mm, in the program frame."""

    path: str | None
    line: int
    column: int
    motion: str  # "G0", "G1", "G2", "G3", "G81", ..., "G28", "G53", "G5", "G999"
    start: tuple[float, float, float]  # where the move starts (NaN where unknown)
    target: tuple[float, float, float]  # the end point; for a cycle the hole bottom (X, Y, Z)
    words: dict[str, Word]  # X/Y/Z (and R for a cycle) words on the line
    incremental: bool  # G91: words are increments
    scale: float  # mm per program unit (25.4 under G20)
    reason: str = ""  # why the move cannot be placed or corrected ("" when it can)
    rotary: dict[str, float] = field(default_factory=dict)  # A/B/C/U/V/W words in effect
    setters: tuple[int | None, int | None, int | None] = (None, None, None)
    # index (in the returned list) of the move that last set each start coordinate
    retract: str = ""  # cycles: "G98" or "G99"
    r_mm: float = math.nan  # cycles: the R plane (absolute mm)
    end: tuple[float, float, float] = _NAN3  # where the tool ends
    is_cycle: bool = False  # a canned-cycle hole (G73, G81-G89)

    x = property(lambda self: self.target[0])
    y = property(lambda self: self.target[1])
    z = property(lambda self: self.target[2])
    a = property(lambda self: self.rotary.get("A"))

    @property
    def is_arc(self) -> bool:
        return self.motion in ("G2", "G3")


class GcodeMoves:
    """The moves of one program, column by column: compact arrays instead of an object per move
    (a million-move program in a few hundred bytes per move); ``move(i)`` builds one
    ``GcodeMove`` on demand.

    After ``finish``: ``line``, ``column`` (N,) int; ``start``, ``target``, ``end`` (N, 3) mm in
    the program frame (NaN where unknown); ``scale`` and ``r_mm`` (N,) mm; ``incremental``,
    ``is_cycle``, ``resets`` (a G28/G30/G53 move, after which the position is not known),
    ``g99`` (a cycle retracting to R) and ``first_cycle`` (the first cycle block of a run: it sets
    the initial level) (N,) bool; ``cycle_axis`` (N,) a cycle's axis (2: Z in G17, 1: Y in
    G18, 0: X in G19; 2 for other moves); ``setters`` (N, 3) int (-1: none);
    ``word_start``, ``word_end`` (N, 4) text offsets of the X, Y, Z, R numbers (-1: not written)
    and ``word_value`` (N, 4) their values in program units; ``rotary_index`` (N,) int into
    ``rotaries`` (the distinct rotary dicts, each once); ``motion``, ``reason``, ``retract``
    lists of str; ``places`` the most decimals among the X, Y, Z literals of the moves (-1:
    none).

    Rows come one by one (``add``) or in bulk (``rows`` to fill, then ``extend``), into arrays
    of ``capacity`` rows (the program's lines: a line is one move at most; pages never written
    are never resident), grown if ever full; ``finish`` exposes the rows stored."""

    def __init__(self, path: str | None, text: str, capacity: int = 1024) -> None:
        self.path, self.text = path, text
        capacity = max(capacity, 1)
        self._ints = np.empty((capacity, 13), np.int64)  # line, column, 3 setters, 4+4 spans
        self._floats = np.empty((capacity, 15))  # start, target, end (9), scale, r_mm, 4 values
        self._flags = np.empty(capacity, np.int8)  # the _F_ bits
        self._rotary = np.empty(capacity, np.int64)
        self.rotaries: list[dict[str, float]] = []
        self.motion: list[str] = []
        self.reason: list[str] = []
        self.retract: list[str] = []
        # one str object per distinct motion and retract: those of the name tables and others
        self._names: dict[str, str] = dict(zip(_NAME_OBJECTS, _NAME_OBJECTS, strict=True))
        self.places = -1  # the most decimals among the X, Y, Z literals of the moves (-1: none)
        self.repeats: dict[
            int, int
        ] = {}  # row -> a cycle's L repeat count where not 1 (0: unknown)
        # row -> its polar words (@ radius, ^ angle; None: not written), X and Y not written
        self.polar: dict[int, tuple[Word | None, Word | None]] = {}
        # (first row, tool) where the programmed tool changes: a tool number, -1 the cell's,
        # a str why it is not known
        self.tool_changes: list[tuple[int, int | str]] = []
        self.arcs: dict[int, Arc] = {}  # row -> the centre, plane and turns of a G2/G3 arc
        # the first row read under control flow or a modal state not known (every row from it
        # on is: O-word loops, branches and subroutines run their moves elsewhere or again);
        # ``finish`` sets the number of rows where there is none
        self.flow_from = -1

    def __len__(self) -> int:
        return len(self.motion)

    def _room(self, m: int) -> int:
        """The index of the next row, the arrays grown to hold ``m`` more."""
        n = len(self.motion)
        if n + m > len(self._flags):
            size = max(n + m, 2 * len(self._flags))
            for key in ("_ints", "_floats", "_flags", "_rotary"):
                old = getattr(self, key)
                grown = np.empty((size, *old.shape[1:]), old.dtype)
                grown[:n] = old[:n]
                setattr(self, key, grown)
        return n

    def add(
        self, line, column, motion, start, target, words, reason, end, state, cycle, r_mm
    ) -> None:
        """Store one move as a row: ``start``, ``target``, ``end`` 3 mm each; ``words`` letter ->
        Word; ``state``: the ``_Modal`` it was read in (pos and setters before the move);
        ``r_mm``: a cycle's R plane (absolute mm)."""
        i = self._room(1)
        rotary = state.rotary
        if not self.rotaries or rotary is not self.rotaries[-1]:
            self.rotaries.append(rotary)
        self._rotary[i] = len(self.rotaries) - 1
        get = words.get
        x, y, z, r = get("X"), get("Y"), get("Z"), get("R")
        for word in (x, y, z):
            if word is not None and _NUMBER_RE.fullmatch(word.literal):  # not an expression
                self.places = max(self.places, decimals_of(word.literal))
        s0, s1, s2 = state.setter
        self._ints[i] = (
            line,
            column,
            -1 if s0 is None else s0,
            -1 if s1 is None else s1,
            -1 if s2 is None else s2,
            -1 if x is None else x.start,
            -1 if y is None else y.start,
            -1 if z is None else z.start,
            -1 if r is None else r.start,
            -1 if x is None else x.end,
            -1 if y is None else y.end,
            -1 if z is None else z.end,
            -1 if r is None else r.end,
        )
        self._floats[i] = (
            start[0],
            start[1],
            start[2],
            target[0],
            target[1],
            target[2],
            end[0],
            end[1],
            end[2],
            state.scale,
            r_mm if cycle else math.nan,
            math.nan if x is None else x.value,
            math.nan if y is None else y.value,
            math.nan if z is None else z.value,
            math.nan if r is None else r.value,
        )
        retract = state.retract if cycle else ""
        self._flags[i] = (
            state.incremental * _F_INCREMENTAL
            + bool(cycle) * _F_CYCLE
            + (cycle == 2) * _F_FIRST
            + bool(cycle) * (_F_G18 * (state.plane == "18") + _F_G19 * (state.plane == "19"))
            + (motion in RESETS) * _F_RESETS
            + (retract == "G99") * _F_G99
        )
        names = self._names
        self.motion.append(names.setdefault(motion, motion))
        self.retract.append(names.setdefault(retract, retract))
        self.reason.append(reason)

    def rows(self, m: int) -> tuple[np.ndarray, np.ndarray]:
        """The next ``m`` rows to fill before ``extend`` stores them: ints (m, 13) and floats
        (m, 15) in the row layout (views)."""
        i = self._room(m)
        return self._ints[i : i + m], self._floats[i : i + m]

    def extend(self, cycle, g99, first, rotary, motion, retract, reason) -> None:
        """Store the rows ``rows`` gave, filled, as ``add`` stores one: ``cycle``, ``g99`` and
        ``first`` (the first cycle of a run) (M,) bool (no row is incremental nor resets the
        position), ``rotary`` the dict in effect
        for all, ``motion``/``retract``/``reason`` M strings each (motions and retracts from
        ``_MOTION_NAMES`` and ``_RETRACT_NAMES``)."""
        if not self.rotaries or rotary is not self.rotaries[-1]:
            self.rotaries.append(rotary)
        i, m = len(self.motion), len(motion)
        self._flags[i : i + m] = (
            _F_CYCLE * np.asarray(cycle, np.int8) + _F_G99 * g99 + _F_FIRST * np.asarray(first)
        )
        self._rotary[i : i + m] = len(self.rotaries) - 1
        self.motion += motion
        self.retract += retract
        self.reason += reason

    def finish(self) -> GcodeMoves:
        """Expose the columns as arrays (views of the rows stored)."""
        n = len(self.motion)
        ints, floats, flags = self._ints[:n], self._floats[:n], self._flags[:n]
        self.ints, self.floats, self.flags = ints, floats, flags
        self.line, self.column, self.setters = ints[:, 0], ints[:, 1], ints[:, 2:5]
        self.word_start, self.word_end = ints[:, 5:9], ints[:, 9:13]
        self.start, self.target, self.end = floats[:, 0:3], floats[:, 3:6], floats[:, 6:9]
        self.scale, self.r_mm, self.word_value = floats[:, 9], floats[:, 10], floats[:, 11:15]
        self.incremental = (flags & _F_INCREMENTAL) != 0
        self.is_cycle = (flags & _F_CYCLE) != 0
        self.first_cycle = (flags & _F_FIRST) != 0
        self.resets = (flags & _F_RESETS) != 0
        self.g99 = (flags & _F_G99) != 0
        self.cycle_axis = np.where(flags & _F_G18, 1, np.where(flags & _F_G19, 0, 2))
        self.rotary_index = self._rotary[:n]
        if self.flow_from < 0:
            self.flow_from = n
        return self

    def tool_spans(self) -> list[tuple[int, int, int | str]]:
        """(first row, end row, tool) of each run of moves programmed with one tool: a tool
        number (its length offset in effect), -1 (none: the cell's tool) or why it is not
        known; the rows before the first change are the cell's tool's."""
        changes = [(0, -1), *self.tool_changes]
        ends = [row for row, _ in changes[1:]] + [len(self.motion)]
        return [(a, b, tool) for (a, tool), b in zip(changes, ends, strict=True) if b > a]

    def move(self, i: int) -> GcodeMove:
        """Move ``i`` as a ``GcodeMove`` (as the reader built it; after ``finish``)."""
        ints = self.ints[i].tolist()
        floats = self.floats[i].tolist()
        words = {}
        for k, letter in enumerate(WORD_LETTERS):
            start, end = ints[5 + k], ints[9 + k]
            if start >= 0:
                literal = self.text[start:end]
                words[letter] = _new_word(Word, (letter, floats[11 + k], start, end, literal))
        flags = int(self.flags[i])
        return GcodeMove(
            self.path,
            ints[0],
            ints[1],
            self.motion[i],
            tuple(floats[0:3]),
            tuple(floats[3:6]),
            words,
            bool(flags & _F_INCREMENTAL),
            floats[9],
            self.reason[i],
            self.rotaries[self.rotary_index[i]],
            tuple(None if j < 0 else j for j in ints[2:5]),
            self.retract[i],
            floats[10],
            tuple(floats[6:9]),
            bool(flags & _F_CYCLE),
        )


class _Line(NamedTuple):
    """One block read: its words (None for letters that are never a position; a word whose
    parameter or expression was evaluated holds the value, its ``literal`` the text), G
    numbers, the letters whose parameter or expression is not decidable (letter -> text as
    written, ``why`` letter -> the reason) and the line's parameter assignments (key, value or
    the reason it is not known), which take effect after the line."""

    words: dict[str, Word | None]
    gcodes: list[str]
    exprs: dict[str, str]
    why: dict[str, str] | None = None
    assigns: list[tuple[int | str, float | str]] | None = None


@dataclass(slots=True)
class _Modal:
    """The modal state while reading, and why the program frame is not the cell's G54 frame.

    Each reason has its own field because each is cancelled by its own code: G54 ends a G55-G59.3
    selection but not a G92/G52 offset, a G10 table change or a G68 rotation."""

    motion: str = "0"
    incremental: bool = False
    scale: float = 1.0
    plane: str = "17"
    arc_absolute: bool = False  # G90.1: an arc's I, J, K are absolute (G91.1: from its start)
    retract: str = "G98"
    cycle_z: float = math.nan
    cycle_r: float = math.nan
    # the initial level: Z where a run of cycle blocks began (None: no run; a non-cycle motion
    # mode or G80 ends one), which G98 retracts to and a G91 R is counted from (as LinuxCNC)
    cycle_il: float | None = None
    pos: list[float] = field(default_factory=lambda: [math.nan] * 3)  # absolute mm, program frame
    setter: list[int | None] = field(default_factory=lambda: [None] * 3)
    rotary: dict[str, float] = field(default_factory=dict)
    flow: str = ""  # control flow / unknown modal state: for the rest of the program
    wcs: str = ""  # G55-G59.3 (cleared by G54)
    offset: str = ""  # G92/G52/G92.3 (cleared by G92.1/G92.2)
    # A/B/C offset by G92/G52 (cleared by G92.1/G92.2): their words are no longer the tool's
    # orientation (X, Y, Z are not moved)
    turned: frozenset[str] = frozenset()
    table: str = ""  # G10 changed the work offsets or tool table: for the rest of the program
    transform: str = ""  # G68/G51 (cleared by G69/G50)
    comp: str = ""  # cutter compensation G41/G42 (cleared by G40)
    unknown_motion: str = ""  # the motion mode is not one whose geometry is known

    def frame_reason(self) -> str:
        return self.flow or self.wcs or self.offset or self.table or self.transform or self.comp

    def apply(self, g: str, lineno: int, l_word: Word | None, axes=frozenset()) -> None:
        """One G-code of a block (its number as text: "1", "91.1"); ``l_word``: the block's L,
        ``axes``: the axis letters the block writes (``_OFFSET_LETTERS``)."""
        if g in MOTION_MODES:
            self.motion, self.unknown_motion = g, ""
            if g not in CYCLES:
                self.cycle_il = None
        elif g == "20" or g == "21":
            self.scale = INCH_MM if g == "20" else 1.0
        elif g == "90" or g == "91":
            self.incremental = g == "91"
        elif g == "90.1" or g == "91.1":
            self.arc_absolute = g == "90.1"
        elif g in ("17", "18", "19"):
            self.plane = g
        elif g in ("98", "99"):
            self.retract = "G" + g
        elif g == "54":
            self.wcs = ""  # back to the cell's frame; offsets, tables, rotations still apply
        elif g in _WCS:
            self.wcs = f"work offset G{g} (line {lineno}): the cell gives only G54"
        elif g in ("92", "52") and axes and _FRAME_LETTERS.isdisjoint(axes):
            self.turned = self.turned | (axes & _ORIENTATION)  # U, V, W, E: nothing to follow
        elif g in ("92", "52", "92.3"):
            self.offset = f"G{g} offset (line {lineno}) moves the program frame"
        elif g in ("92.1", "92.2"):
            self.offset, self.turned = "", frozenset()
        elif g == "10":
            what = f"G10 L{l_word.literal}" if l_word is not None else "G10"
            table = "work offsets" if l_word is None or l_word.value in (2, 20) else "tool table"
            self.table = f"{what} (line {lineno}) changes the {table}"
        elif g in ("41", "42", "41.1", "42.1"):
            self.comp = f"cutter compensation G{g} (line {lineno}) offsets the path"
        elif g == "40":
            self.comp = ""
        elif g in ("68", "51"):
            self.transform = f"G{g} (line {lineno}) rotates or scales the program"
        elif g in ("69", "50"):
            self.transform = ""
        elif g in _NONMODAL or g in _HARMLESS:
            pass
        else:  # a motion whose geometry is not known, or a code this reader does not know
            self.motion, self.cycle_il = g, None
            what = _KNOWN_MOTIONS.get(g, f"unknown G-code G{g}")
            self.unknown_motion = (
                f"{what} (line {lineno}): its geometry is not known to accugrid, not corrected"
            )


def _tool_number(word: Word | None, expr: str | None, lineno: int) -> int | str:
    """The tool number of a T, H or Q word, or why it is not one."""
    if word is None:
        return f"tool number {expr} at line {lineno}: an expression"
    value = word.value
    if value < 0 or value != int(value) or value > 1e9:
        return f"tool number {word.letter}{word.literal} at line {lineno}: not a tool number"
    return int(value)


def _blank_comments(line: str, path: str | None, lineno: int) -> str:
    """The line with ``( )`` comments and the ``;`` tail replaced by spaces (offsets kept)."""
    if "(" not in line and ";" not in line and ")" not in line:
        return line
    if ";" not in line and line.count("(") == 1 and line.count(")") == 1:
        start, end = line.find("("), line.find(")") + 1
        if start < end:  # the common case: one ( ) comment
            return line[:start] + " " * (end - start) + line[end:]
    parts: list[str] = []
    pos, n = 0, len(line)
    found = {c: line.find(c) for c in "(;)"}  # next of each, refreshed only once passed
    while True:
        for c, at in found.items():
            if 0 <= at < pos:
                found[c] = line.find(c, pos)
        hits = [at for at in found.values() if at >= 0]
        if not hits:
            parts.append(line[pos:])
            return "".join(parts)
        at = min(hits)
        parts.append(line[pos:at])
        if line[at] == ")":
            raise InputError("')' without '('", path, lineno, at + 1)
        if line[at] == ";":
            parts.append(" " * (n - at))
            return "".join(parts)
        close = found[")"] if found[")"] > at else line.find(")", at)
        if close < 0:
            raise InputError("unclosed '(' comment", path, lineno, at + 1)
        parts.append(" " * (close + 1 - at))
        pos = close + 1


def _gnum(value: float) -> str:
    """G-code number as a key: 1 -> "1", 91.1 -> "91.1"."""
    return f"{value:.1f}".rstrip("0").rstrip(".")


def _skip_blank(line: str, i: int) -> int:
    """The first index from ``i`` that is not whitespace (the same whitespace as ``\\s``)."""
    while i < len(line) and line[i].isspace():
        i += 1
    return i


def _bracket_end(line: str, i: int, path: str | None, lineno: int) -> int:
    """End of the ``[...]`` that opens at ``line[i]``."""
    depth = 0
    for j in range(i, len(line)):
        if line[j] == "[":
            depth += 1
        elif line[j] == "]":
            depth -= 1
            if depth == 0:
                return j + 1
    raise InputError("unclosed '[' expression", path, lineno, i + 1)


def _expression_end(line: str, i: int, path: str | None, lineno: int) -> int:
    """End of the parameter reference (``#1``, ``##2``, ``#<name>``), ``[expression]`` or
    function (``sin[30]``, ``atan[1]/[2]``) that starts at ``line[i]`` (after an optional
    sign)."""
    if line[i] in "+-":
        i = _skip_blank(line, i + 1)
    while i < len(line) and line[i] == "#":
        i = _skip_blank(line, i + 1)
    if i < len(line) and line[i] == "[":
        return _bracket_end(line, i, path, lineno)
    if i < len(line) and line[i] == "<":
        close = line.find(">", i)
        if close < 0:
            raise InputError("unclosed '<' parameter name", path, lineno, i + 1)
        return close + 1
    m = _FUNCTION_RE.match(line, i)
    if m is not None:
        end = _bracket_end(line, m.end() - 1, path, lineno)
        if m.group(1).lower() == "atan":  # ATAN[y]/[x]
            slash = _skip_blank(line, end)
            if line[slash : slash + 1] != "/":
                raise InputError("ATAN[y] without /[x]", path, lineno, slash + 1)
            at = _skip_blank(line, slash + 1)
            if line[at : at + 1] != "[":
                raise InputError("ATAN[y]/ without [x]", path, lineno, at + 1)
            end = _bracket_end(line, at, path, lineno)
        return end
    m = _DIGITS_RE.match(line, i)
    if m is None:
        raise InputError("cannot read this parameter or expression", path, lineno, i + 1)
    return m.end()


def _is_expression(line: str, i: int) -> bool:
    if i < len(line) and line[i] in "+-":
        i = _skip_blank(line, i + 1)
    return i < len(line) and (line[i] in "#[" or _FUNCTION_RE.match(line, i) is not None)


def _evaluated(params: Parameters, text: str, path: str | None, lineno: int, at: int):
    """The value of a word's or an assignment's ``text`` (starting at ``line[at]``), or the
    reason (str) it is not decidable before run time; InputError where it is not RS274NGC."""
    try:
        value = params.evaluate(text)
    except Undecided as why:
        return str(why)
    except ValueError as bad:
        raise InputError(
            f"cannot read the expression {text.strip()!r}", path, lineno, at + 1
        ) from bad
    except OverflowError:
        return f"{text.strip()} overflows"
    if not math.isfinite(value):
        return f"{text.strip()} is not a finite number"
    return value


def _scan(line: str, offset: int, path: str | None, lineno: int, params: Parameters) -> _Line:
    """Read a comment-free block word by word (every line the bulk reader does not take:
    parameters, expressions, polar words, errors). Expressions are evaluated with ``params`` as
    it stands before the line.

    ``offset``: text offset of ``line[0]``. InputError at the first thing that is not a word or a
    parameter assignment."""
    block = _Line({}, [], {}, {}, [])
    i, n = 0, len(line)
    while True:
        i = _skip_blank(line, i)
        if i >= n:
            return block
        ch = line[i]
        if ch == "#":  # parameter assignment: #1 = 5, #<_z> = [#1 + 2]
            end = _skip_blank(line, _expression_end(line, i, path, lineno))
            if line[end : end + 1] != "=":
                raise InputError("a parameter outside a word must be assigned", path, lineno, i + 1)
            value = _skip_blank(line, end + 1)
            m = _NUMBER_RE.match(line, value)
            if m is None and not _is_expression(line, value):
                raise InputError("cannot read the parameter's value", path, lineno, value + 1)
            after = m.end() if m else _expression_end(line, value, path, lineno)
            try:
                key = params.key_of(line[i:end])
            except Undecided as why:  # which parameter it sets is not known
                block.assigns.append((None, f"{line[i:end].strip()} = ..: {why}"))
                i = after
                continue
            except ValueError as bad:
                raise InputError("cannot read this parameter", path, lineno, i + 1) from bad
            got = _evaluated(params, line[value:after], path, lineno, value)
            if isinstance(got, str):
                got = f"is set from {line[value:after].strip()} (line {lineno}): {got}"
            block.assigns.append((key, got))
            i = after
            continue
        if ch not in _LETTERS and ch not in POLAR:
            bad = line[i:].split()[0]
            raise InputError(f"cannot read {bad!r} as a G-code word", path, lineno, i + 1)
        letter = ch.upper()
        at = _skip_blank(line, i + 1)
        m = _NUMBER_RE.match(line, at)
        if m is None and not _is_expression(line, at):
            bad = line[i:].split()[0]
            raise InputError(f"cannot read {bad!r} as a G-code word", path, lineno, i + 1)
        if m is not None:
            end = m.end()
            _put(block, letter, m.group(), at, end, offset, path, lineno)
            i = end
            continue
        end = _expression_end(line, at, path, lineno)
        if (letter in block.words or letter in block.exprs) and letter != "M":
            raise InputError(f"word {letter} given twice", path, lineno, at + 1)
        got = _evaluated(params, line[at:end], path, lineno, at)
        if isinstance(got, str):
            block.exprs[letter] = line[i:end]
            block.why[letter] = got
        elif letter == "G":
            block.gcodes.append(_G_NAMES.get(got) or _gnum(got))
        elif letter in _KEPT:
            block.words[letter] = _new_word(
                Word, (letter, got, offset + at, offset + end, line[at:end])
            )
        else:
            block.words[letter] = None
        i = end


def _put(block: _Line, letter: str, number: str, at: int, end: int, offset: int, path, lineno):
    """Add one word read at ``line[at:end]`` (its number) to ``block``; ``offset``: of line[0]."""
    if letter == "G":
        value = float(number)
        block.gcodes.append(_G_NAMES.get(value) or _gnum(value))
        return
    words = block.words
    if (letter in words or letter in block.exprs) and letter != "M":
        raise InputError(f"word {letter} given twice", path, lineno, at + 1)
    if letter in _KEPT:
        value = float(number)
        if value - value:  # inf - inf is NaN: a literal beyond the float range
            shown = number if len(number) <= 20 else number[:20] + "..."
            raise InputError(f"word {letter}{shown}: number out of range", path, lineno, at + 1)
        words[letter] = _new_word(Word, (letter, value, offset + at, offset + end, number))
    else:  # N, F, S, M, ...: only seen (a second one is an error), never a position
        words[letter] = None
        if letter == "M" and (number.lstrip("+0") in ("6", "6.", "61", "61.")):
            words["M" + number.lstrip("+0").rstrip(".")] = None  # M6, M61: the tool changes


def _plain_codes(codes: str) -> int:
    """A plain line's G-codes and first letter (``"G99 G81 X"``) as ``1000 * retract + motion +
    2``: retract 98, 99 or 0 (none), motion -1 where the line sets none; a line that is not plain
    (``""``) gives motion -2."""
    m = _CODES_RE.fullmatch(codes)
    if m is None:
        return 0
    return 1000 * int(m[1] or 0) + (int(m[2]) if m[2] else -1) + 2


def _shapes(chunk: str, data: bytes | None, count: int) -> list[str]:
    """The shapes of the first ``count`` lines of ``chunk``: each line with the digits
    ``_ROW_RE`` reads alike as 9s; ``data``: the chunk's latin-1 bytes (None: it has other
    characters, and then each line is its own shape: ``\\d`` is more than 0-9 there).

    ``_ROW_RE`` reads any digits as ``\\d`` but those of a G-code, the one or two right after
    its ``G``; a line keeps its length and every other character in its shape, so lines of one
    shape match alike and have their words at the same offsets: a few hundred shapes for
    100,000 CAM lines, each read once (``_Shapes``)."""
    if data is None:
        shapes = chunk.split("\n")
    else:
        buf = np.frombuffer(data, np.uint8)
        nines = bytearray(data.translate(_NINES))
        first = np.flatnonzero(buf[:-1] == ord("G")) + 1  # a G-code's digits: its first two
        first = first[_DIGIT[buf[first]]]
        second = first[first + 1 < len(buf)] + 1
        second = second[_DIGIT[buf[second]]]
        view = np.frombuffer(nines, np.uint8)
        view[first], view[second] = buf[first], buf[second]
        del view
        shapes = nines.decode("latin-1").split("\n")
    del shapes[count:]
    return shapes


class _Shapes:
    """The line shapes a reader met (_SHAPES_KEPT characters of them kept), each read once:
    ``codes`` (S,)
    its ``_plain_codes`` (of the head ``_ROW_RE`` finds) and ``spans`` (S, 4, 2) the offsets of
    its X, Y, Z, R numbers as a plain line has them (-1: none)."""

    def __init__(self) -> None:
        self.index: dict[str, int] = {}
        self.codes = np.zeros(0, np.int64)
        self.spans = np.zeros((0, 4, 2), np.int64)
        self.size = 0  # characters

    def ids(self, shapes: list[str]) -> np.ndarray:
        """The index (M,) of each shape in ``codes`` and ``spans``, the new ones read."""
        new = list(set(shapes).difference(self.index))
        size = sum(map(len, new))
        if self.size + size > _SHAPES_KEPT:  # not a program of few repeated shapes, it seems
            self.index, self.codes, self.spans, self.size = {}, self.codes[:0], self.spans[:0], 0
            new = list(set(shapes))
            size = sum(map(len, new))
        self.size += size
        if new:
            first = len(self.index)
            self.index.update(zip(new, range(first, first + len(new)), strict=True))
            codes = [_plain_codes(_ROW_RE.match(shape)[1] or "") for shape in new]
            self.codes = np.append(self.codes, codes)
            self.spans = np.concatenate([self.spans, _number_spans(new)])
        return np.fromiter(map(self.index.__getitem__, shapes), np.int64, len(shapes))


def _number_spans(lines: list[str]) -> np.ndarray:
    """The offsets (M, 4, 2) in each line of the numbers after its first X, Y, Z and R before
    any ``(`` (-1: none), a number ending at the first byte not in one."""
    buf = np.frombuffer("\n".join(lines).encode("latin-1", "replace"), np.uint8)
    newlines = np.flatnonzero(buf == 10)
    begins = np.concatenate(([0], newlines + 1))
    ends = np.append(newlines, len(buf))
    stops = np.append(np.flatnonzero(_NOT_IN_NUMBER[buf]), len(buf))
    opens = np.append(np.flatnonzero(buf == ord("(")), len(buf))
    words_end = np.minimum(opens[np.searchsorted(opens, begins)], ends)
    spans = np.full((len(lines), 4, 2), -1)
    for k, letter in enumerate(b"XYZR"):
        found = np.append(np.flatnonzero(buf == letter), len(buf))
        where = found[np.searchsorted(found, begins)] + 1  # the number after the letter
        has = where <= words_end
        spans[has, k, 0] = where[has]
        spans[has, k, 1] = stops[np.searchsorted(stops, where[has])]
    return np.where(spans >= 0, spans - begins[:, None, None], -1)


class _PlainRun(NamedTuple):
    """Consecutive plain lines of a chunk: ``lineno`` of the first; per line ``begin`` (its text
    offset), ``spans`` (M, 4, 2) text offsets (start, end) of the X, Y, Z, R numbers and
    ``values`` (M, 4) their values in program units (-1 and NaN: not written), ``retract`` 98/99
    (0: not written) and ``motion`` (-1: not written)."""

    lineno: int
    begin: np.ndarray
    spans: np.ndarray
    values: np.ndarray
    retract: np.ndarray
    motion: np.ndarray

    def part(self, first: int) -> _PlainRun:
        """The run from its line ``first`` on."""
        if not first:
            return self
        return _PlainRun(self.lineno + first, *(column[first:] for column in self[1:]))


def modal_fill(values: np.ndarray, written: np.ndarray, before) -> np.ndarray:
    """A modal value per line: ``values`` (M,) where ``written`` (M,) bool, else the last one
    written before (``before`` until the first)."""
    last = np.maximum.accumulate(np.where(written, np.arange(len(values)), -1))
    return np.where(last >= 0, values[np.maximum(last, 0)], before)


class _Reader:
    """Reads one program: ``moves`` in order, the modal state in ``state``."""

    def __init__(self, path: str | None, text: str) -> None:
        self.path = path
        self.state = _Modal()
        lines = text.count("\n") if "\n" in text else text.count("\r")  # as split_lines cuts
        self.moves = GcodeMoves(path, text, lines + 1)
        # whole-text checks first: most programs have no O-words or block deletes, and then no
        # line needs those per-line checks
        self.owords = bool(_OWORD_FIRST_RE.match(text) or _OWORD_NEXT_RE.search(text))
        self.slashes = "/" in text
        self.bom = next((b for b in _BOMS if text.startswith(b)), "")
        self.shapes = _Shapes()
        self.params = Parameters()
        self.selected: int | str = "no T word before M6"  # the tool T selected
        self.loaded: int | str = "no tool loaded by the program (T n M6)"
        self.offset: int | str = -1  # whose length offset is in effect (-1: none)

    def line(self, raw: str, lineno: int, line_offset: int) -> None:
        """Read one line (without its ending) that starts at text offset ``line_offset``."""
        bom = self.bom and lineno == 1
        if bom:  # a byte-order mark is not a word (offsets stay as in the file)
            raw = " " * len(self.bom) + raw[len(self.bom) :]
        stripped = raw.strip()
        if not stripped or stripped.startswith("%") or _NUMBERED_PERCENT_RE.fullmatch(stripped):
            return
        if self.owords and _OWORD_RE.match(raw):
            self._flow(f"O-word control flow from line {lineno}")
            return
        line = _blank_comments(raw, self.path, lineno)
        if self.slashes and line.lstrip().startswith("/"):
            line = line.replace("/", " ", 1)
        block = _scan(line, line_offset, self.path, lineno, self.params)
        self.block(block, lineno, line_offset)
        if block.assigns:
            self._assign(block.assigns, lineno)

    def _flow(self, why: str) -> None:
        """Control flow or a modal state not known from here on (``why``): the moves read after
        this are reported with it (``GcodeMoves.flow_from``)."""
        if not self.state.flow:
            self.state.flow = why
            self.moves.flow_from = len(self.moves)

    def _assign(self, assigns: list[tuple[int | str | None, float | str]], lineno: int) -> None:
        """A line's parameter assignments (key, value or the reason it is not known), after the
        line. One whose parameter is not known (key None) may have set any: every parameter is
        unknown from here on; one that sets a work offset (#5211-#5390) moves the program
        frame."""
        state = self.state
        for key, value in assigns:
            if key is None:
                self.params.forget(f"is not known after {value} (line {lineno})")
                continue
            if isinstance(key, int) and key in _OFFSET_PARAMETERS:
                state.table = state.table or (
                    f"#{key} assigned (line {lineno}) changes the work offsets"
                )
            self.params.values[key] = value

    def plain_run(self, run: _PlainRun) -> tuple[int, int]:
        """Take the plain lines of ``run`` in bulk, as ``block`` would take them one by one, as
        far as the modal state allows: (lines taken, lines after them to read one by one).

        Plain lines set only the motion mode and G98/G99, and write some of X, Y, Z (and R) as
        absolute numbers; taken in bulk under G90 with a motion mode of G0, G1 or a canned cycle
        (in G17), every other state read by ``block``."""
        s, m = self.state, len(run.begin)
        if s.incremental:
            return 0, m
        if run.motion[0] < 0 and s.motion not in _BULK_MOTIONS:  # until a line sets a known one
            written = np.flatnonzero(run.motion >= 0)
            return 0, int(written[0]) if len(written) else m
        before = int(s.motion) if s.motion in _BULK_MOTIONS else -1
        motion = modal_fill(run.motion, run.motion >= 0, before)
        cycle = motion >= 73
        if s.plane != "17" and cycle.any():
            return 0, m
        retract = modal_fill(run.retract, run.retract > 0, int(s.retract[1:]))
        v, first = run.values * s.scale, len(self.moves)
        wrote = run.spans[:, :, 0] >= 0  # (m, 4) X, Y, Z, R written
        wrote_r = cycle & wrote[:, 3]  # R is a word of cycles only
        r_mm = modal_fill(v[:, 3], wrote_r, s.cycle_r)  # the R plane in effect
        cycle_z = modal_fill(v[:, 2], cycle & wrote[:, 2], s.cycle_z)  # the depth in effect
        end = np.empty((m, 3))
        for i in range(2):  # X, Y: as written, else where the previous move left them
            end[:, i] = modal_fill(v[:, i], wrote[:, i], s.pos[i])
        # Z: a straight move's as written, a cycle's retract (R under G99, the higher of the
        # initial level and R under G98), else where the previous move left it; the first cycle
        # of a run (after another motion mode) sets the initial level
        end[:, 2] = np.where(cycle, r_mm, v[:, 2])
        starts_run = cycle & ~np.append(s.cycle_il is not None, cycle[:-1])
        carried = (cycle & (retract == 98)) | ~(cycle | wrote[:, 2]) | starts_run
        il = s.cycle_il
        if carried.any():  # those that depend on the previous end: one by one
            z, r, hole = end[:, 2].tolist(), r_mm.tolist(), cycle.tolist()
            run_start, g98 = starts_run.tolist(), (retract == 98).tolist()
            for k in np.flatnonzero(carried).tolist():
                before = z[k - 1] if k else s.pos[2]
                if not hole[k]:
                    z[k] = before
                    continue
                if run_start[k]:
                    il = before
                if g98[k]:
                    z[k] = r[k] if r[k] > il else il
            end[:, 2] = z
        ints, floats = self.moves.rows(m)  # filled in place
        floats[0, 0:3], floats[1:, 0:3] = s.pos, end[:-1]  # start
        target = floats[:, 3:6]
        target[:, :2], target[:, 2] = end[:, :2], np.where(cycle, cycle_z, end[:, 2])
        floats[:, 6:9] = end
        # the move that last set each coordinate, before each move (a cycle always sets Z)
        index = np.arange(first, first + m)
        after = [
            modal_fill(index, wrote[:, i] | (cycle if i == 2 else False), j)
            for i, j in enumerate(-1 if j is None else j for j in s.setter)
        ]
        setters = np.vstack([[-1 if j is None else j for j in s.setter], np.stack(after, 1)[:-1]])
        starts, ends = run.spans[:, :, 0].copy(), run.spans[:, :, 1].copy()
        starts[~wrote_r, 3] = ends[~wrote_r, 3] = -1
        column = np.where(
            wrote[:, 0], starts[:, 0], np.where(wrote[:, 1], starts[:, 1], starts[:, 2])
        )
        ints[:, 0], ints[:, 1] = np.arange(run.lineno, run.lineno + m), column - run.begin + 1
        ints[:, 2:5], ints[:, 5:9], ints[:, 9:13] = setters, starts, ends
        floats[:, 9], floats[:, 10] = s.scale, np.where(cycle, r_mm, np.nan)
        floats[:, 11:15] = np.where(wrote, run.values, np.nan)
        floats[:, 14] = np.where(wrote_r, floats[:, 14], np.nan)
        reason = [s.frame_reason()] * m
        if not reason[0]:
            missing = np.flatnonzero(cycle & (np.isnan(r_mm) | np.isnan(cycle_z))).tolist()
            for k in missing:
                reason[k] = "canned cycle without an R plane or Z depth"
            unknown = np.isnan(target)
            for k in np.flatnonzero(unknown.any(axis=1)).tolist():
                if not reason[k]:
                    axes = ",".join(a for a, u in zip(AXES, unknown[k].tolist(), strict=True) if u)
                    reason[k] = f"{axes} not known here (no absolute value since the start)"
        names = _MOTION_NAMES[motion].tolist()
        retracts = _RETRACT_NAMES[np.where(cycle, retract, 0)].tolist()
        g99 = cycle & (retract == 99)
        self.moves.extend(cycle, g99, starts_run, s.rotary, names, retracts, reason)
        s.motion, s.unknown_motion = str(motion[-1]), ""
        s.cycle_il = il if cycle[-1] else None
        s.retract = f"G{retract[-1]}"
        s.cycle_z, s.cycle_r = float(cycle_z[-1]), float(r_mm[-1])
        s.pos = end[-1].tolist()
        s.setter = [None if j < 0 else j for j in (int(a[-1]) for a in after)]
        return m, 0

    def block(self, block: _Line, lineno: int, line_offset: int) -> None:
        state = self.state
        words = block.words
        gcodes = block.gcodes
        if not _TOOL_WORDS.isdisjoint(words) or gcodes and not _TOOL_CODES.isdisjoint(gcodes):
            self._tool(block, lineno)
        if len(gcodes) > 1:  # a known motion first: an unknown code on the same line wins
            gcodes = sorted(gcodes, key=lambda g: g not in MOTION_MODES)
        axes = _OFFSET_LETTERS & (words.keys() | block.exprs.keys()) if gcodes else frozenset()
        for g in gcodes:
            state.apply(g, lineno, words.get("L"), axes)
        if "G" in block.exprs:
            self._flow(
                f"G-code from an expression {block.exprs['G']} (line {lineno}): the modal state "
                "is not known"
            )
        has_rotary = self._rotary(block)
        # a dwell (G4) takes no axis words: those of its line are the motion mode's
        nonmodal = [g for g in block.gcodes if g in _NONMODAL and g != "4"] if block.gcodes else []
        if nonmodal and nonmodal[0] in _PARAMETER_CODES:
            return  # the axis words are parameters, not a move
        axis_words = {k: words[k] for k in AXES if k in words}
        polar = {k: words[k] for k in POLAR if k in words}
        moving = [k for k in block.exprs if k in _POSITION_LETTERS]
        home = nonmodal[:1] == ["28"] or nonmodal[:1] == ["30"]  # goes home even without words
        circle = state.motion in ("2", "3") and not _ARC_WORDS.isdisjoint(words)  # full circle
        if not axis_words and not polar and not has_rotary and not moving and not home:
            if not circle:
                return
        if (polar or not _POLAR_SET.isdisjoint(block.exprs)) and not (
            {"X", "Y"}.isdisjoint(words) and {"X", "Y"}.isdisjoint(block.exprs)
        ):
            raise InputError("polar words @ ^ with X or Y in one block", self.path, lineno, 1)
        placed = [*axis_words.values(), *polar.values()]
        if placed:
            column = min(w.start for w in placed) - line_offset + 1
        else:
            column = 1
        if nonmodal:  # G28/G30 (via a point) or G53 (machine coordinates)
            name = "G" + nonmodal[0]
            self._add(
                (lineno, column, name, _NAN3, axis_words),
                f"{name}: a machine-coordinate or home move",
                [math.nan] * 3,
                AXES,
            )
            return
        why = _expression_reason(block, lineno)
        if state.motion in CYCLES:
            self._cycle(lineno, column, axis_words, words, block.exprs, why)
        else:
            self._straight(lineno, column, axis_words, block, why, polar)

    def _tool(self, block: _Line, lineno: int) -> None:
        """The tool changes of a block, in LinuxCNC's order: T, M6/M61, then G43/G49."""
        words, exprs = block.words, block.exprs
        if "T" in words or "T" in exprs:
            self.selected = _tool_number(words.get("T"), exprs.get("T"), lineno)
        loaded = None
        if "M6" in words:
            loaded = self.selected
        if "M61" in words:
            loaded = _tool_number(words.get("Q"), exprs.get("Q"), lineno)
        if loaded is not None:
            self.loaded = loaded
            if self.offset != -1 and self.offset != loaded:
                self.offset = (
                    f"tool {loaded} loaded at line {lineno} while the length offset of tool "
                    f"{self.offset} stays in effect: the programmed point is neither tip (G43 "
                    "after the tool change)"
                )
        for g in block.gcodes:
            if g == "49":
                self.offset = -1
            elif g == "43":
                if "H" in words or "H" in exprs:
                    tool = _tool_number(words.get("H"), exprs.get("H"), lineno)
                elif isinstance(self.loaded, str):
                    tool = f"G43 at line {lineno} without H: {self.loaded}"
                else:
                    tool = self.loaded
                self.offset = -1 if tool == 0 else tool
            elif g in ("43.1", "43.2"):
                self.offset = (
                    f"G{g} at line {lineno}: a tool length offset from words, not a cell tool"
                )
        changes = self.moves.tool_changes
        row = len(self.moves)
        if not changes or changes[-1][1] != self.offset:
            if changes and changes[-1][0] == row:
                changes.pop()
            changes.append((row, self.offset))

    def _rotary(self, block: _Line) -> bool:
        """Take the block's A/B/C/U/V/W (NaN when from an expression); True if it has any."""
        written = not _ROTARY_SET.isdisjoint(block.words)
        computed = not _ROTARY_SET.isdisjoint(block.exprs)
        if not (written or computed):
            return False
        rotary = dict(self.state.rotary)  # a new dict: moves share the one in effect when read
        turned = self.state.turned  # offset by G92/G52: not the tool's orientation
        for letter in ROTARY:
            if letter in block.words:
                rotary[letter] = math.nan if letter in turned else block.words[letter].value
            elif letter in block.exprs:
                rotary[letter] = math.nan
        self.state.rotary = rotary
        return True

    def _add(
        self, move: tuple, reason: str, end: list[float], written, cycle=False, r_mm=math.nan
    ) -> None:
        """Store ``move`` (line, column, motion, target, words) with its reason (or "not known"
        for a NaN target), ending at ``end``; ``cycle``: a canned-cycle hole (2: the first of a
        run of cycle blocks), whose R plane is ``r_mm`` (absolute mm)."""
        t = move[3]
        if not reason and (t[0] != t[0] or t[1] != t[1] or t[2] != t[2]):  # NaN: unknown
            missing = ",".join(k for i, k in enumerate(AXES) if math.isnan(t[i]))
            reason = f"{missing} not known here (no absolute value since the start)"
        state = self.state
        index = len(self.moves)
        self.moves.add(*move[:3], state.pos, t, move[4], reason, end, state, cycle, r_mm)
        for i, k in enumerate(AXES):
            if k in written:
                state.setter[i] = index
        state.pos = end

    def _straight(self, lineno, column, axis_words, block, why, polar) -> None:
        s, exprs = self.state, block.exprs
        target = list(s.pos)
        for i, k in enumerate(AXES):
            word = axis_words.get(k)
            if word is not None:
                value = word.value * s.scale
                target[i] = s.pos[i] + value if s.incremental else value
            elif k in exprs:
                target[i] = math.nan
        written = set(axis_words) | set(exprs)
        alone = ""
        if polar or not _POLAR_SET.isdisjoint(exprs):
            target[0], target[1], alone = self._polar_xy(polar, exprs, lineno)
            written |= {"X", "Y"}
            if polar:
                self.moves.polar[len(self.moves)] = (polar.get("@"), polar.get("^"))
        move = (lineno, column, "G" + s.motion, tuple(target), axis_words)
        reason = why or s.frame_reason() or s.unknown_motion
        if s.motion == "80":
            reason = reason or "axis words with G80 (no motion mode)"
            target = [math.nan] * 3
        elif s.motion in ("2", "3"):
            arc, arc_why = arc_of(block, s.plane, s.arc_absolute, lineno, s.motion == "2")
            reason = reason or arc_why
            self.moves.arcs[len(self.moves)] = arc
        elif s.unknown_motion:
            target = [math.nan] * 3  # where an unknown motion ends is not known either
        self._add(move, reason or alone, target, written)

    def _polar_xy(self, polar: dict[str, Word], exprs, lineno: int) -> tuple[float, float, str]:
        """X, Y (mm) a polar move reaches, as LinuxCNC reads ``@`` (radius) and ``^`` (angle,
        degrees) about the program origin: under G90 the words written, the tool's own radius or
        angle for the one not written; under G91 the tool's radius and angle plus the words.
        The third item says why it is not corrected ("" when it can be): with one word, the
        other is where the tool is."""
        if not _POLAR_SET.isdisjoint(exprs):
            return math.nan, math.nan, ""  # the expression's reason is the move's
        s = self.state
        r = polar["@"].value * s.scale if "@" in polar else None
        a = polar["^"].value if "^" in polar else None
        alone = ""
        if r is None or a is None:
            given, other = ("^", "radius") if r is None else ("@", "angle")
            alone = (
                f"polar {given} without {'@' if r is None else '^'} (line {lineno}): its {other} "
                "is where the tool is, not corrected"
            )
        return (*polar_xy(s.pos, r, a, s.incremental), alone)

    def _cycle(self, lineno, column, axis_words, words, exprs, why) -> None:
        """A canned-cycle block: its (first) hole. The cycle's axis is Z in G17, Y in G18, X in
        G19 (its word the depth, R a level on it), the hole's position the other two axes (as
        LinuxCNC reads them). Under G91 those two are increments from where the tool is
        (repeated L times), R from the initial level and the depth from R."""
        s = self.state
        axis = CYCLE_AXIS[s.plane]
        depth = AXES[axis]
        if depth in axis_words:
            s.cycle_z = axis_words[depth].value * s.scale
        elif depth in exprs:
            s.cycle_z = math.nan
        move_words = dict(axis_words)
        if "R" in words:
            s.cycle_r = words["R"].value * s.scale
            move_words["R"] = words["R"]
        elif "R" in exprs:
            s.cycle_r = math.nan
        repeats = 1
        reason = why or s.frame_reason()
        polar = not _POLAR_SET.isdisjoint(words) or not _POLAR_SET.isdisjoint(exprs)
        if polar:
            if axis != 2:
                reason = reason or (
                    f"polar words in a canned cycle in G{s.plane} (line {lineno}): not read"
                )
            elif s.incremental:  # each hole turns about the origin from the one before
                reason = reason or (
                    f"G91 canned cycle with polar words (line {lineno}): its holes are read, not "
                    "corrected"
                )
            elif "@" not in words or "^" not in words:
                given = "@" if "@" in words else "^"
                reason = reason or (
                    f"polar {given} alone in a canned cycle (line {lineno}): the other is where "
                    "the tool is, not corrected"
                )
            self.moves.polar[len(self.moves)] = (words.get("@"), words.get("^"))
        if "L" in words:
            count = words["L"].value
            if count > MAX_REPEATS:
                reason = reason or (
                    f"canned cycle L{words['L'].literal}: more than {MAX_REPEATS} repeats, not read"
                )
            elif count >= 1 and count == int(count):
                repeats = int(count)
            else:
                reason = reason or f"canned cycle L{words['L'].literal}: not a repeat count"
        if "L" in exprs:
            reason = reason or f"canned cycle {exprs['L']}: the repeat count is not known"
        repeat_k = s.motion != "87" and ("K" in words or "K" in exprs)
        if repeat_k:  # Fanuc-like controls repeat the cycle K times; RS274NGC rejects K here
            reason = reason or (
                f"canned cycle G{s.motion} with a K word (line {lineno}): K is no word of "
                "this cycle in RS274NGC and a repeat count on Fanuc-like controls, so its holes "
                "are not known"
            )
        step = [0.0, 0.0, 0.0]  # the increment of each repeat (G91), 0 on the cycle's axis
        first = list(s.pos)
        for i, k in enumerate(AXES):
            if i == axis:
                continue
            if k in axis_words:
                value = axis_words[k].value * s.scale
                step[i] = value if s.incremental else 0.0
                first[i] = s.pos[i] + value if s.incremental else value
            elif k in exprs:
                first[i] = step[i] = math.nan
        if polar:  # each repeat under G91 turns and stretches about the origin again
            radius = words["@"].value * s.scale if "@" in words else None
            angle = words["^"].value if "^" in words else None
            if _POLAR_SET.isdisjoint(exprs) and axis == 2:
                first[:2] = polar_xy(s.pos, radius, angle, s.incremental)
            else:
                first[0] = first[1] = math.nan
        first_of_run = s.cycle_il is None
        if first_of_run:
            s.cycle_il = s.pos[axis]
        r_level = s.cycle_il + s.cycle_r if s.incremental else s.cycle_r
        bottom = r_level + s.cycle_z if s.incremental else s.cycle_z
        first[axis] = bottom
        if math.isnan(s.cycle_r) or math.isnan(s.cycle_z):
            reason = reason or f"canned cycle without an R plane or {depth} depth"
        clear = r_level if s.retract == "G99" else max(s.cycle_il, r_level)
        last = [first[i] + (repeats - 1) * step[i] for i in range(3)]
        if polar and s.incremental and axis == 2:
            last[:2] = polar_xy(first, radius, angle, True, repeats - 1)
        if repeat_k or "L" in exprs or ("L" in words and repeats == 1 and words["L"].value != 1):
            repeats = 0  # not known: under G91 neither is where its holes end
            if s.incremental:
                last = [math.nan] * 3
        last[axis] = clear
        if repeats != 1:
            self.moves.repeats[len(self.moves)] = repeats
        move = (lineno, column, "G" + s.motion, tuple(first), move_words)
        written = set(axis_words) | set(exprs) | ({"X", "Y", depth} if polar else {depth})
        cycle = 2 if first_of_run else 1
        self._add(move, reason, last, written, cycle=cycle, r_mm=r_level)


def polar_xy(
    pos, radius: float | None, angle: float | None, incremental: bool, times: int = 1
) -> tuple[float, float]:
    """Where a polar move ends, X, Y mm, from the tool at ``pos`` (X, Y mm, program frame), as
    LinuxCNC reads ``@`` (``radius``, mm) and ``^`` (``angle``, degrees; None: not written)
    about the program origin: under G90 the values written, the tool's own radius or angle for
    one not written; under G91 the tool's radius and angle plus the values written, ``times``
    over (a G91 cycle's repeats; 0: where it starts)."""
    x, y = pos[0], pos[1]
    r, a = math.hypot(x, y), math.degrees(math.atan2(y, x))
    if incremental:
        step = radius or 0.0
        if times > 1 and r + times * step < 0:  # the radius turns negative on the way: each flips
            for _ in range(times):
                x, y = polar_xy((x, y), radius, angle, True)
            return x, y
        r, a = r + times * step, a + times * (angle or 0.0)
    else:
        r = r if radius is None else radius
        a = a if angle is None else angle
    turn = math.radians(a)
    return r * math.cos(turn), r * math.sin(turn)


def _expression_reason(block: _Line, lineno: int) -> str:
    """Why a position word's parameter or expression is not decidable before run time ("":
    every one is)."""
    used = [k for k in block.exprs if k in _POSITION_LETTERS]
    if not used:
        return ""
    k = used[0]
    return f"{block.exprs[k]} uses a parameter or an expression: {block.why[k]} (line {lineno})"


def parse_gcode(text: str, path: str | os.PathLike[str] | None = None) -> list[GcodeMove]:
    """Every move of an RS274NGC program, in order (see the module docstring for the rules)."""
    moves = gcode_moves(text, path)
    return [moves.move(i) for i in range(len(moves))]


def gcode_moves(text: str, path: str | os.PathLike[str] | None = None) -> GcodeMoves:
    """The moves of ``parse_gcode`` as columns.

    Text with ``\\n`` line endings is read a chunk of lines at a time, each distinct shape of line
    matched once (``_shapes``, ``_Shapes``): runs of plain lines are taken in bulk
    (``_Reader.plain_run``), every other line by the line reader (``_Reader.line``). Text
    without ``\\n`` (one line, or lone ``\\r`` endings) is read by the line reader alone. Both
    give what the line reader gives for every line (tests/test_gcode_bulk.py)."""
    path = None if path is None else os.fspath(path)
    check_text(text, path)
    reader = _Reader(path, text)
    if "\n" not in text:
        offset = 0
        for lineno, raw in enumerate(split_lines(text), start=1):
            reader.line(raw, lineno, offset)
            offset += len(raw) + 1
        return reader.moves.finish()
    start, lineno = 0, 1
    while True:
        stop = text.find("\n", min(start + _CHUNK, len(text)))
        stop = len(text) if stop < 0 else stop + 1
        lineno = _chunk(text, start, stop, lineno, reader)
        if stop == len(text):
            return reader.moves.finish()
        start = stop


def _chunk(text: str, start: int, stop: int, lineno: int, reader: _Reader) -> int:
    """Read the whole lines of ``text[start:stop]`` (line ``lineno`` first); the next line's
    number."""
    chunk = text[start:stop]
    try:
        data = chunk.encode("latin-1")
    except UnicodeEncodeError:  # a str not read from a file
        data = None
    text_part = data if data is not None else chunk.encode("latin-1", "replace")
    buf = np.frombuffer(text_part, np.uint8)
    newlines = np.flatnonzero(buf == 10)
    count = len(newlines) + (0 if chunk.endswith("\n") and stop < len(text) else 1)
    shape = reader.shapes.ids(_shapes(chunk, data, count))
    packed = reader.shapes.codes[shape]
    retract, motion = packed // 1000, packed % 1000 - 2
    begins = np.concatenate(([0], newlines + 1))[:count]
    ends = np.append(newlines, len(chunk))[:count]
    plain = motion > -2
    at = np.flatnonzero(plain)
    if len(at):
        spans = reader.shapes.spans[shape[at]]  # in the line: in the chunk
        spans = np.where(spans >= 0, spans + begins[at, None, None], -1)
        values = np.full((len(at), 4), np.nan)
        written = spans[:, :, 0] >= 0
        decimals = np.full((len(at), 4), -1)
        values[written], decimals[written] = literal_values(
            buf, spans[:, :, 0][written], spans[:, :, 1][written]
        )
        finite = ~np.isinf(values).any(axis=1)
        if finite.any():  # each of these lines is a move (or an error): its X, Y, Z decimals
            reader.moves.places = max(reader.moves.places, int(decimals[finite, :3].max()))
        spans = np.where(spans >= 0, spans + start, -1)  # offsets in the text
        retract, motion = retract[at], motion[at]
        plain[at[~finite]] = False  # a literal beyond the float range: the line reader says where
    begins, ends = begins + start, ends + start

    def read_lines(lo: int, hi: int) -> None:
        """Lines lo..hi-1 of the chunk by the line reader."""
        for k, a, b in zip(
            range(lo, hi), begins[lo:hi].tolist(), ends[lo:hi].tolist(), strict=True
        ):
            reader.line(text[a:b], lineno + k, a)

    runs = np.flatnonzero(np.diff(plain, prepend=False, append=False)).reshape(-1, 2)
    done = 0
    for lo, hi in runs.tolist():
        read_lines(done, lo)
        a, b = np.searchsorted(at, (lo, hi))
        run = _PlainRun(
            lineno + lo, begins[lo:hi], spans[a:b], values[a:b], retract[a:b], motion[a:b]
        )
        k = lo
        while k < hi:
            fast, slow = reader.plain_run(run.part(k - lo))
            read_lines(k + fast, k + fast + slow)
            k += fast + slow
        done = hi
    read_lines(done, count)
    return lineno + count
