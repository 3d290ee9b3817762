"""Pre-flight rewrite of an ABB RAPID module (``.mod``, ``.modx``, ``.prg``, ``.sys``); see
``codegen.rewrite`` for what a rewrite is.

One linear scan (``scan``) reads the module into statements: comments (``!``) and strings are
masked, routine and module headers, ``%%%`` blocks, records and the words that open or close a
block (``IF .. THEN``, ``FOR .. DO``, ``ENDPROC`` ...) are set aside, the rest split at ``;``. A
statement with unbalanced ``[ ]`` or ``( )`` is an InputError at its line and column.

Positions are robtargets ``[[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[eax_a,..,eax_f]]``: those
declared (``CONST``/``PERS``/``VAR``, with ``LOCAL``/``TASK``, arrays ``{n}`` too, on one line or
many) and those written inline as the target of a move. A robtarget is corrected only when every
use is the target of a linear or joint move (MoveL, MoveJ, their DO/AO/GO/Sync forms, TriggL,
TriggJ) with the cell's tool (``rapid.tool``) in the cell's work object (``rapid.wobj``, whose user
frame is the cell's base) or in ``wobj0`` (no ``\\WObj``: the robot's base frame, taken as the
world frame). Left as they are, with the reason in the report: robtargets that are an operand of
``Offs``/``RelTool`` or read anywhere else, reassigned at run time (``p := ..``, ``p.trans := ..``,
``t{i} := ..``), moved in another work object or with another tool, in a work object changed at
run time, points of circular moves and the target before one (the arc's start), used by an
instruction accugrid does not know, not used, without literal numbers, with a quaternion that is
not unit, or with external axes in use (unless ``--ignore-external-axes``); and every
``tooldata``, ``wobjdata``, ``jointtarget``, ``loaddata``, ``pose`` (never corrected). Only the
x, y, z numbers of a corrected robtarget change (the input's decimals, at least 0.01 mm);
orientation, confdata and every other byte stay. Whether a placed robtarget is corrected is
the correction policy's verdict (``codegen.rewrite.correct_points``), and so is the job's rule
(``partial_check``: a robtarget the policy does not correct, one a motion commands that cannot
be placed, or a module where none is corrected, fails the job unless ``--allow-partial``). A
robtarget is commanded when a motion goes to it or to a position derived from it: inline in a
move, or named in a move, in an instruction named like one (``ArcL``, ``SearchL``,
``MyMoveL``) or a call of a routine of the module (a custom move), or as an ``Offs``/``RelTool``
operand there; never-corrected data and robtargets no motion names do not count. A module
without robtargets is an InputError too.
"""

from __future__ import annotations

import bisect
import re
from dataclasses import dataclass, field
from itertools import repeat

import numpy as np

from accugrid.codegen.plugin_types import CORRECTED, Options, Rows, Scan
from accugrid.codegen.program_text import (
    MIN_PLACES_MM,
    check_text,
    comment_block,
    distinct_ints,
    precision,
)
from accugrid.codegen.rapid.configuration import read_configuration
from accugrid.codegen.rapid.rigid import RigidModule, read_rigid
from accugrid.codegen.splice import ByteSplicer, texts_of
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import fixed_bytes

__all__ = [
    "RapidPlacement",
    "RapidPositions",
    "add_header",
    "code_of_cfx",
    "scan",
    "scan_positions",
    "splice",
    "splice_positions",
]

QUATERNION_TOL = 1e-3  # |  |q| - 1 | beyond this: not an orientation the controller accepts
UNUSED_AXIS = 8.9e9  # 9E+09 marks an external axis not in use
NEVER = ("tooldata", "wobjdata", "jointtarget", "loaddata", "pose")
_WHY_NEVER = {
    "tooldata": "a tool (TCP and load)",
    "wobjdata": "a work object (frames)",
    "jointtarget": "joint angles",
    "loaddata": "a payload",
    "pose": "a frame or displacement",
}
# move instruction -> (indices of its point arguments, index of its tool argument, circular)
_MOVES = {
    **{m: ((0,), 3, False) for m in ("movel", "movej", "moveldo", "movejdo", "movelao")},
    **{m: ((0,), 3, False) for m in ("movejao", "movelgo", "movejgo", "movelsync", "movejsync")},
    **{m: ((0,), 4, False) for m in ("triggl", "triggj")},
    **{m: ((0, 1), 4, True) for m in ("movec", "movecdo", "movecao", "movecgo", "movecsync")},
    "triggc": ((0, 1), 5, True),
}
_NUM = r"([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"


def _group(count: int) -> str:
    return r"\[\s*" + r"\s*,\s*".join([_NUM] * count) + r"\s*\]"


_ROBTARGET = re.compile(
    r"\[\s*" + r"\s*,\s*".join([_group(3), _group(4), _group(4), _group(6)]) + r"\s*\]"
)
_MASK = re.compile(r'"[^"\r\n]*"|![^\r\n]*')
# on the lower-cased text: a cheap look at the first letter, then the word start, then the words
_SET_ASIDE = re.compile(
    r"(?=[%bcdefilmprtuw])(?<!\w)(?:"
    r"%%%[\s\S]*?%%%"
    r"|module\s+\w+\s*(?:\([^)]*\))?"
    r"|(?:local\s+)?(?:proc|trap|func\s+\w+)\s+\w+\s*\([^)]*\)"
    r"|record\b[\s\S]*?\bendrecord\b"
    r"|(?:if|elseif|while|for)\b[^;]*?\b(?:then|do)\b"
    r"|test\b[^\r\n;]*|case\b[^:;]*:|default\s*:"
    r"|error\b(?:\s*\([^)]*\))?"
    r"|(?:endproc|endfunc|endtrap|endmodule|endif|endfor|endwhile|endtest|else|backward|undo)\b"
    r")"
)
_DECL = re.compile(
    r"\s*(?:(?:LOCAL|TASK)\s+)*(CONST|PERS|VAR)\s+(\w+)\s+(\w+)\s*(\{[^}]*\})?\s*(?::=([\s\S]*))?\Z",
    re.I,
)
_ASSIGN = re.compile(r"\s*([A-Za-z]\w*)\s*(?:\{[^}]*\})?\s*(?:\.\s*\w+\s*)*:=")
_INSTR = re.compile(r"\s*([A-Za-z]\w*)")
_NAME = re.compile(r"(?<![.\w])([A-Za-z]\w*)(?:\s*\{\s*(\d+)\s*\}|\s*\{[^}]*\})?")  # p{3}: 3
# a motion: the moves above, an instruction named like a move (ArcL, SearchL, MyMoveL) or a
# routine of the module (a custom move: PROC Drill(robtarget p) .. MoveL p ..)
_MOTION = re.compile(r"\w*move\w*|(?:arc|trigg|search)\w*", re.I)
_PROC = re.compile(r"\bPROC\s+(\w+)\s*\(", re.I)
_OFFSET_BEFORE = re.compile(r"\b(Offs|RelTool)\s*\(\s*\Z", re.I)
_MODULE_LINE = re.compile(r"^[ \t]*MODULE\b.*$", re.I | re.M)


@dataclass
class _Target:
    """One robtarget the statement reader found: ``name`` (``p``, ``p{3}``, ``inline MoveL``),
    its statement's ``line``, the offsets (start, end) of its x, y, z numbers, x, y, z and the
    quaternion [q1..q4] as written (``values``, 7), the cfx of its confdata, why its own numbers
    keep it from correction (``own``), its frame (0 robot, 1 the cell's work object, -1 none
    yet), the reason it is left as it is ("" when placeable) and whether a motion goes to it or
    to a position derived from it (``commanded``)."""

    name: str
    line: int
    spans: list[tuple[int, int]]
    values: list[float]
    cfx: int = -1
    own: str = ""
    frame: int = -1
    reason: str = ""
    commanded: bool = False
    tool: int = -1  # the tool number it is moved with (-1: the cell's, rapid.tool)


@dataclass
class RapidPositions:
    """What ``scan`` found: every robtarget as columns, in the order of the module (as
    ``codegen.plugin.Positions``: ``xyz`` (N, 3) mm as written, NaN where not literal, ``line``
    (N,), ``name``, ``reason`` ("" where it can be placed), ``frame`` (N,) 0 robot / 1 work
    object / -1 none), ``commanded`` (N,) bool (a motion goes to it or to a position derived
    from it), ``quat`` (N, 4) [q1..q4], ``cfx`` (N,), ``spans`` (N, 3, 2) start/end offsets of
    its x, y, z literals (-1: none), ``places`` (N,) the decimals a corrected x, y, z gets (its
    literals' most, at least 0.01 mm); and the rows of the report that are no robtarget
    (``others``: never-corrected data, joint targets of moves: line, name, reason)."""

    path: str
    xyz: np.ndarray
    quat: np.ndarray
    cfx: np.ndarray
    spans: np.ndarray
    places: np.ndarray
    line: np.ndarray
    name: list[str]
    reason: list[str]
    frame: np.ndarray
    commanded: np.ndarray
    tool: np.ndarray
    others: list[tuple[int, str, str]] = field(default_factory=list)


@dataclass
class _Use:
    line: int
    frame: int  # 0 robot, 1 the cell's work object, -1 not placeable
    reason: str
    index: int | None = None  # array element (1-based), None: every element
    moved: bool = False  # in a motion instruction: the robot goes to it or to a derived position
    tool: int = -1  # the tool number it is moved with (-1: the cell's)


def _masked(text: str) -> str:
    """``text`` with comments and strings blanked, then everything that is no statement set
    aside (the same length: offsets stay)."""
    out = _MASK.sub(lambda m: " " * len(m.group()), text)
    pieces, last = [], 0
    for m in _SET_ASIDE.finditer(out.lower()):  # latin-1 lower-cases one character to one
        pieces += (out[last : m.start()], re.sub(r"[^\r\n]", " ", m.group()))
        last = m.end()
    pieces.append(out[last:])
    return "".join(pieces)


def _check_brackets(stmt: str, start: int, path: str, where) -> None:
    """InputError at the first bracket of ``stmt`` (at offset ``start``) that is not closed or
    closes none."""
    if stmt.count("[") == stmt.count("]") and stmt.count("(") == stmt.count(")"):
        return  # the usual statement: no walk over its characters
    depth = {"[": 0, "(": 0}
    pairs = {"]": "[", ")": "("}
    for k, ch in enumerate(stmt):
        if ch in depth:
            depth[ch] += 1
        elif ch in pairs:
            depth[pairs[ch]] -= 1
            if depth[pairs[ch]] < 0:
                raise InputError(f"unbalanced {ch!r} in this statement", path, *where(start + k))
    for ch, d in depth.items():
        if d:
            raise InputError(
                f"unbalanced {ch!r}: {d} not closed in this statement",
                path,
                *where(start + len(stmt) - 1),
            )


def _split_top(text: str, separator: str, at: int = 0) -> list[tuple[int, str]]:
    """``text[at:]`` cut at each ``separator`` outside brackets: (offset in ``text``, piece)."""
    if "[" not in text and "(" not in text:  # the usual move: no walk over its characters
        pieces, start = [], at
        for piece in text[at:].split(separator):
            pieces.append((start, piece))
            start += len(piece) + 1
        return pieces
    pieces, depth, start = [], 0, at
    for k in range(at, len(text)):
        ch = text[k]
        if ch in "[(":
            depth += 1
        elif ch in "])":
            depth -= 1
        elif ch == separator and depth == 0:
            pieces.append((start, text[start:k]))
            start = k + 1
    pieces.append((start, text[start:]))
    return pieces


def _arguments(stmt: str, at: int) -> tuple[list[tuple[int, str]], dict[str, str]]:
    """The positional arguments (offset in ``stmt``, text stripped) of an instruction whose
    arguments start at ``at``, and its optional ones (``\\WObj:=w``: lower-case name -> value)."""
    positional, optional = [], {}
    for offset, piece in _split_top(stmt, ",", at):
        (_, first), *switches = _split_top(piece, "\\")
        if first.strip():
            lead = len(first) - len(first.lstrip())
            positional.append((offset + lead, first.strip()))
        for _, switch in switches:
            name, _, value = switch.partition(":=")
            optional[name.strip().lower()] = value.strip()
    return positional, optional


def scan(
    path: str,
    text: str,
    section,
    ignore_external_axes: bool = False,
    tools: dict[str, tuple[int, np.ndarray]] | None = None,
) -> RapidPositions:
    """The robtargets of a RAPID module and the reason each is left alone ("" when it can be
    corrected), in the frames of ``section`` (``codegen.rapid.section.RapidSection``);
    ``ignore_external_axes``: external axes in use do not keep a robtarget from correction;
    ``tools``: the tooldata names a move may use (lower case) -> (tool number, -1: the cell's
    tool; flange_T_tool (4, 4) mm), None: the cell's tool (``rapid.tool``) alone.

    The lines in the layout ``codegen.rapid.rigid`` reads are read with array operations and the
    rest statement by statement; where one of those lines does not stand alone as a statement
    (inside a ``%%%`` block, a record, after an unfinished statement) or shares a name with the
    words around it, the whole module is read statement by statement."""
    check_text(text, path)
    rigid = read_rigid(text)
    if rigid is not None and rigid.rigid.any():
        found = _scan(path, text, section, ignore_external_axes, rigid, tools)
        if found is not None:
            return found
    return _scan(path, text, section, ignore_external_axes, None, tools)


# words that start a piece the statement reader sets aside: a module whose rigid lines hold one
# as a name is read statement by statement
_KEYWORDS = frozenset(
    "module local proc trap func record endrecord if elseif while for then do test case default"
    " error endproc endfunc endtrap endmodule endif endfor endwhile endtest else backward"
    " undo".split()
)


_BLOCK = 1 << 16  # robtargets spliced at a time
_BLANK = np.array([chr(c).isspace() for c in range(256)])  # what str.strip() strips


class _Rigid:
    """The rigid lines of a module (``codegen.rapid.rigid.RigidModule``) and the text the
    statement reader reads instead (``rest``): each run of rigid lines, from the first one's
    text to the last one's, replaced by one ``;`` (the other statements, their lines' text and
    columns stay), with the offsets of those ``;`` (``marks``); ``to_text`` maps an offset in
    ``rest`` back to the module's text and ``line`` a line of ``rest`` to the module's."""

    def __init__(self, text: str, r: RigidModule) -> None:
        self.r = r
        lines = np.flatnonzero(r.rigid)
        run = np.concatenate([[True], np.diff(lines) != 1])  # the first line of each run
        first, last = lines[run], lines[np.append(run[1:], True)]
        starts, ends = r.line_start[first], r.line_end[last]
        cuts = np.concatenate([[0], np.stack([starts, ends], axis=1).ravel(), [len(text)]])
        pieces = map(text.__getitem__, map(slice, cuts[0::2].tolist(), cuts[1::2].tolist()))
        self.rest = ";".join(pieces)
        removed = np.cumsum(ends - starts - 1)  # each run's text became one character
        self.marks = starts - np.concatenate([[0], removed[:-1]]).astype(np.int64)
        self.removed = np.concatenate([[0], removed]).astype(np.int64)
        gone = np.cumsum(last - first)  # lines of the module no longer in ``rest``
        self.mark_lines = (first - np.concatenate([[0], gone[:-1]])).tolist()  # 0-based
        self.gone = [0, *gone.tolist()]
        self.keys = _lower(r.names)
        self.decl_of = dict(zip(self.keys, range(len(self.keys)), strict=True))
        # the same names in the same order (as RobotStudio writes them): lower-cased once
        self.move_keys = self.keys if r.targets == r.names else _lower(r.targets)
        self.move_lines = r.move_line + 1
        if len(self.decl_of) == len(self.keys) and self.move_keys == self.keys:
            self.move_decl = np.arange(len(self.keys))  # the k-th move to the k-th robtarget
        else:  # the declaration each move names (-1: none)
            self.move_decl = np.fromiter(
                map(self.decl_of.get, self.move_keys, repeat(-1)), np.int64, len(self.move_keys)
            )
        self.handed = np.zeros(len(self.keys), bool)  # declarations judged by the statements
        self.tools = None  # the module's tools (``scan``)

    def to_text(self, offsets: np.ndarray) -> np.ndarray:
        """Offsets (any shape) in ``rest``, none at a mark, as offsets in the module's text."""
        return offsets + self.removed[np.searchsorted(self.marks, offsets)]

    def line(self, line: int) -> int:
        """The module's line (1-based) of the line ``line`` (1-based) of ``rest``, none a
        mark's."""
        return line + self.gone[bisect.bisect_left(self.mark_lines, line - 1)]

    def problem(self, known: set[str]) -> bool:
        """Whether the module must be read statement by statement: a robtarget declared twice,
        or a name of the rigid lines that is a keyword, or a robtarget (``known``: the lower-case
        names the statements declare) named like a word of a rigid line (a tool, a speed ..)."""
        words = {"const", "pers", "var", "robtarget"} if self.keys else set()
        if self.move_keys:
            words |= {"movel", "movej", "wobj"}
        for rest in self.r.rests:
            words |= {w.lower() for w in rest or () if w}
        return bool(
            len(self.decl_of) < len(self.keys)
            or not _KEYWORDS.isdisjoint(self.keys)
            or not _KEYWORDS.isdisjoint(self.move_keys)
            or words & _KEYWORDS
            or known & words
            or any(k in self.decl_of for k in known)
        )

    def alone(self, chars: np.ndarray) -> bool:
        """Whether every rigid line stands alone as a statement: its mark is still a ``;`` in the
        masked ``rest`` (``chars``, its bytes: no ``%%%`` block, record or header covers it) and
        only blanks separate it from the ``;`` before it."""
        if (chars[self.marks] != 59).any():
            return False
        solid = np.flatnonzero(~_BLANK[chars])
        before = np.searchsorted(solid, self.marks) - 1
        return bool(((before < 0) | (chars[solid[np.maximum(before, 0)]] == 59)).all())

    def why(self, m: int, section, unfit) -> tuple[int, str, int]:
        """``_move_frame`` of the rigid move m (with the module's ``tools``)."""
        speed_zone_tool_wobj = self.r.rests[self.r.rest[m]]
        tool, wobj = speed_zone_tool_wobj[2:]
        return _move_frame(tool, wobj, int(self.move_lines[m]), section, unfit, self.tools)

    def merge_moves(self, moves: list, known: set[str]) -> list:
        """The statement reader's moves and the rigid ones in the order of the module when a
        circular move needs the move before it, else the statement reader's alone (``known``:
        the robtargets the statements declare)."""
        if not any(circular for _, _, circular in moves):
            return moves
        keys = self.move_keys
        mine = [
            (line, [keys[m]] if keys[m] in known or keys[m] in self.decl_of else [], False)
            for m, line in enumerate(self.move_lines.tolist())
        ]
        return sorted(moves + mine, key=lambda move: move[0])

    def hand_over(self, declared, uses, moves, section, unfit, ignore_external_axes) -> None:
        """Give the statement reader each rigid declaration used in a statement or at the start
        of an arc (``moves`` as merged) as a ``_Target``, and each rigid move to a robtarget it
        judges as a ``_Use``, among the others in the order of the module."""
        handed = {k for k in uses if k in self.decl_of}
        for (_, _, circular), (_, prev, _) in zip(moves[1:], moves, strict=False):
            if circular:
                handed |= {k for k in prev if k in self.decl_of}
        r = self.r
        for key in handed:
            d = self.decl_of[key]
            self.handed[d] = True
            tail = r.tails[r.tail[d]].tolist()
            values = [*r.xyz[d].tolist(), *tail[:4]]
            own = _own_reason([*values, *tail[4:]], ignore_external_axes)
            spans = [tuple(span) for span in r.span[d].tolist()]
            line = int(r.decl_line[d]) + 1
            declared[key] = [_Target(r.names[d], line, spans, values, int(tail[7]), own)]
        added = set()
        handed = np.append(self.handed, False)  # [-1]: not declared on a rigid line
        maybe = (self.move_decl < 0) | handed[self.move_decl]
        for m in np.flatnonzero(maybe).tolist():  # to a robtarget of the statements or handed
            key = self.move_keys[m]
            if key in declared:
                frame, why, tool = self.why(m, section, unfit)
                use = _Use(int(self.move_lines[m]), -1 if why else frame, why, None, True, tool)
                uses.setdefault(key, []).append(use)
                added.add(key)
        for key in added:
            uses[key].sort(key=lambda u: u.line)  # stable: a statement's uses keep their order

    def judged(self, section, unfit, ignore_external_axes) -> RapidPositions:
        """The robtargets declared on rigid lines and moved to by rigid moves alone, judged as
        the statement reader judges them (``_scan``), with array operations."""
        r = self.r
        keep = np.flatnonzero(~self.handed)
        k = len(r.names)
        judged = [
            _move_frame(g[2], g[3], 0, section, unfit, self.tools) if g else (-1, "", -1)
            for g in r.rests
        ]
        rest_frame = np.array([f for f, _, _ in judged] or [0], np.int64)[r.rest]
        rest_bad = np.array([bool(w) for _, w, _ in judged] or [False], bool)[r.rest]
        rest_tool = np.array([t for _, _, t in judged] or [-1], np.int64)[r.rest]
        m = np.flatnonzero(self.move_decl >= 0)
        m = m[~self.handed[self.move_decl[m]]]
        d = self.move_decl[m]
        uses = np.bincount(d, minlength=k)
        in_wobj = np.bincount(d, weights=rest_frame[m] == 1, minlength=k).astype(np.int64)
        first_bad = np.full(k, len(self.move_keys), np.int64)
        bad = m[rest_bad[m]]
        np.minimum.at(first_bad, self.move_decl[bad], bad)
        frame = np.where(in_wobj > 0, 1, 0)
        mixed = (in_wobj > 0) & (in_wobj < uses)
        low, high = np.full(k, 1 << 40), np.full(k, -(1 << 40))
        np.minimum.at(low, d, rest_tool[m])
        np.maximum.at(high, d, rest_tool[m])
        tools = (low < high) & ~mixed & (first_bad == len(self.move_keys))  # different tools
        placed = (uses > 0) & (first_bad == len(self.move_keys)) & ~mixed & ~tools
        frame = np.where(placed, frame, -1)
        tool = np.where(placed, low, -1)
        own_of_tail = [
            _own_reason([0.0, 0.0, 0.0, *tail], ignore_external_axes) for tail in r.tails.tolist()
        ]
        reason = [own_of_tail[t] for t in r.tail.tolist()]
        for i in np.flatnonzero(mixed & (first_bad == len(self.move_keys))).tolist():
            reason[i] = "used in the robot frame and in the work object"
        for i in np.flatnonzero(tools).tolist():
            lines = ", ".join(map(str, self.move_lines[m[d == i]].tolist()))
            reason[i] = f"moved with different tools (lines {lines})"
        for i in np.flatnonzero(first_bad < len(self.move_keys)).tolist():
            reason[i] = self.why(int(first_bad[i]), section, unfit)[1]
        for i in np.flatnonzero(uses == 0).tolist():
            reason[i] = "not used by any move"
        names = r.names
        if len(keep) < k:
            names = [r.names[i] for i in keep.tolist()]
            reason = [reason[i] for i in keep.tolist()]
        else:
            keep = slice(None)  # every one: views, no copies
        tail = r.tail[keep]
        return RapidPositions(
            "",
            r.xyz[keep],
            r.tails[:, :4][tail],
            r.tails[:, 7].astype(np.int64)[tail],
            r.span[keep],
            np.maximum(r.places[keep], MIN_PLACES_MM),
            r.decl_line[keep] + 1,
            names,
            reason,
            frame[keep],
            uses[keep] > 0,
            tool[keep],
        )


def _lower(names: list[str]) -> list[str]:
    """The names (no LF in any) lower-cased, in one call."""
    return "\n".join(names).lower().split("\n") if names else []


def _statements(masked: str, chars: np.ndarray, marks: np.ndarray | None) -> list:
    """(offset, text) of every statement of the masked text (its bytes ``chars``) that is not
    blank: the text before each ``;``, those ending at a mark of a rigid line (``marks``,
    sorted; blank by ``_Rigid.alone``) left out."""
    semis = np.flatnonzero(chars == 59)
    starts = np.concatenate([[0], semis[:-1] + 1]).astype(np.int64)
    if marks is not None and len(marks):
        j = np.minimum(np.searchsorted(marks, semis), len(marks) - 1)
        keep = marks[j] != semis
        starts, semis = starts[keep], semis[keep]
    pieces = map(masked.__getitem__, map(slice, starts.tolist(), semis.tolist()))
    return [(a, piece) for a, piece in zip(starts.tolist(), pieces, strict=True) if piece.strip()]


def _scan(path, text, section, ignore_external_axes, r, tools=None) -> RapidPositions | None:
    """``scan`` with the rigid lines ``r`` (None: none); None when those do not stand alone."""
    rigid = _Rigid(text, r) if r is not None else None
    if rigid is not None:
        rigid.tools = tools
    rest = rigid.rest if rigid is not None else text
    masked = _masked(rest)
    chars = np.frombuffer(masked.encode("latin-1"), np.uint8)
    if rigid is not None and not rigid.alone(chars):
        return None
    newlines = np.flatnonzero(chars == 10).tolist()  # masking keeps every line ending

    def where(offset: int) -> tuple[int, int]:
        line = bisect.bisect_left(newlines, offset)
        column = offset - (newlines[line - 1] if line else -1)
        return (line + 1 if rigid is None else rigid.line(line + 1)), column

    statements = _statements(masked, chars, rigid.marks if rigid is not None else None)
    inline: list[_Target] = []
    others: list[tuple[int, str, str]] = []
    declared: dict[str, list[_Target]] = {}  # lower-case robtarget name -> its targets
    data: dict[str, str] = {}  # lower-case tooldata / wobjdata name -> its value (masked)
    decl_of: dict[int, str] = {}  # statement -> the robtarget it declares
    for s, (at, stmt) in enumerate(statements):
        _check_brackets(stmt, at, path, where)
        m = _DECL.match(stmt)
        if not m:
            continue
        kind, name = m.group(2).lower(), m.group(3)
        line = where(at + m.start(2))[0]
        if kind in NEVER:
            others.append((line, name, f"{kind}: {_WHY_NEVER[kind]}, never corrected"))
        if kind in ("tooldata", "wobjdata") and m.group(5) is not None:
            data[name.lower()] = m.group(5)
        if kind != "robtarget":
            continue
        decl_of[s] = name.lower()
        targets = declared.setdefault(name.lower(), [])
        if m.group(5) is None:
            targets.append(_Target(name, line, [], [], reason="declared without a value"))
            continue
        value_at = at + m.start(5)
        value = m.group(5)
        literals = list(_ROBTARGET.finditer(value))
        rest_value = _ROBTARGET.sub("", value)
        if not literals or rest_value.strip(" \t\r\n[],"):
            targets.append(_Target(name, line, [], [], reason="its value is not literal numbers"))
            continue
        array = m.group(4) is not None
        for j, lit in enumerate(literals, 1):
            targets.append(
                _literal(
                    f"{name}{{{j}}}" if array else name, lit, value_at, where, ignore_external_axes
                )
            )
    known = set(declared)  # the lower-case names of the robtargets the statements declare
    rigid_keys = rigid.decl_of if rigid is not None else {}  # and those of the rigid lines
    if rigid is not None and rigid.problem(known):
        return None
    uses: dict[str, list[_Use]] = {}
    assigned: set[str] = set()
    moves: list[tuple[int, list[str], bool]] = []  # line, lower-case names or "#k", circular
    wobj = section.wobj.lower()
    routines = {m.group(1).lower() for m in _PROC.finditer(_MASK.sub("", rest))}
    unfit = _unfit_frames(data, section, tools)
    for s, (at, stmt) in enumerate(statements):
        line = where(at + len(stmt) - len(stmt.lstrip()))[0]
        assign = _ASSIGN.match(stmt)
        if assign:
            assigned.add(assign.group(1).lower())
        instr = _INSTR.match(stmt)
        move = _MOVES.get(instr.group(1).lower()) if instr and not assign else None
        positional, optional = _arguments(stmt, instr.end()) if move else ([], {})
        frame, why, tool_no = 0, "", -1
        if move:
            used_tool = positional[move[1]][1] if len(positional) > move[1] else ""
            wobj_text = optional.get("wobj")
            frame, why, tool_no = _move_frame(used_tool, wobj_text, line, section, unfit, tools)
            if move[2]:
                why = why or f"a point of the circular move at line {line}: arcs are not corrected"
            points = [positional[i] for i in move[0] if i < len(positional)]
            moves.append((line, [], move[2]))
            for offset, arg in points:
                lit = _ROBTARGET.fullmatch(arg)
                if lit:
                    target = _literal(
                        f"inline {instr.group(1)}",
                        lit,
                        at + offset,
                        where,
                        ignore_external_axes,
                        line,
                    )
                    target.frame, target.reason = (frame, why) if why else (frame, "")
                    target.commanded, target.tool = True, tool_no
                    moves[-1][1].append(f"#{len(inline)}")
                    inline.append(target)
        elif instr and instr.group(1).lower() == "moveabsj":
            others.append((line, "MoveAbsJ", "joint target of MoveAbsJ, never corrected"))
        if not (known or rigid_keys) or s in decl_of and not stmt.count(":="):
            continue
        called = instr.group(1) if instr and not assign else ""
        motion = bool(move or _MOTION.fullmatch(called) or called.lower() in routines)
        for ref in _NAME.finditer(stmt):
            key = ref.group(1).lower()
            if key not in known and key not in rigid_keys:
                continue
            if decl_of.get(s) == key and ref.start() < stmt.find(":="):
                continue  # the name in its own declaration
            index = int(ref.group(2)) if ref.group(2) else None  # None: any element
            before = stmt[: ref.start()]
            offset_fn = _OFFSET_BEFORE.search(before)
            arg = next((a for o, a in positional if o == ref.start()), None) if move else None
            if assign and assign.group(1).lower() == key:
                use = _Use(line, -1, f"reassigned at run time at line {line}", index)
            elif offset_fn:
                use = _Use(
                    line,
                    -1,
                    f"operand of {offset_fn.group(1)}(...) at line {line}: the offset point is "
                    "not a drilling position",
                    index,
                )
            elif (
                move
                and arg is not None
                and arg == ref.group(0).strip()
                and any(positional[i][0] == ref.start() for i in move[0] if i < len(positional))
            ):
                use = _Use(line, -1 if why else frame, why, index, tool=tool_no)
                moves[-1][1].append(key)
            else:
                what = instr.group(1) if instr and not assign else "an expression"
                use = _Use(
                    line, -1, f"used by {what} at line {line}, not a move accugrid places", index
                )
            use.moved = motion
            uses.setdefault(key, []).append(use)
    targets = inline + [t for ts in declared.values() for t in ts]
    if rigid is not None:  # the statements' offsets in the module's text
        for target in targets:
            if target.spans:
                target.spans = [tuple(s) for s in rigid.to_text(np.array(target.spans)).tolist()]
        moves = rigid.merge_moves(moves, known)
        rigid.hand_over(declared, uses, moves, section, unfit, ignore_external_axes)
    _arc_starts(moves, uses, inline)
    for key, targets in declared.items():
        for j, target in enumerate(targets, 1):
            mine = [u for u in uses.get(key, ()) if u.index is None or u.index == j]
            target.commanded = any(u.moved for u in mine)
            if target.reason:
                continue
            if not mine:
                target.reason = "not used by any move"
                continue
            bad = next((u for u in mine if u.frame < 0), None)
            if bad is not None:
                target.reason = bad.reason
            elif len({u.frame for u in mine}) > 1:
                target.reason = "used in the robot frame and in the work object"
            elif len({u.tool for u in mine}) > 1:
                lines = ", ".join(str(u.line) for u in mine)
                target.reason = f"moved with different tools (lines {lines})"
            else:
                target.frame, target.tool = mine[0].frame, mine[0].tool
    parts = [_columns(inline + [t for ts in declared.values() for t in ts], text)]
    if rigid is not None:
        parts.append(rigid.judged(section, unfit, ignore_external_axes))
    found = _joined(path, parts)
    if wobj in assigned:
        why = f"work object {section.wobj} is changed at run time"
        for i in np.flatnonzero(found.frame == 1).tolist():
            found.reason[i] = found.reason[i] or why
    found.others = others
    return found


def _columns(targets: list[_Target], text: str) -> RapidPositions:
    """The statement reader's robtargets as columns (spans in ``text``), their reason the
    reason found else their own (``_Target.own``)."""
    n = len(targets)
    xyz, quat = np.full((n, 3), np.nan), np.full((n, 4), np.nan)
    spans, places = np.full((n, 3, 2), -1, np.int64), np.full(n, -1, np.int64)
    for i, t in enumerate(targets):
        if t.spans:
            xyz[i], quat[i] = t.values[:3], t.values[3:7]
            spans[i] = t.spans[:3]
            places[i] = precision([text[a:b] for a, b in t.spans[:3]], MIN_PLACES_MM)
    return RapidPositions(
        "",
        xyz,
        quat,
        np.array([t.cfx for t in targets], np.int64),
        spans,
        places,
        np.array([t.line for t in targets], np.int64),
        [t.name for t in targets],
        [t.reason or t.own for t in targets],
        np.array([t.frame for t in targets], np.int64),
        np.array([t.commanded for t in targets], bool),
        np.array([t.tool for t in targets], np.int64),
    )


def _joined(path: str, parts: list[RapidPositions]) -> RapidPositions:
    """The robtargets of ``parts`` in the order of the module (line, then offset; stable)."""
    parts = [p for p in parts if len(p.name)] or parts[:1]
    keys = ("xyz", "quat", "cfx", "spans", "places", "line", "frame", "commanded", "tool")
    if len(parts) == 1:
        columns = {key: getattr(parts[0], key) for key in keys}
        names, reasons = parts[0].name, parts[0].reason
    else:
        columns = {key: np.concatenate([getattr(p, key) for p in parts]) for key in keys}
        names = [n for p in parts for n in p.name]
        reasons = [w for p in parts for w in p.reason]
    start = np.maximum(columns["spans"][:, 0, 0], 0)  # none: 0
    if (np.diff((columns["line"] << 40) | start) < 0).any():  # offsets below 2**40
        order = np.lexsort((start, columns["line"]))
        columns = {key: value[order] for key, value in columns.items()}
        names = [names[i] for i in order.tolist()]
        reasons = [reasons[i] for i in order.tolist()]
    return RapidPositions(path, name=names, reason=reasons, **columns)


def _move_frame(tool_text: str, wobj_text: str | None, line: int, section, unfit, tools) -> tuple:
    """(frame, why, tool) of a linear or joint move with the tool argument ``tool_text`` in the
    work object ``wobj_text`` (None: no ``\\WObj``) at ``line``: frame 0 robot / 1 the cell's
    work object; why "" when its targets can be placed; the tool's number (-1: the cell's) among
    ``tools`` (``scan``)."""
    used_wobj = ("wobj0" if wobj_text is None else wobj_text).lower()
    why, tool_no = "", -1
    if tools is not None:
        tool_no = tools.get(tool_text.lower(), (-1,))[0]
        if tool_text.lower() not in tools:
            why = (
                f"moved with tool {tool_text or '?'} at line {line}, which the cell does "
                "not declare (rapid.tool, the names of tool_data)"
            )
    elif tool_text.lower() != section.tool.lower():
        why = (
            f"moved with tool {tool_text or '?'} at line {line}, not the cell's "
            f"(rapid.tool {section.tool}): the grid holds for the cell's TCP"
        )
    elif used_wobj != "wobj0" and used_wobj != section.wobj.lower():
        why = (
            f"moved in work object {wobj_text} at line {line}, not the cell's "
            f"(rapid.wobj {section.wobj}) nor wobj0"
        )
    for what in (tool_text.lower(), used_wobj):
        why = why or (f"{unfit[what]} (line {line})" if what in unfit else "")
    return (0 if used_wobj == "wobj0" else 1), why, tool_no


def _unfit_frames(data: dict[str, str], section, tools: dict | None) -> dict[str, str]:
    """The cell's tools and work object where the module declares them otherwise than the cell
    (a stationary tool, a tool with another TCP than the cell's ``tools``, a work object the
    robot holds, another user or object frame): lower-case name -> why its moves are not
    placed."""
    out = {}
    wobj = section.wobj.lower()
    names = {section.tool.lower(): section.tool}
    for tool in tools or names:
        if data.get(tool, "[TRUE").lstrip(" \t\r\n[").upper().startswith("FALSE"):
            name = names.get(tool, tool)
            out[tool] = f"tool {name} is stationary (robhold FALSE): the robot holds the part"
        elif tools is not None and tool in data:
            numbers = [float(n) for n in re.findall(_NUM, data[tool])[:7]]
            if len(numbers) == 7 and not _same_pose(_pose(numbers), tools[tool][1]):
                out[tool] = f"the module's tooldata {tool} is not the TCP the cell gives it"
    value = data.get(wobj)
    if value is None:
        return out
    if value.lstrip(" \t\r\n[").upper().startswith("TRUE"):
        out[wobj] = f"work object {section.wobj} is held by the robot (robhold TRUE)"
        return out
    numbers = [float(n) for n in re.findall(_NUM, value.split(",", 3)[-1])]
    if len(numbers) != 14:
        return out
    robot_T_wobj = _pose(numbers[:7]) @ _pose(numbers[7:])
    if not _same_pose(robot_T_wobj, section.robot_T_wobj):
        out[wobj] = (
            f"the module's wobjdata {section.wobj} (user and object frame) is not the cell's base "
            "frame"
        )
    return out


def _pose(numbers: list[float]) -> np.ndarray:
    """RAPID [x, y, z, q1, q2, q3, q4] (mm) as a pose (4, 4) mm."""
    pose = np.eye(4)
    pose[:3, :3] = _matrices(np.array(numbers[3:7]))[0]
    pose[:3, 3] = numbers[:3]
    return pose


def _same_pose(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two poses (4, 4) mm agree within 0.01 mm and 1e-6 (rotation matrix elements)."""
    return np.allclose(a[:3, 3], b[:3, 3], rtol=0, atol=0.01) and np.allclose(
        a[:3, :3], b[:3, :3], rtol=0, atol=1e-6
    )


def _literal(name, lit, offset, where, ignore_external_axes, line=None) -> _Target:
    """The robtarget of the match ``lit`` of ``_ROBTARGET`` in text at ``offset``."""
    spans = [(offset + lit.start(g), offset + lit.end(g)) for g in (1, 2, 3)]
    numbers = [float(v) for v in lit.groups()]
    own = _own_reason(numbers, ignore_external_axes)
    line = line or where(offset + lit.start())[0]
    return _Target(name, line, spans, numbers[:7], int(numbers[10]), own)


def _own_reason(numbers: list[float], ignore_external_axes: bool) -> str:
    """Why a robtarget's own 17 numbers keep it from being corrected ("" when nothing does)."""
    q = np.array(numbers[3:7])
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > QUATERNION_TOL:
        return f"quaternion of length {norm:.6f}, not a unit quaternion: no valid orientation"
    ext = numbers[11:17]
    used = [k for k, v in enumerate(ext) if abs(v) < UNUSED_AXIS]
    if used and not ignore_external_axes:
        k = used[0]
        return (
            f"external axis eax_{'abcdef'[k]} = {ext[k]:g} in use: the cell has none "
            "(--ignore-external-axes if they move neither the robot nor the work object)"
        )
    return ""


def _arc_starts(moves, uses, inline: list[_Target]) -> None:
    """The target of the move before a circular move is the arc's start: left alone (``#k``:
    the k-th inline target)."""
    for (line, _, circular), (prev_line, prev, _) in zip(moves[1:], moves, strict=False):
        if not circular:
            continue
        why = f"the start of the circular move at line {line}: arcs are not corrected"
        for key in prev:
            if key.startswith("#"):
                target = inline[int(key[1:])]
                target.reason = target.reason or why
            else:
                uses.setdefault(key, []).append(_Use(prev_line, -1, why))


def splice(text: str, positions: RapidPositions, new_xyz: np.ndarray, opts: Options) -> bytearray:
    """``text`` with the x, y, z of every robtarget whose row of ``new_xyz`` (N, 3) mm is not
    NaN replaced (``opts.decimals``, else the robtarget's own decimals, at least 0.01 mm)."""
    return _spliced(text, positions, new_xyz, opts)[0]


def _spliced(
    text: str, positions: RapidPositions, new_xyz: np.ndarray, opts: Options
) -> tuple[bytearray, np.ndarray]:
    """``splice`` and the values the new literals read as (N, 3) mm, NaN where not replaced; a
    number whose value does not change keeps its literal. A block of robtargets at a time."""
    new_xyz = np.asarray(new_xyz, dtype=float).reshape(-1, 3)
    written = np.full(new_xyz.shape, np.nan)
    out = ByteSplicer(text)
    todo = np.flatnonzero(~np.isnan(new_xyz[:, 0]))
    for a in range(0, len(todo), _BLOCK):
        rows = todo[a : a + _BLOCK]
        places = (
            positions.places[rows] if opts.decimals is None else np.full(rows.size, opts.decimals)
        )
        flat, each = new_xyz[rows].ravel(), np.repeat(places, 3)
        blocks = []
        for p in distinct_ints(each):
            at = np.flatnonzero(each == p)
            blocks.append((at, *fixed_bytes(flat[at], p)))
        width = max(cells.shape[1] for _, cells, _ in blocks)
        cells, values = np.zeros((len(flat), width), np.uint8), np.empty(len(flat))
        for at, block, printed in blocks:  # NUL-padded on the left, as fixed_bytes pads
            cells[at, width - block.shape[1] :] = block
            values[at] = printed
        written[rows] = values.reshape(-1, 3)
        changed = values != positions.xyz[rows].ravel()
        spans = positions.spans[rows].reshape(-1, 2)[changed]
        new, lengths = texts_of(cells[changed])
        out.add(spans[:, 0], spans[:, 1], new, lengths)
    return out.finish(), written


@dataclass(frozen=True)
class RapidPlacement:
    """What places robtargets in the robot frame besides the module's text (the plug-in's
    ``placement``): the cell's RAPID ``section`` (its tool and work object) and whether
    robtargets with external axes in use are corrected (``ignore_external_axes``)."""

    section: object
    ignore_external_axes: bool = False


def scan_positions(texts: dict[str, str], opts: Options, placement: RapidPlacement) -> Scan:
    """The robtargets of RAPID modules (path -> latin-1 text) in the frames of the cell's RAPID
    section; InputError where a module has no robtarget (unless ``opts.allow_partial``)."""
    section = placement.section
    frames = np.stack([np.eye(4), section.robot_T_wobj])
    tools = None
    if opts.tool_data is not None:
        tools = {name: (n, opts.tool_data[n]) for name, n in (section.tool_names or {}).items()}
        tools[section.tool.lower()] = (-1, opts.tool_data[opts.tool_number])
    parts, others, found_all, robot, rotations, status, at = [], [], [], [], [], [], []
    start = 0
    for path, text in texts.items():
        found = scan(path, text, section, placement.ignore_external_axes, tools)
        n = len(found.name)
        if not n and not opts.allow_partial:
            what = f"; {len(found.others)} data left as they are" if found.others else ""
            raise InputError(f"no robtarget in this module: nothing to correct{what}", path, 1)
        rows = Rows([path], np.zeros(n, np.int64), found.line, found.name, found.reason, found.xyz)
        rows.commanded[:] = found.commanded  # partial_check counts those left uncorrected
        rows.tool[:] = found.tool
        mine = np.flatnonzero(~np.fromiter(map(bool, found.reason), bool, n))
        if mine.size:
            robot.append(np.empty((mine.size, 3)))
            rotations.append(np.empty((mine.size, 3, 3)))
            for a in range(0, mine.size, _BLOCK):  # (n, 4, 4) frames a block at a time
                k, b = mine[a : a + _BLOCK], slice(a, a + _BLOCK)
                t = frames[found.frame[k]]
                robot[-1][b] = np.einsum("nij,nj->ni", t[:, :3, :3], found.xyz[k]) + t[:, :3, 3]
                rotations[-1][b] = _rotations(frames, found.frame[k], found.quat[k])
            status.append(code_of_cfx(found.cfx[mine]))
            at.append(start + mine)
        parts.append(rows)
        others.append(_other_rows(path, found))
        found_all.append((text, found, start, mine))
        start += n
    return Scan(
        Rows.concat(parts),
        np.concatenate(at or [np.zeros(0, np.int64)]),
        robot[0] if len(robot) == 1 else np.concatenate(robot or [np.zeros((0, 3))]),
        rotations[0] if len(rotations) == 1 else np.concatenate(rotations or [np.zeros((0, 3, 3))]),
        np.concatenate(status or [np.zeros(0, np.int64)]),
        others=Rows.concat(others),
        state=(frames, found_all),
    )


def splice_positions(scan: Scan, corrected: np.ndarray, opts: Options) -> dict[str, bytearray]:
    """Every module's bytes with the x, y, z of its corrected robtargets (``corrected`` (M, 3)
    mm robot frame, NaN rows: not corrected) written back in their frames."""
    frames, found_all = scan.state
    rows, data, k = scan.rows, {}, 0
    for text, found, start, mine in found_all:
        new = np.full((len(found.name), 3), np.nan)
        for a in range(0, mine.size, _BLOCK):  # (n, 4, 4) frames a block at a time
            m = mine[a : a + _BLOCK]
            t = frames[found.frame[m]]
            e = corrected[k : k + m.size] - scan.robot[k : k + m.size]
            back = np.einsum("nji,nj->ni", t[:, :3, :3], e)  # R^T e
            done = np.flatnonzero(np.isfinite(e[:, 0]))
            new[m[done]] = found.xyz[m][done] + back[done]
            rows.status[start + m[done]] = CORRECTED
            k += m.size
        data[found.path], written = _spliced(text, found, new, opts)
        done = np.flatnonzero(~np.isnan(new[:, 0]))
        for a in range(0, done.size, _BLOCK):
            d = done[a : a + _BLOCK]
            rows.new[start + d] = written[d]
            rows.rounding_mm[start + d] = np.linalg.norm(written[d] - new[d], axis=1)
    return data


def code_of_cfx(cfx: np.ndarray) -> np.ndarray:
    """The configuration code (N,) of the arm configuration a confdata's cfx (N,) names
    (``configuration.read_configuration``; -1 where cfx is not 0..7), so that the policy holds each
    robtarget against the configuration its grid was measured in."""
    cfx = np.asarray(cfx, dtype=np.int64)
    confdata = np.zeros((len(cfx), 4), np.int64)
    confdata[:, 3] = cfx
    return np.where((cfx >= 0) & (cfx <= 7), read_configuration(confdata).code, -1)


def _rotations(frames: np.ndarray, frame: np.ndarray, quats: np.ndarray) -> np.ndarray:
    """Robot-frame orientations (N, 3, 3) of quaternions (N, 4) written in ``frames[frame]``
    (frames (F, 4, 4), frame (N,)): each run of rows with the same frame and quaternion (a whole
    module, mostly) computed once, for its first row."""
    first = np.ones(len(frame), bool)
    first[1:] = (frame[1:] != frame[:-1]) | (quats[1:] != quats[:-1]).any(axis=1)  # NaN: its own
    heads = np.flatnonzero(first)
    found = frames[frame[heads], :3, :3] @ _matrices(quats[heads])
    return found[np.cumsum(first) - 1]


def _matrices(quats: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of RAPID quaternions [q1, q2, q3, q4] (N, 4) (q1 the scalar),
    normalised: the operations of scipy's ``Rotation.from_quat(..).as_matrix()`` in its order,
    so the same bits, without importing ``scipy.spatial`` (a third of a rewrite's start-up)."""
    w, x, y, z = np.asarray(quats, dtype=float).reshape(-1, 4).T
    norm = np.sqrt(x * x + y * y + z * z + w * w)
    w, x, y, z = w / norm, x / norm, y / norm, z / norm
    x2, y2, z2, w2 = x * x, y * y, z * z, w * w
    xy, zw, xz, yw, yz, xw = x * y, z * w, x * z, y * w, y * z, x * w
    m = np.empty((len(w), 3, 3))
    m[:, 0] = np.stack([x2 - y2 - z2 + w2, 2 * (xy - zw), 2 * (xz + yw)], axis=1)
    m[:, 1] = np.stack([2 * (xy + zw), -x2 + y2 - z2 + w2, 2 * (yz - xw)], axis=1)
    m[:, 2] = np.stack([2 * (xz - yw), 2 * (yz + xw), -x2 - y2 + z2 + w2], axis=1)
    return m


def _other_rows(path: str, found: RapidPositions) -> Rows:
    n = len(found.others)
    return Rows(
        [path],
        np.zeros(n, np.int64),
        np.array([o[0] for o in found.others], np.int64),
        [o[1] for o in found.others],
        [o[2] for o in found.others],
        np.full((n, 3), np.nan),
    )


def add_header(text: str, lines: list[str]) -> str:
    """The module with the header as ``!`` comments right after its ``MODULE`` line (at the
    top when it has none), in the module's line ending."""
    block = comment_block(text, lines, "    ! {}")
    m = _MODULE_LINE.search(text)
    if m is None:
        return block + text
    end = text.find("\n", m.end())
    at = len(text) if end < 0 else end + 1
    if end < 0:
        block = ("\r\n" if "\r\n" in text else "\n") + block
    return text[:at] + block + text[at:]
