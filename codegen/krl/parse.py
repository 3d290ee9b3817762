"""KUKA KRL reader: every Cartesian position of a .src/.dat with the exact span of each number,
and the base frame ($BASE) in effect wherever a motion uses one.

Line-based and case-insensitive (KRL has one statement per line; ``;`` starts a comment, so
inline-form FOLD lines are comments). It finds:

- positions: ``DECL [GLOBAL] [CONST] E6POS|POS|FRAME|AXIS|E6AXIS name = {...}``, element or
  variable assignments ``name[3] = {...}``, and aggregates inside motions (``PTP``, ``LIN``,
  ``CIRC aux, target``, ``SPTP``, ``SLIN``, ``SCIRC``, ``SPL``, the ``_REL`` forms);
- uses: motions that go to a named position (``PTP XP1``, ``LIN lfWorkPos[i]``);
- base frame context, followed in program order: ``$BASE = BASE_DATA[n]``, ``$BASE = {FRAME: ..}``,
  ``$BASE = $NULLFRAME``, ``BAS(#BASE, n)``, ``FDAT_ACT = Fname`` (``BASE_NO`` of the FDAT
  declaration), and for one spline motion ``WITH $BASE = SBASE(Fname.BASE_NO)``. What cannot be
  decided is an ``unknown`` base with the reason: frame arithmetic ``:``, a variable, ``EK(...)``,
  the start of a routine (inherited from the caller), a call that may change it, a jump target,
  a branch or loop that changes it.

Numbers are spans into the text given (character offsets), so a rewrite replaces only them.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from typing import NamedTuple

from accugrid.codegen.program_text import check_text, decimals_of, split_lines
from accugrid.kinematics.errors import InputError

MOTIONS = frozenset(
    "PTP LIN CIRC SPTP SLIN SCIRC SPL PTP_REL LIN_REL CIRC_REL SPTP_REL SLIN_REL SCIRC_REL".split()
)
POSITION_TYPES = frozenset(("E6POS", "POS", "FRAME", "AXIS", "E6AXIS"))
CARTESIAN_KEYS = frozenset("X Y Z A B C S T E1 E2 E3 E4 E5 E6".split())
_JOINTS = frozenset(("A1", "A2", "A3", "A4", "A5", "A6"))
JOINT_KEYS = frozenset("A1 A2 A3 A4 A5 A6 E1 E2 E3 E4 E5 E6".split())
_NOT_CALLS = (
    frozenset(
        """IF ELSE ENDIF WHILE ENDWHILE FOR ENDFOR LOOP ENDLOOP REPEAT UNTIL SWITCH CASE DEFAULT
    ENDSWITCH RETURN WAIT HALT CONTINUE EXIT GOTO TRIGGER INTERRUPT ANOUT ANIN DIGIN PULSE BRAKE
    RESUME DEF DEFFCT END ENDFCT DECL EXT EXTFCT EXTP EXTFCTP GLOBAL SIGNAL STRUC ENUM CONST
    DEFDAT ENDDAT PUBLIC SPLINE ENDSPLINE PTP_SPLINE BAS NOT""".split()
    )
    | MOTIONS
)

NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_FLAT_RE = re.compile(r"(\s*([A-Za-z_]\w*)\s+)(?:(" + NUMBER + r")|('[^']*')|([^,]*?))(\s*(?:,|$))")
_ITEM_RE = re.compile(r"\s*([A-Za-z_]\w*)\s+(?:(" + NUMBER + r")|('[^']*')|([^,]*?))\s*(?:,|$)")
_TYPE_PREFIX_RE = re.compile(r"\s*([A-Za-z_]\w*)\s*:")
_LABEL_RE = re.compile(r"\s*([A-Za-z_]\w*)\s*:(?!:)\s*")
_WORD_RE = re.compile(r"\s*([A-Za-z_$]\w*)")
_DECL_RE = re.compile(
    r"\s*(?:GLOBAL\s+)?(?:DECL\s+)?(?:GLOBAL\s+)?(?:CONST\s+)?([A-Za-z_]\w*)\s+([A-Za-z_$]\w*)\s*(\[[^\]]*\])?\s*",
    re.I,
)
_GLOBAL_DECL_RE = re.compile(r"\s*GLOBAL\s+DECL\b", re.I)
_TARGET_NAME_RE = re.compile(r"([A-Za-z_$][\w$]*)\s*(\[[^\]]*\])?((?:\s*\.\s*\w+)*)")
_ASSIGN_RE = re.compile(r"\s*([A-Za-z_$][\w$]*)\s*(\[[^\]]*\])?((?:\s*\.\s*\w+)*)\s*=(?!=)\s*")
_INT_RE = re.compile(r"\s*\+?(\d+)\s*$")
_BAS_RE = re.compile(r"\s*BAS\s*\(\s*#\s*(\w+)\s*(?:,\s*(.*?))?\s*\)\s*$", re.I)
_BASE_DATA_RE = re.compile(r"\s*BASE_DATA\s*\[\s*(\d+)\s*\]\s*$", re.I)
_CALL_RE = re.compile(r"\s*([A-Za-z_]\w*)\s*\(")
_ROUTINE_RE = re.compile(r"\s*(?:GLOBAL\s+)?(DEF|DEFFCT)\s+(?:\w+\s+)?([A-Za-z_]\w*)\s*\(", re.I)


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


_new_number = tuple.__new__  # a Number without the NamedTuple constructor's Python frame


@dataclass(frozen=True)
class BaseRef:
    """The base frame in effect at a place in a program.

    kind: "number" (BASE_DATA[number]), "literal" (xyzabc given in the program), "fdat" (the
    BASE_NO of FDAT ``fdat``, resolved once every file is read), "unknown" (``reason`` says why).
    """

    kind: str
    line: int = 0  # where it was set (0: before the file)
    number: int | None = None
    xyzabc: tuple[float, ...] | None = None
    fdat: str | None = None
    reason: str = ""
    label: str | None = None  # set when the state was carried across a jump target

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


@dataclass
class KrlScan:
    """Everything read from one file."""

    path: str | None
    positions: list[KrlPosition] = field(default_factory=list)
    uses: list[KrlUse] = field(default_factory=list)
    fdats: dict[str, tuple[int | None, int, str]] = field(default_factory=dict)
    # FDAT name -> (BASE_NO or None, line, reason when None)
    base_data: dict[int, tuple[tuple[float, ...], int]] = field(default_factory=dict)
    # BASE_DATA[n] = {..} in this file -> (xyzabc, line)
    assigned: dict[str, int] = field(default_factory=dict)
    # names given a non-literal value at run time -> first line


def normalize_name(name: str) -> str:
    """``lfWorkPos[ 3 ]`` -> ``LFWORKPOS[3]``; a non-integer index becomes ``[*]``."""
    if "[" not in name and " " not in name and "\t" not in name:
        return name.upper()
    name = re.sub(r"\s+", "", name).upper()
    head, bracket, rest = name.partition("[")
    if not bracket:
        return head
    index = rest.rstrip("]")
    return f"{head}[{index}]" if index.isdigit() else f"{head}[*]"


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
    if "{" in body or '"' in body:
        items = _split_top(body)  # nested aggregates or strings: item by item
    else:
        items = None
    stop = end - 1
    if items is None:  # the common flat aggregate: one C-level scan, spans by arithmetic
        cursor = body_start
        for lead, key, number, bits, other, trail in _FLAT_RE.findall(code, body_start, stop):
            key = key.upper()
            vstart = cursor + len(lead)
            if key in numbers:
                raise InputError(f"component {key} given twice", path, lineno, vstart + 1)
            if number:
                cursor = vstart + len(number)
                numbers[key] = _new_number(
                    Number, (key, float(number), offset + vstart, offset + cursor, number)
                )
            elif bits:
                cursor = vstart + len(bits)
                numbers[key] = _bits(key, bits, vstart, offset, path, lineno)
            else:
                cursor = vstart + len(other)
                if key in CARTESIAN_KEYS or key in JOINT_KEYS:
                    reason = reason or f"component {key} is {other!r}, not a number"
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
            raise InputError(
                f"cannot read aggregate component {item.strip()!r}", path, lineno, item_start + 1
            )
        key = m.group(1).upper()
        if key in numbers:
            raise InputError(f"component {key} given twice", path, lineno, m.start(2) + 1)
        if m.group(2) is not None:
            numbers[key] = Number(
                key,
                float(m.group(2)),
                offset + m.start(2),
                offset + m.end(2),
                m.group(2),
            )
        elif m.group(3) is not None:
            numbers[key] = _bits(key, m.group(3), m.start(3), offset, path, lineno)
    return type_name, numbers, reason, end


def _refuse_item(code: str, start: int, stop: int, path: str | None, lineno: int) -> None:
    """InputError at the first part of an aggregate body that is not ``NAME value``."""
    expected = start
    for m in _ITEM_RE.finditer(code, start, stop):
        if m.start() != expected:
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
        return "joint-space target (AXIS/E6AXIS): not a Cartesian position"
    missing = [k for k in "XYZ" if k not in keys]
    if missing:
        given = ",".join(k for k in "XYZABC" if k in keys) or "none"
        return (
            f"partial aggregate (gives {given}; missing {','.join(missing)}): "
            "the correction would need components the program does not give"
        )
    return ""


class _Flow:
    """$BASE through a routine: conditionals, loops, jump targets and calls."""

    def __init__(self, initial: BaseRef, trust_calls: bool) -> None:
        self.initial = initial
        self.trust_calls = trust_calls
        self.state = initial
        self.blocks: list[dict] = []
        self.sets_base = False
        self.records: list[KrlPosition | KrlUse] = []

    def start_routine(self, name: str, line: int) -> None:
        self.finish_routine()
        if self.initial.kind == "unknown":
            self.state = BaseRef(
                "unknown",
                line,
                reason=f"start of routine {name} (line {line}): $BASE is inherited from the caller",
            )
        else:
            self.state = self.initial
        self.blocks = []
        self.sets_base = False
        self.records = []

    def finish_routine(self) -> None:
        """A jump target makes the base path-dependent when the routine sets the base anywhere."""
        if not self.sets_base:
            return
        for rec in self.records:
            if rec.base is not None and rec.base.label:
                rec.base = BaseRef(
                    "unknown",
                    rec.base.line,
                    reason=f"after jump target {rec.base.label}: $BASE depends on the path "
                    "taken to it",
                )

    def set(self, base: BaseRef) -> None:
        self.state = base
        self.sets_base = True

    def record(self, rec: KrlPosition | KrlUse) -> None:
        self.records.append(rec)
        for block in self.blocks:
            block["records"].append(rec)

    def label(self, name: str, line: int) -> None:
        s = self.state
        self.state = BaseRef(
            s.kind, s.line, s.number, s.xyzabc, s.fdat, s.reason, f"{name} (line {line})"
        )

    def call(self, name: str, line: int) -> None:
        if not self.trust_calls:
            self.state = BaseRef(
                "unknown",
                line,
                reason=f"after the call {name}() at line {line}, which may change $BASE",
            )

    def open(self, keyword: str, line: int) -> None:
        self.blocks.append(
            {"kw": keyword, "line": line, "start": self.state, "ends": [], "records": []}
        )

    def branch(self) -> None:
        if self.blocks:
            block = self.blocks[-1]
            block["ends"].append(self.state)
            block["has_else"] = True
            self.state = block["start"]

    def close(self, line: int) -> None:
        if not self.blocks:
            return
        block = self.blocks.pop()
        start = block["start"]
        where = f"{block['kw']} at line {block['line']}"
        if block["kw"] in ("IF", "SWITCH"):
            ends = block["ends"] + [self.state]
            if not block.get("has_else"):
                ends.append(start)
            if all(e is start for e in ends):
                self.state = start
            elif all(e is ends[0] for e in ends):
                self.state = ends[0]
            else:
                self.state = BaseRef(
                    "unknown", line, reason=f"$BASE set in one branch of {where} only"
                )
            return
        if self.state is not start:  # a loop body that changes the base
            changed = BaseRef("unknown", line, reason=f"$BASE changes inside the loop {where}")
            for rec in block["records"]:
                if rec.base is start:
                    rec.base = changed
            if block["kw"] != "REPEAT":
                self.state = changed


_OPENERS = {"IF", "SWITCH", "FOR", "WHILE", "LOOP", "REPEAT"}
_CLOSERS = {"ENDIF", "ENDSWITCH", "ENDFOR", "ENDWHILE", "ENDLOOP", "UNTIL"}
_BRANCHES = {"ELSE", "CASE", "DEFAULT"}


def scan_krl(
    text: str,
    path: str | os.PathLike[str] | None = None,
    *,
    initial_base: BaseRef | None = None,
    trust_calls: bool = False,
) -> KrlScan:
    """Read one KRL file (.src, .dat or $config.dat text).

    ``initial_base``: the base in effect at the start of each routine (default: unknown, it is
    the caller's). ``trust_calls``: assume a call to another routine does not change $BASE.
    """
    path = None if path is None else os.fspath(path)
    check_text(text, path)
    scan = KrlScan(path)
    flow = _Flow(initial_base or BaseRef("unknown", 0, reason="no $BASE set"), trust_calls)
    decl_types: dict[str, str] = {}
    offset = 0
    for lineno, line in enumerate(split_lines(text), start=1):
        line_offset = offset
        offset += len(line) + 1
        code = code_part(line, path, lineno)
        if not code or code.isspace() or code.lstrip()[:1] == "&":
            continue
        if code.count("{") != code.count("}"):
            col = code.find("{") if code.count("{") > code.count("}") else code.find("}")
            raise InputError("unbalanced braces", path, lineno, col + 1)
        _statement(code, line_offset, lineno, scan, flow, decl_types)
    flow.finish_routine()
    return scan


def parse_krl(text: str, path: str | os.PathLike[str] | None = None) -> list[KrlPosition]:
    """Every position aggregate of a KRL file, in file order (see ``scan_krl`` for the rest)."""
    return scan_krl(text, path).positions


def _statement(
    code: str,
    off: int,
    lineno: int,
    scan: KrlScan,
    flow: _Flow,
    decl_types: dict[str, str],
) -> None:
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

    if word in ("DEF", "DEFFCT", "GLOBAL") and not _GLOBAL_DECL_RE.match(code, pos):
        routine = _ROUTINE_RE.match(code, pos)
        if routine:
            flow.start_routine(routine.group(2), lineno)
        return
    if word in ("END", "ENDFCT", "DEFDAT", "ENDDAT"):
        flow.finish_routine()
        flow.sets_base = False
        flow.records = []
        return
    if word in _OPENERS:
        flow.open(word, lineno)
        return
    if word in _BRANCHES:
        flow.branch()
        return
    if word in _CLOSERS:
        flow.close(lineno)
        return
    if word in MOTIONS:
        _motion(code, rest_at, word, off, lineno, scan, flow)
        return
    if (
        word == "DECL"
        or (word == "GLOBAL" and _GLOBAL_DECL_RE.match(code, pos))
        or (word in POSITION_TYPES or word == "FDAT")
        and _DECL_RE.match(code, pos)
    ):
        _decl(code, pos, off, lineno, scan, decl_types)
        return
    if word == "BAS":
        m = _BAS_RE.match(code, pos)
        if m and m.group(1).upper() == "BASE":
            arg = m.group(2) or ""
            n = _INT_RE.match(arg)
            if n:
                flow.set(BaseRef("number", lineno, number=int(n.group(1))))
            else:
                flow.set(BaseRef("unknown", lineno, reason=f"BAS(#BASE, {arg}): not a number"))
        return
    assign = _ASSIGN_RE.match(code, pos)
    if assign:
        _assignment(code, assign, off, lineno, scan, flow, decl_types)
        return
    call = _CALL_RE.match(code, pos)
    if call and word not in _NOT_CALLS:
        flow.call(call.group(1), lineno)


def _decl(
    code: str, pos: int, off: int, lineno: int, scan: KrlScan, decl_types: dict[str, str]
) -> None:
    m = _DECL_RE.match(code, pos)
    if m is None:
        return
    type_name = m.group(1).upper()
    name = m.group(2)
    decl_types[name.upper()] = type_name
    rest = code[m.end() :]
    if not rest.startswith("="):
        return
    value_at = m.end() + 1
    while value_at < len(code) and code[value_at] in " \t":
        value_at += 1
    if type_name == "FDAT":
        _fdat(code, value_at, name, lineno, scan)
        return
    if type_name not in POSITION_TYPES or code[value_at : value_at + 1] != "{":
        return
    full = name + (m.group(3) or "")
    _add_position(code, value_at, off, lineno, scan, "decl", type_name, full, None)


def _fdat(code: str, at: int, name: str, lineno: int, scan: KrlScan) -> None:
    base_no, reason = _fdat_base(code, at, scan.path, lineno)
    scan.fdats[name.upper()] = (base_no, lineno, reason)


def _fdat_base(code: str, at: int, path: str | None, lineno: int) -> tuple[int | None, str]:
    if code[at : at + 1] != "{":
        return None, "FDAT is not a literal"
    body = code[at + 1 : match_brace(code, at, path, lineno) - 1]
    fields = {}
    for item in _split_top(body):
        parts = item.split(None, 1)
        if len(parts) == 2:
            fields[parts[0].upper().rstrip(":")] = parts[1].strip()
    ipo = fields.get("IPO_FRAME", "#BASE").replace(" ", "").upper()
    if ipo != "#BASE":
        return None, f"IPO_FRAME {ipo}: a fixed tool (external TCP), not a base frame"
    base_no = fields.get("BASE_NO")
    if base_no is None or not base_no.isdigit():
        return None, f"FDAT BASE_NO is {base_no!r}, not a number"
    return int(base_no), ""


def _add_position(
    code: str,
    at: int,
    off: int,
    lineno: int,
    scan: KrlScan,
    kind: str,
    type_name: str,
    name: str,
    base: BaseRef | None,
) -> tuple[KrlPosition, int]:
    prefix, numbers, reason, end = parse_aggregate(code, at, off, scan.path, lineno)
    type_name = type_name or prefix
    reason = reason or position_reason(type_name, numbers)
    pos = KrlPosition(scan.path, lineno, at + 1, kind, type_name, name, numbers, base, reason)
    scan.positions.append(pos)
    return pos, end


def _assignment(
    code: str,
    m: re.Match,
    off: int,
    lineno: int,
    scan: KrlScan,
    flow: _Flow,
    decl_types: dict[str, str],
) -> None:
    target = m.group(1).upper()
    index = m.group(2) or ""
    member = re.sub(r"\s+", "", m.group(3) or "").upper()
    value_at = m.end()
    value = code[value_at:].strip()
    if target == "$BASE" and not member:
        flow.set(_base_value(code, value_at, off, lineno, scan))
        return
    if target == "$BASE" or (target == "FDAT_ACT" and member):
        flow.set(BaseRef("unknown", lineno, reason=f"{code.strip()}: changes part of the base"))
        return
    if target == "FDAT_ACT":
        if value.startswith("{"):
            base_no, reason = _fdat_base(code, value_at, scan.path, lineno)
            flow.set(
                BaseRef("number", lineno, number=base_no)
                if base_no is not None
                else BaseRef("unknown", lineno, reason=reason)
            )
        elif re.fullmatch(r"[A-Za-z_]\w*", value):
            flow.set(BaseRef("fdat", lineno, fdat=value.upper()))
        else:
            flow.set(BaseRef("unknown", lineno, reason=f"FDAT_ACT = {value}: not a name"))
        return
    if target == "BASE_DATA" and not member:
        n = re.fullmatch(r"\[\s*(\d+)\s*\]", index)
        if n and value.startswith("{") and ":" not in value.replace("FRAME:", ""):
            prefix, numbers, reason, _ = parse_aggregate(code, value_at, off, scan.path, lineno)
            if not reason and all(k in numbers for k in "XYZABC"):
                xyzabc = tuple(numbers[k].value for k in "XYZABC")
                scan.base_data[int(n.group(1))] = (xyzabc, lineno)
        return
    if target in ("$TOOL", "TOOL_DATA", "$LOAD", "$NULLFRAME"):
        return
    name = m.group(1) + index
    if not member and value.startswith("{") and code[value_at : value_at + 1] == "{":
        end = match_brace(code, value_at, scan.path, lineno)
        if not code[end:].strip():
            type_name = decl_types.get(target, "")
            if type_name and type_name not in POSITION_TYPES:
                return
            pos, _ = _add_position(
                code, value_at, off, lineno, scan, "assign", type_name, name, None
            )
            if not pos.numbers or not set(pos.numbers) & (CARTESIAN_KEYS | JOINT_KEYS):
                scan.positions.pop()  # an aggregate of some other structure type
            return
    key = normalize_name(name)
    scan.assigned.setdefault(key, lineno)
    if key.endswith("]"):
        scan.assigned.setdefault(key.split("[")[0] + "[*]", lineno)


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
        return BaseRef("number", lineno, number=int(n.group(1)))
    return BaseRef("unknown", lineno, reason=f"$BASE = {value}: set from a variable")


_TRAILING = re.compile(r"\s*(?:,|C_\w+|WITH\b|CA\b|$)", re.I)


_WITH_BASE_RE = re.compile(r"\bWITH\b.*?\$BASE\s*=\s*(.*?)\s*(?:,\s*\$|$)", re.I)
_SBASE_RE = re.compile(r"SBASE\s*\(\s*([A-Za-z_]\w*)\s*\.\s*BASE_NO\s*\)$", re.I)


def _with_base(code: str, lineno: int) -> BaseRef | None:
    """The base a spline motion sets for itself: ``WITH ..., $BASE = SBASE(FP1.BASE_NO)`` (the
    KSS 8 inline form) or ``$BASE = BASE_DATA[n]``; None when the WITH part does not set it."""
    m = _WITH_BASE_RE.search(code)
    if m is None:
        return None
    value = m.group(1)
    sbase = _SBASE_RE.match(value)
    if sbase:
        return BaseRef("fdat", lineno, fdat=sbase.group(1).upper())
    n = _BASE_DATA_RE.match(value)
    if n:
        return BaseRef("number", lineno, number=int(n.group(1)))
    return BaseRef("unknown", lineno, reason=f"WITH $BASE = {value}: not a BASE_DATA number")


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
    base = flow.state
    if "$" in code and "WITH" in code.upper():
        base = _with_base(code, lineno) or base
    for _ in range(count):
        while at < len(code) and code[at] in " \t,":
            at += 1
        if at >= len(code):
            return
        start = at
        operands: list[tuple[str, int, int]] = []  # ("agg"|"name"|"other", start, end)
        while True:
            if code[at] == "{":
                end = match_brace(code, at, scan.path, lineno)
                operands.append(("agg", at, end))
            else:
                m = _TARGET_NAME_RE.match(code, at)
                if m is None or m.end() == at:
                    end = len(code)
                    operands.append(("other", at, end))
                else:
                    end = m.end()
                    if code[end : end + 1] == "(":
                        operands.append(("other", at, len(code)))
                        end = len(code)
                    else:
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
            break
        target_text = code[start:at].strip()
        arith = len(operands) > 1
        for kind, s, e in operands:
            if kind == "agg":
                if relative:
                    why = f"relative motion {word}: an offset, not a position"
                elif arith:
                    why = f"frame arithmetic ':' in {target_text}: computed at run time"
                else:
                    why = ""
                pos, _ = _add_position(code, s, off, lineno, scan, "motion", "", word, base)
                pos.reason = why or pos.reason
                flow.record(pos)
            else:
                operand = code[s:e].strip()
                name = normalize_name(operand) if kind == "name" else ""
                if kind == "name" and name.startswith("$"):
                    why = f"system variable {operand}: the position is only known at run time"
                elif kind != "name" or "." in name:
                    why = f"target {operand!r} is an expression"
                elif relative:
                    why = f"relative motion {word}: an offset, not a position"
                elif arith:
                    why = f"frame arithmetic ':' in {target_text}: computed at run time"
                else:
                    why = ""
                use = KrlUse(scan.path, lineno, s + 1, word, name, operand, base, why)
                scan.uses.append(use)
                flow.record(use)
