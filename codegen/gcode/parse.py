"""RS274NGC reader: every move of a G-code program with its absolute target and the exact span of
each number, for pre-flight correction.

Follows the modal state a CAM post relies on: motion mode (G0/G1/G2/G3, canned cycles G73/G81-G89
with G98/G99 and sticky Z and R), G90/G91 (incremental targets are made absolute), G20/G21
(targets in mm; ``scale`` converts back), G17/G18/G19, N-numbers, ``( )`` and ``;`` comments,
words in any order and case, with or without spaces. G54 is the program frame (the power-on
default); anything that moves the program frame in a way the cell does not describe (G55-G59.3,
G92, G52, G10) or leaves the position unknown (G28/G30, G53, expressions, O-word control flow)
makes the affected moves carry a ``reason`` instead of being guessed.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from typing import NamedTuple

from accugrid.codegen.program_text import check_text, decimals_of, split_lines
from accugrid.kinematics.errors import InputError

_WORD_RE = re.compile(r"([A-Za-z])\s*([-+]?(?:\d+\.?\d*|\.\d+))")
_COMMENT_RE = re.compile(r"\([^)]*\)|;.*", re.S)
_LINE_RE = re.compile(r"(?:\s*[A-Za-z]\s*[-+]?(?:\d+\.?\d*|\.\d+))*\s*")
_EXPR_RE = re.compile(r"([A-Za-z])\s*([#\[])")
_OWORD_RE = re.compile(
    r"\s*[Oo]\s*(?:\d+|<[^>]*>)\s*(sub|endsub|if|elseif|else|endif|while|endwhile|do|call|"
    r"return|repeat|endrepeat|break|continue)\b",
    re.I,
)
_OWORD_ANY_RE = re.compile(r"^" + _OWORD_RE.pattern, re.I | re.M)  # a line _OWORD_RE may match
AXES = "XYZ"
ROTARY = "ABCUVW"
CYCLES = frozenset(("73", "81", "82", "83", "84", "85", "86", "87", "88", "89"))
MOTION_MODES = frozenset(("0", "1", "2", "3", "80")) | CYCLES
INCH_MM = 25.4
_ROTARY_SET = frozenset(ROTARY)
_KEPT = frozenset(AXES + ROTARY + "R")  # letters whose Word a move needs
_NONMODAL = frozenset("4 10 28 28.1 30 30.1 52 53 92 92.1 92.2 92.3".split())
_PARAMETER_CODES = frozenset("4 10 28.1 30.1 52 92 92.1 92.2 92.3".split())
_G_NAMES = {float(g): g for g in (str(i) for i in range(100))}
_new_word = tuple.__new__  # a Word without the NamedTuple constructor's Python frame


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
    motion: str  # "G0", "G1", "G2", "G3", "G81", ..., "G28", "G53"
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
    end: tuple[float, float, float] = (math.nan, math.nan, math.nan)  # where the tool ends
    is_cycle: bool = False  # a canned-cycle hole (G73, G81-G89)

    x = property(lambda self: self.target[0])
    y = property(lambda self: self.target[1])
    z = property(lambda self: self.target[2])
    a = property(lambda self: self.rotary.get("A"))

    @property
    def is_arc(self) -> bool:
        return self.motion in ("G2", "G3")


def _refuse(line: str, path: str | None, lineno: int) -> None:
    """InputError at the first thing in a (comment-free) line that is not a word."""
    rest = _WORD_RE.sub(lambda m: " " * len(m.group(0)), line)
    col = len(rest) - len(rest.lstrip())
    bad = rest.split()[0] if rest.split() else line.strip()
    raise InputError(f"cannot read {bad!r} as a G-code word", path, lineno, col + 1)


def _blank_comments(line: str, path: str | None, lineno: int) -> str:
    """The line with ``( )`` comments and the ``;`` tail replaced by spaces (offsets kept)."""
    if "(" not in line and ";" not in line and ")" not in line:
        return line
    if ";" not in line and line.count("(") == 1 and line.count(")") == 1:
        start, end = line.find("("), line.find(")") + 1
        if start < end:  # one ( ) comment: what the regex below does, without a callback
            return line[:start] + " " * (end - start) + line[end:]
    out = _COMMENT_RE.sub(_spaces, line)
    if "(" in out:
        raise InputError("unclosed '(' comment", path, lineno, out.index("(") + 1)
    if ")" in out:
        raise InputError("')' without '('", path, lineno, out.index(")") + 1)
    return out


def _spaces(m: re.Match) -> str:
    return " " * (m.end() - m.start())


def _gnum(value: float) -> str:
    """G-code number as a key: 1 -> "1", 91.1 -> "91.1"."""
    return f"{value:.1f}".rstrip("0").rstrip(".")


def parse_gcode(text: str, path: str | os.PathLike[str] | None = None) -> list[GcodeMove]:
    """Every move of an RS274NGC program, in order (see the module docstring for the rules)."""
    path = None if path is None else os.fspath(path)
    check_text(text, path)
    moves: list[GcodeMove] = []
    pos = [math.nan, math.nan, math.nan]  # current absolute position, mm, program frame
    setter: list[int | None] = [None, None, None]
    rotary: dict[str, float] = {}
    motion = "0"
    incremental = False
    scale = 1.0
    plane = "17"
    retract = "G98"
    cycle_z = math.nan
    cycle_r = math.nan
    frame_reason = ""  # set while the program frame is not the cell's
    flow_reason = ""
    comp_reason = ""
    offset = 0
    # whole-text checks first: most programs have no O-words, block deletes or expressions,
    # and then no line needs those per-line regex calls
    owords = _OWORD_ANY_RE.search(text) is not None
    slashes = "/" in text
    exprs = "#" in text or "[" in text
    expr = None
    for lineno, raw in enumerate(split_lines(text), start=1):
        line_offset = offset
        offset += len(raw) + 1
        stripped = raw.strip()
        if not stripped or stripped.startswith("%"):
            continue
        if owords and _OWORD_RE.match(raw):
            flow_reason = flow_reason or f"O-word control flow from line {lineno}"
            continue
        line = _blank_comments(raw, path, lineno)
        if slashes and line.lstrip().startswith("/"):
            line = line.replace("/", " ", 1)
        if exprs:
            expr = _EXPR_RE.search(line)
        if expr is None and _LINE_RE.fullmatch(line) is None:
            _refuse(line, path, lineno)
        words: dict[str, Word | None] = {}
        gwords: list[float] = []
        for m in _WORD_RE.finditer(line):
            letter, number = m.group(1, 2)
            letter = letter.upper()
            if letter == "G":
                gwords.append(float(number))
                continue
            if letter in words and letter != "M":
                raise InputError(f"word {letter} given twice", path, lineno, m.start(2) + 1)
            if letter in _KEPT:
                start, end = m.span(2)
                words[letter] = _new_word(
                    Word, (letter, float(number), line_offset + start, line_offset + end, number)
                )
            else:  # N, F, S, M, T, ...: only seen (a second one is an error), never a position
                words[letter] = None
        gcodes = [_G_NAMES.get(v) or _gnum(v) for v in gwords] if gwords else gwords
        axis_words = {k: words[k] for k in AXES if k in words}
        for g in gcodes:
            if g in MOTION_MODES:
                motion = g
            elif g == "20":
                scale = INCH_MM
            elif g == "21":
                scale = 1.0
            elif g == "90":
                incremental = False
            elif g == "91":
                incremental = True
            elif g in ("17", "18", "19"):
                plane = g
            elif g in ("98", "99"):
                retract = "G" + g
            elif g == "54":
                frame_reason = "" if not frame_reason.startswith("work offset") else ""
            elif g in ("55", "56", "57", "58", "59", "59.1", "59.2", "59.3"):
                frame_reason = f"work offset G{g} (line {lineno}): the cell gives only G54"
            elif g in ("92", "52", "92.3"):
                frame_reason = f"G{g} offset (line {lineno}) moves the program frame"
            elif g in ("92.1", "92.2"):
                frame_reason = ""
            elif g == "10":
                frame_reason = f"G10 (line {lineno}) changes the work offsets"
            elif g in ("41", "42", "41.1", "42.1"):
                comp_reason = f"cutter compensation G{g} (line {lineno}) offsets the path"
            elif g == "40":
                comp_reason = ""
            elif g in ("68", "51"):
                frame_reason = f"G{g} (line {lineno}) rotates or scales the program"
        has_rotary = not _ROTARY_SET.isdisjoint(words)
        if has_rotary:  # a new dict: moves share the one in effect when they were read
            rotary = dict(rotary)
            for letter in ROTARY:
                if letter in words:
                    rotary[letter] = words[letter].value
        nonmodal = [g for g in gcodes if g in _NONMODAL] if gcodes else gcodes
        if nonmodal and nonmodal[0] in _PARAMETER_CODES:
            continue  # the axis words are parameters, not a move
        if expr is not None and expr.group(1).upper() in AXES + ROTARY:
            flow_reason = flow_reason or f"expression {expr.group(0)}.. at line {lineno}"
            pos = [math.nan] * 3
            continue
        if not axis_words and not has_rotary:
            continue
        column = min(w.start for w in axis_words.values()) - line_offset + 1 if axis_words else 1
        start = tuple(pos)
        setters = tuple(setter)
        index = len(moves)
        if nonmodal:  # G28/G30 (via a point) or G53 (machine coordinates)
            name = "G" + nonmodal[0]
            moves.append(
                GcodeMove(
                    path,
                    lineno,
                    column,
                    name,
                    start,
                    (math.nan,) * 3,
                    axis_words,
                    incremental,
                    scale,
                    f"{name}: a machine-coordinate or home move",
                    rotary,
                    setters,
                )
            )
            pos = [math.nan] * 3
            setter = [index] * 3
            continue
        target = list(pos)
        relative = incremental and motion not in CYCLES
        for i, k in enumerate(AXES):
            word = axis_words.get(k)
            if word is not None:
                target[i] = pos[i] + word.value * scale if relative else word.value * scale
        reason = flow_reason or frame_reason or comp_reason
        move = GcodeMove(
            path,
            lineno,
            column,
            "G" + motion,
            start,
            tuple(target),
            axis_words,
            incremental,
            scale,
            "",
            rotary,
            setters,
        )
        if motion == "80":
            move.reason = "axis words with G80 (no motion mode)"
            pos = [math.nan] * 3
        elif motion in CYCLES:
            move.is_cycle = True
            if "Z" in axis_words:
                cycle_z = axis_words["Z"].value * scale
            if "R" in words:
                cycle_r = words["R"].value * scale
                move.words = dict(axis_words, R=words["R"])
            move.retract = retract
            move.r_mm = cycle_r
            bottom = [target[0], target[1], cycle_z]
            move.target = tuple(bottom)
            if incremental:
                reason = reason or "canned cycle in G91 (incremental cycle words)"
            elif plane != "17":
                reason = reason or f"canned cycle in plane G{plane} (only G17 is read)"
            elif math.isnan(cycle_r) or math.isnan(cycle_z):
                reason = reason or "canned cycle without an R plane or Z depth"
            clear = cycle_r if retract == "G99" else max(pos[2], cycle_r)
            pos = [target[0], target[1], clear if not incremental else math.nan]
        else:
            if motion in ("2", "3"):
                reason = reason or (
                    f"arc G{motion}: its end point and centre would have to move together"
                )
            pos = target
        t = move.target
        if not reason and (t[0] != t[0] or t[1] != t[1] or t[2] != t[2]):  # NaN: unknown
            missing = ",".join(k for i, k in enumerate(AXES) if math.isnan(t[i]))
            reason = f"{missing} not known here (no absolute value since the start)"
        if reason and not move.reason:
            move.reason = reason
        move.end = tuple(pos)
        if "X" in axis_words:
            setter[0] = index
        if "Y" in axis_words:
            setter[1] = index
        if "Z" in axis_words or move.is_cycle:
            setter[2] = index
        moves.append(move)
    return moves
