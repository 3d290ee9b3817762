"""The reader of FANUC TP programs in their ASCII form (``.ls``): one pass over the text into
its sections, the instructions of ``/MN`` and the positions of ``/POS``; InputError at the line
and column of what it cannot read.

- Sections: the program starts with ``/PROG``; ``/ATTR``, ``/APPL``, ``/MN``, ``/POS``, ``/END``
  follow (``/MN`` is required, ``/POS`` may be absent or empty).
- ``/MN``: numbered lines ``n:`` (the number in at most four columns: point-logic sub-lines,
  indented deeper, number themselves) numbered 1, 2, ... without a gap, as the controller keeps
  them; an unnumbered ``:`` line continues the instruction before it (a circular move's end
  point). Labels in brackets (``PR[2:ROS-I p cache]``, ``P[2:""]``) are masked, remarks (``!``)
  and disabled lines (``//``) set aside. Each instruction is read for what places a position:
  motions (``J``/``L``/``C``/``A`` to ``P[n]`` or ``PR[n]``, their options: ``Offset``,
  ``Tool_Offset``, ``INC``, ``COORD``, ``RTCP``), reads of ``P[n]`` elsewhere, frame selections
  (``UFRAME_NUM=``, ``UTOOL_NUM=``; German ``BENUTZER_NUM``, ``WKZ_NUM``) and frame assignments
  (``UFRAME[n]=``, ``UTOOL[n]=``).
- ``/POS``: entries ``P[n(:label)]{ GP1: UF : u, UT : t, [CONFIG : '..',] X = .. mm, Y, Z,
  W = .. deg, P, R [, E1 = ..] GP2: .. };``: Cartesian, joint (``J1 = .. deg``) or remote-TCP
  (``RX = ..``) positions of group 1, other groups noted. Any spacing, tabs and number spelling
  (``.094``, ``-0.000000``); ``KONFIG`` for ``CONFIG``. Text in ``/POS`` that is no such entry
  is an InputError.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from accugrid.infra.errors import InputError

__all__ = ["Instruction", "LsProgram", "Position", "read_ls"]

NUM = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?"
_SECTION = re.compile(r"^/(PROG|ATTR|APPL|MN|POS|END)\b", re.M)
_LINE = re.compile(r"[^\r\n]*(?:\r\n|\n|\r)?")
_NUMBERED = re.compile(r"([ \t]*)(\d+):")
_CONTINUED = re.compile(r"[ \t]*:")
_LABEL = re.compile(r"\[([^\]:\[]*):[^\]\[]*\]")  # [n:label] -> [n]
_MOTION = re.compile(r"\s*([JLCA])\s+(P|PR)\[([^\]]*)\]", re.I)
_TARGET = re.compile(r"\s*(P|PR)\[([^\]]*)\]", re.I)
_POINT = re.compile(r"(?<![A-Za-z_\[])P\[\s*(\d+)\s*\]")
_OFFSET = re.compile(r"\b(?:(?:Tool_|WKZ_)?Offset|VOFFSET|INC)\b", re.I)
_COORD = re.compile(r"\bCOORD\b", re.I)
_RTCP = re.compile(r"\bRTCP\b", re.I)
_SELECT = re.compile(r"\b(UFRAME_NUM|BENUTZER_NUM|UTOOL_NUM|WKZ_NUM)\s*=\s*([^;\s]+)", re.I)
_ASSIGN = re.compile(r"\b(UFRAME|BENUTZER|UTOOL|WKZ)\s*\[\s*([^\]]*)\]\s*=", re.I)
_ENTRY = re.compile(r"P\[\s*(\d+)\s*(?::[^\]]*)?\]\s*\{(.*?)\}\s*;", re.S)
_GROUP = re.compile(r"GP(\d+)\s*:")
_FRAMES = re.compile(r"\s*UF\s*:\s*(\d+)\s*,\s*UT\s*:\s*(\d+)\s*,")
_CONFIG = re.compile(r"\s*\w+\s*:\s*'([^']*)'\s*,")
_AXES = re.compile(r"\s*(X|Y|Z|W|P|R)\s*=\s*(" + NUM + r")\s*(mm|deg)\s*(,|\Z)")
_EXTENDED = re.compile(r"\s*E(\d)\s*=\s*(" + NUM + r")\s*(mm|deg)\s*(,|\Z)")
_JOINT = re.compile(r"\s*J\d\s*=")
_REMOTE = re.compile(r"\s*RX\s*=")
_USER = {"uframe_num": "uf", "benutzer_num": "uf", "utool_num": "ut", "wkz_num": "ut"}
_ASSIGNED = {"uframe": "uf", "benutzer": "uf", "utool": "ut", "wkz": "ut"}


@dataclass
class Instruction:
    """A /MN instruction: its ``line`` (of its number), its text (labels masked, continuation
    lines after a line break), the motion (``J``/``L``/``C``/``A``, "" for none), the positions
    P[n] it moves to (``targets``), the targets that are no P[n] of /POS (``unknown``: ``PR[2]``,
    ``P[R[3]]``), the positions it reads otherwise (``reads``), its options (``offset``: the word
    found, "" for none; ``coord``, ``rtcp``)."""

    line: int
    text: str
    motion: str = ""
    targets: list[int] = field(default_factory=list)
    unknown: list[str] = field(default_factory=list)
    reads: list[int] = field(default_factory=list)
    offset: str = ""
    coord: bool = False
    rtcp: bool = False


@dataclass
class Position:
    """A /POS entry P[n]: ``line`` of its ``P[``, ``kind`` of group 1 ("cartesian", "joint",
    "remote", "none"), ``uf``, ``ut``, the CONFIG text (``config``, "" for none), X, Y, Z, W,
    P, R (``values``) and the (start, end) offsets of its X, Y, Z literals (``spans``),
    ``literals`` (their text), the other groups (``groups``) and extended axes (``extended``)
    it holds."""

    number: int
    line: int
    kind: str
    uf: int = -1
    ut: int = -1
    config: str = ""
    values: tuple[float, ...] = ()
    spans: tuple[tuple[int, int], ...] = ()
    literals: tuple[str, ...] = ()
    groups: tuple[int, ...] = ()
    extended: tuple[str, ...] = ()


@dataclass
class LsProgram:
    """What ``read_ls`` found: the instructions of /MN, the positions of /POS (in order), the
    frame selections and assignments of the body (``selects``/``assigns``: "uf"/"ut" ->
    [(line, value text)]), the end of the /MN line (``mn``, where a header goes) and the line
    numbers of /MN (``numbers``: (start, end) offsets of each number's digits, and the
    number)."""

    path: str
    instructions: list[Instruction]
    positions: list[Position]
    selects: dict[str, list[tuple[int, str]]]
    assigns: dict[str, list[tuple[int, str]]]
    mn: int
    numbers: list[tuple[int, int, int]]


def read_ls(path: str, text: str) -> LsProgram:
    """The sections, instructions and positions of the program ``text`` (latin-1) at ``path``;
    InputError at the line and column of what the reader cannot read."""
    sections = {m.group(1): m for m in _SECTION.finditer(text)}
    first = text.lstrip()
    if not first.startswith("/PROG"):
        raise InputError("not a FANUC TP program: it does not start with /PROG", path, 1, 1)
    if "MN" not in sections:
        raise InputError("no /MN section: not a FANUC TP program", path, 1, 1)
    mn = sections["MN"]
    pos = sections.get("POS")
    end = sections.get("END")
    mn_end = pos.start() if pos else (end.start() if end else len(text))
    instructions, selects, assigns, numbers = _body(path, text, mn.end(), mn_end)
    positions = []
    if pos is not None:
        positions = _positions(path, text, pos.end(), end.start() if end else len(text))
    return LsProgram(path, instructions, positions, selects, assigns, mn.end(), numbers)


def _where(text: str, offset: int) -> tuple[int, int]:
    """(line, column) of an offset, 1-based."""
    line = text.count("\n", 0, offset) + 1
    return line, offset - (text.rfind("\n", 0, offset) + 1) + 1


def _body(path: str, text: str, start: int, end: int):
    """The instructions of /MN (``text[start:end]``), its frame selections and assignments, its
    line numbers."""
    instructions: list[Instruction] = []
    numbers: list[tuple[int, int, int]] = []
    selects: dict[str, list] = {"uf": [], "ut": []}
    assigns: dict[str, list] = {"uf": [], "ut": []}
    expect = 1
    line = _where(text, start)[0] - 1
    pieces: list[tuple[int, str]] = []  # (line, text) of each statement, continuations joined
    for m in _LINE.finditer(text, start, end):
        raw = m.group()
        if not raw:
            break
        line += 1
        body = raw.rstrip("\r\n")
        numbered = _NUMBERED.match(body)
        if numbered and len(numbered.group(1).expandtabs(4)) <= 4:
            number = int(numbered.group(2))
            if number != expect:
                column = numbered.start(2) + 1
                raise InputError(
                    f"line number {number} where {expect} follows: the lines of /MN are "
                    "numbered 1, 2, ... without a gap",
                    path,
                    line,
                    column,
                )
            expect += 1
            numbers.append((m.start() + numbered.start(2), m.start() + numbered.end(2), number))
            pieces.append((line, body[numbered.end() :]))
        elif numbered:  # a point-logic sub-line: a statement of its own
            pieces.append((line, body[numbered.end() :]))
        elif _CONTINUED.match(body) and pieces:
            last_line, last = pieces[-1]
            pieces[-1] = (last_line, last + "\n" + body[_CONTINUED.match(body).end() :])
    for line, statement in pieces:
        instruction = _instruction(line, statement)
        if instruction is None:
            continue
        instructions.append(instruction)
        for word, value in _SELECT.findall(instruction.text):
            selects[_USER[word.lower()]].append((line, value))
        for word, value in _ASSIGN.findall(instruction.text):
            assigns[_ASSIGNED[word.lower()]].append((line, value.strip()))
    return instructions, selects, assigns, numbers


def _instruction(line: int, statement: str) -> Instruction | None:
    """The instruction of one statement (its text after ``n:``), None for a remark or a disabled
    line."""
    text = statement.strip()
    if text.startswith(("!", "//")) or not text:
        return None
    text = _LABEL.sub(r"[\1]", text)
    out = Instruction(line, text)
    parts = text.split("\n")  # a circular move's end point continues it on a line of its own
    motion = _MOTION.match(parts[0])
    points = [int(n) for n in _POINT.findall(text)]
    if motion is None:
        out.reads = points
        return out
    out.motion = motion.group(1).upper()
    goals = [motion.groups()[1:]]
    end = _TARGET.match(parts[1]) if out.motion == "C" and len(parts) > 1 else None
    if end is not None:
        goals.append(end.groups())
    for kind, value in goals:
        value = value.strip() + ("]" if value.count("[") > value.count("]") else "")
        if kind.upper() == "P" and value.isdigit():
            out.targets.append(int(value))
        else:
            out.unknown.append(f"{kind.upper()}[{value}]")
    reads = list(points)
    for n in out.targets:
        reads.remove(n)
    out.reads = reads
    found = _OFFSET.search(text)
    out.offset = found.group() if found else ""
    out.coord = bool(_COORD.search(text))
    out.rtcp = bool(_RTCP.search(text))
    return out


def _positions(path: str, text: str, start: int, end: int) -> list[Position]:
    """The entries of /POS (``text[start:end]``); InputError at text that is no entry."""
    out: list[Position] = []
    seen: dict[int, int] = {}
    at = start
    line, counted = _where(text, start)[0], start  # the line of offset ``counted``
    for m in _ENTRY.finditer(text, start, end):
        gap = text[at : m.start()]
        if gap.strip():
            offset = at + len(gap) - len(gap.lstrip())
            raise InputError(
                "cannot read this as a /POS position P[n]{...};", path, *_where(text, offset)
            )
        at = m.end()
        number = int(m.group(1))
        line += text.count("\n", counted, m.start())  # counted on: one pass over /POS
        counted = m.start()
        if number in seen:
            raise InputError(f"P[{number}] is defined twice (line {seen[number]})", path, line, 1)
        seen[number] = line
        out.append(_entry(path, text, m, number, line))
    rest = text[at:end]
    if rest.strip():
        offset = at + len(rest) - len(rest.lstrip())
        raise InputError(
            "cannot read this as a /POS position P[n]{...};", path, *_where(text, offset)
        )
    return out


def _entry(path: str, text: str, m: re.Match, number: int, line: int) -> Position:
    """One /POS entry: group 1 read, the other groups noted."""
    body_at = m.start(2)
    body = m.group(2)
    groups = list(_GROUP.finditer(body))

    def fail(offset: int, what: str) -> InputError:
        return InputError(f"P[{number}]: {what}", path, *_where(text, body_at + offset))

    if not groups or body[: groups[0].start()].strip():
        at = len(body) - len(body.lstrip())
        raise fail(at, "expected a motion group (GP1: UF : n, UT : n, ...)")
    others = tuple(int(g.group(1)) for g in groups if g.group(1) != "1")
    first = next((k for k, g in enumerate(groups) if g.group(1) == "1"), None)
    if first is None:
        return Position(number, line, "none", groups=others)
    g = groups[first]
    stop = groups[first + 1].start() if first + 1 < len(groups) else len(body)
    at = g.end()
    frames = _FRAMES.match(body, at, stop)
    if frames is None:
        raise fail(
            at + len(body[at:stop]) - len(body[at:stop].lstrip()), "expected UF : n, UT : n,"
        )
    uf, ut = int(frames.group(1)), int(frames.group(2))
    at = frames.end()
    if _JOINT.match(body, at, stop):
        return Position(number, line, "joint", uf, ut, groups=others)
    config = ""
    c = _CONFIG.match(body, at, stop)
    if c is not None:
        config, at = c.group(1), c.end()
    if _REMOTE.match(body, at, stop):
        return Position(number, line, "remote", uf, ut, config, groups=others)
    values, spans, literals = [], [], []
    for axis in "XYZWPR":
        a = _AXES.match(body, at, stop)
        if a is None or a.group(1) != axis:
            raise fail(
                at + len(body[at:stop]) - len(body[at:stop].lstrip()), f"expected {axis} = .."
            )
        unit = "mm" if axis in "XYZ" else "deg"
        if a.group(3) != unit:
            raise fail(a.start(3), f"{axis} is in {unit}, got {a.group(3)}")
        values.append(float(a.group(2)))
        if axis in "XYZ":
            spans.append((body_at + a.start(2), body_at + a.end(2)))
            literals.append(a.group(2))
        at = a.end()
    extended = []
    while (e := _EXTENDED.match(body, at, stop)) is not None:
        extended.append(f"E{e.group(1)}")
        at = e.end()
    if body[at:stop].strip():
        raise fail(at + len(body[at:stop]) - len(body[at:stop].lstrip()), "cannot read this")
    return Position(
        number,
        line,
        "cartesian",
        uf,
        ut,
        config,
        tuple(values),
        tuple(spans),
        tuple(literals),
        others,
        tuple(extended),
    )
