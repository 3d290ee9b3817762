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
import math
import re
from dataclasses import dataclass, field

import numpy as np

from accugrid.codegen.program_text import (
    MIN_PLACES_MM,
    check_text,
    number_text,
    precision,
)
from accugrid.codegen.program_text import (
    splice as splice_text,
)
from accugrid.codegen.rewrite import (
    CORRECTED,
    Options,
    Result,
    Rows,
    correct_points,
    partial_check,
)
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import comment_text
from accugrid.kinematics.configuration import kuka_status

__all__ = ["RapidPositions", "add_header", "kuka_status_of", "rewrite_rapid", "scan", "splice"]

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
    """One robtarget: ``name`` (``p``, ``p{3}``, ``inline MoveL``), its statement's ``line``,
    the offsets (start, end) of its x, y, z numbers, x, y, z and the quaternion [q1..q4] as
    written (``values``, 7), the cfx of its confdata, why its own numbers keep it from
    correction (``own``), its frame
    (0 robot, 1 the cell's work object, -1 none yet), the reason it is left as it is (""
    when placeable) and whether a motion goes to it or to a position derived from it
    (``commanded``)."""

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
    """What ``scan`` found: every robtarget (``targets``) and the rows of the report that are
    no robtarget (``others``: never-corrected data, joint targets of moves); columns as
    ``codegen.plugin.Positions`` (``xyz`` program frame mm, ``frame`` 0 robot / 1 work object)."""

    path: str
    targets: list[_Target]
    others: list[tuple[int, str, str]] = field(default_factory=list)  # line, name, reason

    @property
    def xyz(self) -> np.ndarray:
        nan = [math.nan] * 3
        return np.array([t.values[:3] or nan for t in self.targets], dtype=float).reshape(-1, 3)

    @property
    def line(self) -> np.ndarray:
        return np.array([t.line for t in self.targets], dtype=np.int64)

    @property
    def name(self) -> list[str]:
        return [t.name for t in self.targets]

    @property
    def reason(self) -> list[str]:
        return [t.reason for t in self.targets]

    @property
    def frame(self) -> np.ndarray:
        return np.array([t.frame for t in self.targets], dtype=np.int64)

    @property
    def tool(self) -> np.ndarray:
        """(N,) the tool number each robtarget is moved with (-1: the cell's)."""
        return np.array([t.tool for t in self.targets], dtype=np.int64)

    @property
    def commanded(self) -> np.ndarray:
        """(N,) bool: a motion goes to the robtarget or to a position derived from it."""
        return np.array([t.commanded for t in self.targets], dtype=bool)


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
    tool; flange_T_tool (4, 4) mm), None: the cell's tool (``rapid.tool``) alone."""
    check_text(text, path)
    masked = _masked(text)
    newlines = [m.start() for m in re.finditer("\n", text)]

    def where(offset: int) -> tuple[int, int]:
        line = bisect.bisect_left(newlines, offset)
        return line + 1, offset - (newlines[line - 1] if line else -1)

    statements, start = [], 0
    for end in (m.start() for m in re.finditer(";", masked)):
        if masked[start:end].strip():
            statements.append((start, masked[start:end]))
        start = end + 1
    found = RapidPositions(path, [])
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
            found.others.append((line, name, f"{kind}: {_WHY_NEVER[kind]}, never corrected"))
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
        rest = _ROBTARGET.sub("", value)
        if not literals or rest.strip(" \t\r\n[],"):
            targets.append(_Target(name, line, [], [], reason="its value is not literal numbers"))
            continue
        array = m.group(4) is not None
        for j, lit in enumerate(literals, 1):
            targets.append(
                _literal(
                    f"{name}{{{j}}}" if array else name, lit, value_at, where, ignore_external_axes
                )
            )
    uses: dict[str, list[_Use]] = {n: [] for n in declared}
    assigned: set[str] = set()
    moves: list[tuple[int, list[str], bool]] = []  # line, lower-case names or "#k", circular
    wobj, tool = section.wobj.lower(), section.tool.lower()
    routines = {m.group(1).lower() for m in _PROC.finditer(_MASK.sub("", text))}
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
            used_wobj = optional.get("wobj", "wobj0").lower()
            used_tool = positional[move[1]][1] if len(positional) > move[1] else ""
            if tools is not None:
                tool_no = tools.get(used_tool.lower(), (-1,))[0]
                if used_tool.lower() not in tools:
                    why = (
                        f"moved with tool {used_tool or '?'} at line {line}, which the cell does "
                        "not declare (rapid.tool, the names of tool_data)"
                    )
            elif used_tool.lower() != tool:
                why = (
                    f"moved with tool {used_tool or '?'} at line {line}, not the cell's "
                    f"(rapid.tool {section.tool}): the grid holds for the cell's TCP"
                )
            elif used_wobj != "wobj0" and used_wobj != wobj:
                why = (
                    f"moved in work object {optional['wobj']} at line {line}, not the cell's "
                    f"(rapid.wobj {section.wobj}) nor wobj0"
                )
            frame = 0 if used_wobj == "wobj0" else 1
            for what in (used_tool.lower(), used_wobj):
                why = why or (f"{unfit[what]} (line {line})" if what in unfit else "")
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
                    moves[-1][1].append(f"#{len(found.targets)}")
                    found.targets.append(target)
        elif instr and instr.group(1).lower() == "moveabsj":
            found.others.append((line, "MoveAbsJ", "joint target of MoveAbsJ, never corrected"))
        if not declared or s in decl_of and not stmt.count(":="):
            continue
        called = instr.group(1) if instr and not assign else ""
        motion = bool(move or _MOTION.fullmatch(called) or called.lower() in routines)
        for ref in _NAME.finditer(stmt):
            key = ref.group(1).lower()
            if key not in declared:
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
            uses[key].append(use)
    _arc_starts(moves, uses, found)
    for key, targets in declared.items():
        for j, target in enumerate(targets, 1):
            mine = [u for u in uses[key] if u.index is None or u.index == j]
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
        found.targets.extend(targets)
    for target in found.targets:
        target.reason = target.reason or target.own
        if not target.reason and target.frame == 1 and wobj in assigned:
            target.reason = f"work object {section.wobj} is changed at run time"
    found.targets.sort(key=lambda t: (t.line, t.spans[0][0] if t.spans else 0))
    return found


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


def _arc_starts(moves, uses, found: RapidPositions) -> None:
    """The target of the move before a circular move is the arc's start: left alone."""
    for (line, _, circular), (prev_line, prev, _) in zip(moves[1:], moves, strict=False):
        if not circular:
            continue
        why = f"the start of the circular move at line {line}: arcs are not corrected"
        for key in prev:
            if key.startswith("#"):
                target = found.targets[int(key[1:])]
                target.reason = target.reason or why
            else:
                uses[key].append(_Use(prev_line, -1, why))


def splice(text: str, positions: RapidPositions, new_xyz: np.ndarray, opts: Options) -> bytearray:
    """``text`` with the x, y, z of every robtarget whose row of ``new_xyz`` (N, 3) mm is not
    NaN replaced (``opts.decimals``, else the robtarget's own decimals, at least 0.01 mm)."""
    return splice_text(text, _edits(text, positions, new_xyz, opts))


def _edits(text: str, positions: RapidPositions, new_xyz: np.ndarray, opts: Options) -> list:
    """(start, end, new text) of the x, y, z of every robtarget with a new position, in the
    order of the targets (three per target)."""
    edits = []
    for target, new in zip(positions.targets, np.asarray(new_xyz).tolist(), strict=True):
        if math.isnan(new[0]):
            continue
        old = [text[a:b] for a, b in target.spans[:3]]
        places = opts.decimals if opts.decimals is not None else precision(old, MIN_PLACES_MM)
        for (a, b), old_text, old_value, value in zip(
            target.spans[:3], old, target.values[:3], new, strict=True
        ):
            edits.append((a, b, number_text(old_text, old_value, value, places)))
    return edits


def rewrite_rapid(texts: dict[str, str], opts: Options, section) -> Result:
    """Rewrite RAPID modules (path -> latin-1 text) in the frames of the cell's RAPID
    ``section``; InputError where a module has nothing that can be placed."""
    data, parts = {}, []
    frames = np.stack([np.eye(4), section.robot_T_wobj])
    tools = None
    if opts.tool_data is not None:
        tools = {name: (n, opts.tool_data[n]) for name, n in (opts.tool_names or {}).items()}
        tools[section.tool.lower()] = (-1, opts.tool_data[opts.tool_number])
    for path, text in texts.items():
        found = scan(path, text, section, opts.ignore_external_axes, tools)
        rows = Rows(
            [path],
            np.zeros(len(found.targets), np.int64),
            found.line,
            found.name,
            found.reason,
            found.xyz,
        )
        rows.commanded[:] = found.commanded  # partial_check counts those left uncorrected
        rows.tool[:] = found.tool
        new = np.full((len(found.targets), 3), np.nan)
        at = np.flatnonzero(~np.fromiter(map(bool, found.reason), bool, len(found.targets)))
        if at.size:
            t = frames[found.frame[at]]
            xyz = found.xyz[at]
            robot = np.einsum("nij,nj->ni", t[:, :3, :3], xyz) + t[:, :3, 3]
            quats = np.array([found.targets[i].values[3:7] for i in at.tolist()])
            rotations = t[:, :3, :3] @ _matrices(quats)
            cfx = np.array([found.targets[i].cfx for i in at.tolist()])
            corrected = correct_points(robot, rows, at, opts, rotations, status=kuka_status_of(cfx))
            back = np.einsum("nji,nj->ni", t[:, :3, :3], corrected - robot)  # R^T e
            done = np.flatnonzero(np.isfinite(corrected[:, 0]))
            new[at[done]] = xyz[done] + back[done]
            rows.status[at[done]] = CORRECTED
        edits = _edits(text, found, new, opts)
        data[path] = splice_text(text, edits)
        done = ~np.isnan(new[:, 0])
        rows.new[done] = np.array([float(e[2]) for e in edits]).reshape(-1, 3)
        rows.rounding_mm[done] = np.linalg.norm(rows.new[done] - new[done], axis=1)
        if not found.targets and not opts.allow_partial:
            what = f"; {len(found.others)} data left as they are" if found.others else ""
            raise InputError(f"no robtarget in this module: nothing to correct{what}", path, 1)
        partial_check(rows, opts)  # the policy's job rule, over the robtargets
        parts += [rows, _other_rows(path, found)]
    return Result(data, Rows.concat(parts))


def kuka_status_of(cfx: np.ndarray) -> np.ndarray:
    """The KUKA Status (N,) of the arm configuration a confdata's cfx (N,) names (-1 where cfx
    is not 0..7), so that the policy holds each robtarget against the Status its grid was
    measured in. cfx = 4 * (wrist centre behind axis 1) + 2 * (behind the lower arm) + (axis 5
    negative); behind axis 1 is the shoulder flag (Status bit 0), axis 5 negative the wrist
    (bit 2), and behind the lower arm is the elbow flag (bit 1) negated within the IRB 6700's
    axis 3 range (``kinematics.configuration``)."""
    cfx = np.asarray(cfx, dtype=np.int64)
    status = kuka_status((cfx >> 2) & 1, 1 - ((cfx >> 1) & 1), cfx & 1)
    return np.where((cfx >= 0) & (cfx <= 7), status, -1)


def _matrices(quats: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of RAPID quaternions [q1, q2, q3, q4] (N, 4), normalised."""
    from scipy.spatial.transform import Rotation

    q = np.asarray(quats, dtype=float).reshape(-1, 4)
    return Rotation.from_quat(np.roll(q, -1, axis=1)).as_matrix().reshape(-1, 3, 3)


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
    newline = "\r\n" if "\r\n" in text else "\n"
    block = "".join(f"    ! {comment_text(line, 200)}{newline}" for line in lines)
    m = _MODULE_LINE.search(text)
    if m is None:
        return block + text
    end = text.find("\n", m.end())
    at = len(text) if end < 0 else end + 1
    if end < 0:
        block = newline + block
    return text[:at] + block + text[at:]
