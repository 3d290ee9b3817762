"""Pre-flight rewrite of a KUKA KRL .src/.dat (see ``codegen.rewrite`` for what a rewrite is).

KRL inline aggregates use the base in effect at that line (see ``codegen.krl.parse``). A stored
position (declared or assigned with a literal) is corrected only if a motion uses it, or, in a
.dat given alone with ``--base``, if it is a POS/E6POS; never a frame (``$TOOL``/``$BASE``/
``$LOAD``/``TOOL_DATA``/``BASE_DATA`` value, ``:`` operand) or a CONST. It takes the base of the
motions that use it (its own FDAT wins over ``--base``) and is corrected once however many
motions use it. BASE_DATA[n] comes from ``--config-dat`` (if it defines n), else from the cell's
``base`` and ``base_data``; base 0 ($NULLFRAME, BAS(#BASE,0)) is the robot frame ($WORLD =
$ROBROOT). A call of a routine of the given files that keeps $BASE and $TOOL keeps them, and a
local routine starts in the base every call of it has (``codegen.krl.routines``). A relative
motion (``LIN_REL``...) is corrected as the position it reaches and written back as an
increment (``codegen.krl.relative``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import cached_property
from itertools import chain, count, repeat
from pathlib import Path

import numpy as np

from accugrid.codegen.bytescan import PAD, text_bytes
from accugrid.codegen.krl.parse import (
    FRAME_OPERAND,
    JOINT_TARGET,
    BaseRef,
    Declared,
    Fdat,
    FrameUse,
    KrlScan,
    ToolFrame,
    normalize_name,
    scan_krl,
    wildcard,
)
from accugrid.codegen.krl.relative import Chains, resolve, write_increments
from accugrid.codegen.krl.routines import call_effects, routine_starts
from accugrid.codegen.krl.tables import MOTION, PositionTable
from accugrid.codegen.plugin_types import CORRECTED, Options, Rows, Scan
from accugrid.codegen.program_text import (
    MIN_PLACES_MM,
    UTF8_BOM,
    comment_block,
    distinct_ints,
    insert_after_lines,
    precision,
)
from accugrid.codegen.rewrite import rotations_of
from accugrid.codegen.splice import ByteSplicer, literals
from accugrid.kinematics.frames import pose_from_xyzabc, rotation_angle_deg

__all__ = ["KrlPlacement", "add_header", "scan_positions", "splice_positions"]

_BLOCK = 1 << 16  # positions per block of corrected numbers formatted at once


@dataclass(frozen=True)
class KrlPlacement:
    """What places KRL positions in the robot frame besides the program's text (the plug-in's
    ``placement``): ``base_data`` BASE_DATA number -> robot_T_base (4, 4) mm (the cell's),
    ``base`` the base in effect where a routine sets none (``--base``), ``trust_calls`` (calls
    keep $BASE),
    ``ignore_external_axes`` and ``config_dat``, the text of a $config.dat (its BASE_DATA,
    FDATs and declarations are read, it is not rewritten)."""

    base_data: dict[int, np.ndarray]
    base: int | None = None
    trust_calls: bool = False
    ignore_external_axes: bool = False
    config_dat: str | None = None


@dataclass
class _Files:
    """What the splice needs of a scan: each file's path, text and table, its placed rows
    (``todo``) and the index of each one's robot_T_base (``placed``), the frames, the first
    report row of each file (``starts``), the positions in their base frames (``which`` frame,
    ``base_xyz``; the splice takes both) and the chains of relative motions."""

    files: list[tuple[str | None, str, PositionTable]]
    todo: list[np.ndarray]
    placed: list[np.ndarray]
    frames: np.ndarray
    starts: np.ndarray
    which: np.ndarray
    base_xyz: np.ndarray
    chains: Chains | None = None  # the relative motions, with the scans they are in
    relative: list[KrlScan] = field(default_factory=list)


def scan_positions(texts: dict[str, str], opts: Options, placement: KrlPlacement) -> Scan:
    """The positions of a KRL .src and/or .dat (texts by path), placed by ``placement``."""
    initial = BaseRef("number", 0, number=placement.base) if placement.base is not None else None
    scans = [
        scan_krl(text, path, initial_base=initial, trust_calls=placement.trust_calls)
        for path, text in texts.items()
    ]
    scans = _with_calls(scans, initial, placement.trust_calls)
    config = placement.config_dat
    config = scan_krl(config, "$config.dat") if config is not None else None
    ctx = _Context(scans, config, initial, placement, opts)
    parts, placed = [], []
    for s, scan in enumerate(scans):
        rows, frames = _position_rows(ctx, s, scan, placement)
        parts.append(rows)
        placed.append(frames)
    chains = None
    if any(scan.relative for scan in scans):
        reasons = [p.reason for p in parts]
        chains = resolve(scans, placed, reasons, ctx.stored_row, ctx.frames)
        for s, part in enumerate(parts):
            relative = chains.rows[s]
            known = chains.start[s][:, 0] >= 0
            part.commanded[relative] = ~known
            part.old[relative[known]] = chains.xyz[s][known]  # where it reaches, as written
    parts += [_use_rows(ctx, scan) for scan in scans]
    rows = Rows.concat(parts)
    starts = np.cumsum([0] + [len(p) for p in parts[: len(scans)]])
    del parts
    todo = [np.flatnonzero(which >= 0) for which in placed]
    frames = np.array(ctx.frames) if ctx.frames else np.zeros((0, 4, 4))
    files = [(scan.path, scan.text, scan.table) for scan in scans]
    relative = scans if chains is not None else []
    del scans, ctx, config  # the uses and names are done with: memory for what follows
    status = [
        aggregate_status(text, table.agg[t])
        for (_, text, table), t in zip(files, todo, strict=True)
    ]
    absolute = [(table.xyz, table.abc) for _, _, table in files]
    if chains is not None:
        absolute = _reached(chains, absolute)
    which = np.concatenate([placed[s][t] for s, t in enumerate(todo)])
    base_xyz = np.concatenate([xyz[t] for (xyz, _), t in zip(absolute, todo, strict=True)])
    abc = np.concatenate([abc[t] for (_, abc), t in zip(absolute, todo, strict=True)])
    at = np.concatenate([starts[s] + t for s, t in enumerate(todo)])
    n = len(which)
    robot = np.empty((n, 3))
    for a in range(0, n, _BLOCK):  # (N, 4, 4) frames a block at a time
        f = frames[which[a : a + _BLOCK]]
        robot[a : a + _BLOCK] = (
            np.einsum("nij,nj->ni", f[:, :3, :3], base_xyz[a : a + _BLOCK]) + f[:, :3, 3]
        )
    # the orientation of each run of positions in one frame with the same A, B, C (a whole file,
    # mostly) computed once, for its first position
    first = np.ones(n, bool)
    first[1:] = (which[1:] != which[:-1]) | (abc[1:] != abc[:-1]).any(axis=1)  # NaN: its own
    heads = np.flatnonzero(first)
    rotations = None
    if len(heads) == 1:  # one orientation for all: a read-only view, not N copies of it
        one = rotations_of(frames[which[heads]][:, :3, :3], abc[heads])
        rotations = np.broadcast_to(one, (n, 3, 3))
    elif n:
        rotations = rotations_of(frames[which[heads]][:, :3, :3], abc[heads])[np.cumsum(first) - 1]
    state = _Files(files, todo, placed, frames, starts, which, base_xyz, chains, relative)
    return Scan(rows, at, robot, rotations, np.concatenate(status), state=state)


def _with_calls(scans: list[KrlScan], initial: BaseRef | None, trust: bool) -> list[KrlScan]:
    """``scans`` read again where what their calls do is known (``codegen.krl.routines``): the
    routines of the files they call (unless ``trust``: every call keeps $BASE and $TOOL), and
    the base their local routines start in; until that base is known for no more of them (each
    round knows it for more, or stops)."""
    effects = [None] * len(scans) if trust else call_effects(scans)
    starts: list[dict[str, BaseRef]] = [{} for _ in scans]
    redo = [e is not None for e in effects]
    for _ in range(2 + sum(len(scan.routines) for scan in scans)):  # one more known a round
        found = routine_starts(scans)
        redo = [r or new != old for r, new, old in zip(redo, found, starts, strict=True)]
        starts = found
        if not any(redo):
            break
        for s in np.flatnonzero(redo).tolist():
            text, path = scans[s].text, scans[s].path
            scans[s] = scan_krl(
                text,
                path,
                initial_base=initial,
                trust_calls=trust,
                calls=effects[s],
                starts=starts[s],
            )
        redo = [False] * len(scans)
    return scans


def splice_positions(scan: Scan, corrected: np.ndarray, opts: Options) -> dict[str, bytearray]:
    """Every file's bytes with its corrected positions (``corrected`` (M, 3) mm robot frame,
    NaN rows: not corrected) written back in its base frame, relative motions as increments;
    unchanged files as they were."""
    state: _Files = scan.state
    frames, which, targets, robot = state.frames, state.which, state.base_xyz, scan.robot
    # the positions in their base frames become the targets, in place; the robot-frame points
    # and frame indices are done with: the memory they free holds the new text
    state.which = state.base_xyz = scan.robot = None
    for a in range(0, len(which), _BLOCK):
        f = frames[which[a : a + _BLOCK]]
        e = corrected[a : a + _BLOCK] - robot[a : a + _BLOCK]
        targets[a : a + _BLOCK] += np.einsum("nji,nj->ni", f[:, :3, :3], e)  # R^T e
    del which, robot
    bounds = np.cumsum([0] + [t.size for t in state.todo])
    per_file = [targets[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=True)]
    places = [
        opts.decimals if opts.decimals is not None else _places(table)
        for _, _, table in state.files
    ]
    extra: list[list] = [[] for _ in state.files]
    if state.chains is not None and len(targets):
        extra = _increments(
            state.chains, state.relative, state.todo, per_file, scan.rows, state.starts, places
        )
    out: dict[str, bytes | bytearray] = {}
    for s, (path, text, table) in enumerate(state.files):
        if state.todo[s].size:
            out[path] = _splice(
                text,
                table,
                state.todo[s],
                per_file[s],
                scan.rows,
                state.starts[s],
                places[s],
                extra[s],
            )
        else:
            out[path] = text.encode("latin-1")  # nothing corrected in it
    return out


def _places(table: PositionTable) -> int:
    """The file's precision (``program_text.precision`` of its X, Y, Z literals)."""
    given = table.places[table.places >= 0]
    if not given.size:
        return precision((), MIN_PLACES_MM)
    return max(int(given.max()), MIN_PLACES_MM)


def _position_rows(
    ctx: _Context, s: int, scan: KrlScan, placement: KrlPlacement
) -> tuple[Rows, np.ndarray]:
    """The report rows of a file's positions, and for each the index of its robot_T_base in
    ``ctx.frames`` (-1: not placed, the row says why)."""
    t = scan.table
    n = len(t)
    complete = ~np.isnan(t.xyz).any(axis=1)
    old = np.where(complete[:, None], t.xyz, np.nan)
    reasons = list(t.reason)
    for i in scan.relative:  # placed where its start is known (``resolve``)
        reasons[i] = ""
    if t.external and not placement.ignore_external_axes:
        for i, (key, value) in t.external.items():
            reasons[i] = reasons[i] or (
                f"external axis {key} = {value:g}: the robot frame depends on external "
                "kinematics (--ignore-external-axes if not)"
            )
    frame = np.full(n, -1, np.int64)
    open_ = np.fromiter(map(bool, reasons), bool, n) == 0 if any(reasons) else np.ones(n, bool)
    motion = open_ & (t.kind == MOTION)
    for b in distinct_ints(t.base[motion]):
        at = np.flatnonzero(motion & (t.base == b))
        _, f, reason = ctx.resolve(scan.bases[b])
        if reason:
            for i in at.tolist():
                reasons[i] = reason
        else:
            frame[at] = ctx.frame_id(f)
    stored = np.flatnonzero(open_ & (t.kind != MOTION))
    if stored.size:
        quick, found, why = ctx.quick_frames(s, stored)
        frame[stored[quick]] = found[quick]
        for k, reason in why.items():
            reasons[stored[k]] = reason
        for i in stored[~quick].tolist():
            f, reason = ctx.stored_frame(s, i)
            if reason:
                reasons[i] = reason
            else:
                frame[i] = ctx.frame_id(f)
    rows = Rows([scan.path or ""], np.zeros(n, np.int64), t.line, t.name, reasons, old)
    if ctx.frame_tools:
        placed = frame >= 0
        rows.tool[placed] = np.array(ctx.frame_tools, np.int64)[frame[placed]]
    for i in np.flatnonzero(frame < 0).tolist():  # not placed: does a motion command it?
        if t.reason[i] != JOINT_TARGET and not t.reason[i].startswith(FRAME_OPERAND):
            rows.commanded[i] = t.kind[i] == MOTION or ctx.moved_to(s, i)
    return rows, frame


def _use_rows(ctx: _Context, scan: KrlScan) -> Rows:
    """Report rows of the motions to a name that correct nothing (with the reason)."""
    u = scan.use_table
    n = len(u)
    if ctx.aligned is not None:  # every motion uses a stored position's name
        check = np.zeros(n, bool)
    else:
        check = ~np.fromiter(map(ctx.named.__contains__, u.name), bool, n)
    if any(u.reason):
        check |= np.fromiter(map(bool, u.reason), bool, n)
    lines, names, reasons, cartesian = [], [], [], []
    for i in np.flatnonzero(check).tolist():
        reason = u.reason[i] or ctx.unmatched_reason(u.name[i], u.text[i])
        if reason:
            lines.append(int(u.line[i]))
            names.append(u.text[i])
            reasons.append(reason)
            cartesian.append(not (reason.startswith(FRAME_OPERAND) or ctx.joint_name(u.name[i])))
    n = len(lines)
    rows = Rows(
        [scan.path or ""], np.zeros(n, np.int64), lines, names, reasons, np.full((n, 3), np.nan)
    )
    rows.commanded[:] = cartesian  # a motion to it: commanded unless a joint target
    return rows


class _Context:
    """What every file given says, merged: which names are positions, under which base.

    A stored position (declared or assigned with a literal) is a drilling position only if a
    motion uses it, or, in a .dat given alone with ``--base``, if it is a POS/E6POS. Never when it
    is a frame (assigned to $TOOL/$BASE/$LOAD/TOOL_DATA/BASE_DATA, an operand of ``:``) or
    declared CONST. Its FDAT (``XP1`` <-> ``FP1``) wins over ``--base``; an FDAT with an external
    TCP leaves it uncorrected, and so does one with another tool than the cell's unless the
    cell declares ``tool_data`` (then each position takes the tool of its motions: FDAT
    ``TOOL_NO``, ``$TOOL``, ``BAS(#TOOL, n)``, one tool for all of them)."""

    def __init__(
        self,
        scans: list[KrlScan],
        config: KrlScan | None,
        initial: BaseRef | None,
        placement: KrlPlacement,
        opts: Options,
    ) -> None:
        self.placement = placement
        self.opts = opts
        self.initial = initial
        self.scans = scans
        self.every = scans + ([config] if config is not None else [])
        self.base_data = dict(placement.base_data)
        if config is not None:
            for n, (xyzabc, _) in config.base_data.items():
                self.base_data[n] = pose_from_xyzabc(np.array(xyzabc))
        # number -> flange_T_tool of every tool the cell gives (without tool_data: its tool)
        self.cell_tools = opts.tool_data
        if self.cell_tools is None and opts.flange_T_tool is not None:
            self.cell_tools = {opts.tool_number: opts.flange_T_tool}
        self.tool_conflicts = _tool_conflicts(self.every, self.cell_tools)
        self.fdats: dict[str, Fdat] = {}
        self.frame_uses: dict[str, tuple[str, FrameUse]] = {}
        self.assigned: dict[str, tuple[str, int]] = {}
        for scan in reversed(self.every):  # the given files win over $config.dat
            self.fdats.update(scan.fdats)
        for scan in self.every:
            where = scan.path or ""
            for key, use in scan.frame_uses.items():
                self.frame_uses.setdefault(key, (where, use))
            for key, line in scan.assigned.items():
                self.assigned.setdefault(key, (where, line))
        # stored positions: key of each table row ("" for motions), whether it is a plain name
        self.keys: list[list[str]] = []
        self.plain: list[np.ndarray] = []
        self.named: set[str] = set()
        self.twice: set[str] = set()
        distinct = []  # per file: no key twice in it, none empty
        for scan in scans:
            t = scan.table
            n = len(t)
            keys = _upper(t.name)
            for i in np.flatnonzero(t.kind == MOTION).tolist():
                keys[i] = ""
            plain = np.fromiter(map(str.isidentifier, t.name), bool, n)
            for i in np.flatnonzero(~plain).tolist():
                if keys[i]:
                    keys[i] = normalize_name(t.name[i])
            self.keys.append(keys)
            self.plain.append(plain)
            found = set(keys)
            found.discard("")
            if self.named:
                self.twice.update(self.named.intersection(found))
                self.named.update(found)
            else:
                self.named = found
            distinct.append(len(found) == n)
            if len(found) < n - keys.count(""):
                seen: set[str] = set()
                for k in keys:
                    if k in seen:
                        self.twice.add(k)
                    seen.add(k)
                self.twice.discard("")
        self.config_named = {}
        if config is not None:
            for p in config.positions:
                self.config_named[p.key] = p
        # motions to a name that may be a stored position, all files: file, line, base id
        where = [np.full(len(scan.use_table), s) for s, scan in enumerate(scans)]
        self.use_scan = np.concatenate(where or [np.zeros(0, np.int64)])
        self.use_line = np.concatenate([scan.use_table.line for scan in scans] or [self.use_scan])
        self.use_base = np.concatenate([scan.use_table.base for scan in scans] or [self.use_scan])
        names = list(chain.from_iterable(scan.use_table.name for scan in scans))
        reasons = list(chain.from_iterable(scan.use_table.reason for scan in scans))
        if any(reasons) or "" in names:  # not a stored position's name
            names = [n if not r else "" for n, r in zip(names, reasons, strict=True)]
        self.use_names = names
        # the file whose stored positions are the names the motions use, in their order, each
        # once (a controller's .dat and its .src): the k-th motion uses its k-th row
        self.aligned = next(
            (k for k, keys in enumerate(self.keys) if distinct[k] and keys == names), None
        )
        self.used_twice: set[str] = set()
        if self.aligned is None and len(self.use_of) < len(names) - names.count(""):
            self.used_twice = {n for i, n in enumerate(names) if n and self.use_of[n] != i}
        self._uses: dict[str, list[tuple[int, int]]] | None = None
        self.lone_dat = all(Path(s.path or "").suffix.lower() == ".dat" for s in scans)
        self._resolved: dict[BaseRef, tuple[object, np.ndarray | None, str]] = {}
        self.frames: list[np.ndarray] = []
        self.frame_tools: list[int] = []  # the tool number of each of ``frames`` (-1: the cell's)
        self._frame_ids: dict[int, int] = {}
        self._blocked = set(self.frame_uses) | set(self.assigned)

    @cached_property
    def wild_named(self) -> set[str]:
        """The stored positions' array element names with their indices as wildcards."""
        if "[" not in "".join(self.named):
            return set()
        return {wildcard(key) for key in self.named if "[" in key}

    @cached_property
    def use_of(self) -> dict[str, int]:
        """The first motion (index among the motions of all files) to each name."""
        names = self.use_names
        use_of = dict(zip(reversed(names), range(len(names) - 1, -1, -1), strict=True))
        use_of.pop("", None)
        return use_of

    def frame_id(self, placed: tuple[np.ndarray, int]) -> int:
        """Index of ``placed`` (one of the resolved (frame, tool) pairs) in ``frames``."""
        found = self._frame_ids.get(id(placed))
        if found is None:
            found = self._frame_ids[id(placed)] = len(self.frames)
            self.frames.append(placed[0])
            self.frame_tools.append(placed[1])
        return found

    def resolve(self, base: BaseRef) -> tuple[object, tuple[np.ndarray, int] | None, str]:
        """(identity key, (robot_T_base, tool number, -1: the cell's) or None, reason), once
        per distinct base. Without ``Options.tool_data`` the tool is always the cell's."""
        found = self._resolved.get(base)
        if found is None:
            ident, frame, reason = self._resolve(base)
            tool = -1
            if frame is not None:
                tool, why = self._tool_of(base)
                if why:
                    ident, frame, reason = None, None, why
            placed = None if frame is None else (frame, tool)
            found = self._resolved[base] = ((ident, tool), placed, reason)
        return found

    def _tool_of(self, base: BaseRef) -> tuple[int, str]:
        """The tool the motions under ``base`` (a placed base) command (-1: the cell's; with
        ``Options.tool_data`` its number), or why their positions cannot be corrected: a tool
        not known, or, without ``tool_data``, another than the cell's (a TOOL_DATA number, an
        FDAT's ``TOOL_NO``, a literal frame that differs from the cell's tool by more than its
        written decimals)."""
        tool = base.tool
        if tool is None and base.kind == "fdat":
            tool = self.fdats[base.fdat or ""].tool_no
        if tool is None:
            return -1, ""
        if isinstance(tool, str):
            return -1, f"tool unknown: {tool}"
        tools = self.opts.tool_data
        cell = self.opts.tool_number
        if isinstance(tool, ToolFrame):
            number = _tool_frame_number(tool, self.cell_tools or {}, cell)
            if number is None:
                which = "any tool of the cell file" if tools is not None else "the cell's tool"
                return -1, (
                    f"tool unknown: $TOOL set to a literal frame (line {tool.line}) that is not "
                    f"{which} within its written decimals"
                )
            tool = number
        if tool in self.tool_conflicts:
            return -1, f"tool unknown: {self.tool_conflicts[tool]}"
        if tools is None:
            return -1, self.opts.other_tool(tool)
        return tool, ""

    def _resolve(self, base: BaseRef) -> tuple[object, np.ndarray | None, str]:
        if base.kind == "fdat":
            fdat = self.fdats.get(base.fdat or "")
            if fdat is None:
                return None, None, f"FDAT {base.fdat} (line {base.line}) is not in the given files"
            reason = self._fdat_reason(base.fdat or "", fdat)
            if reason:
                return None, None, reason
            base = BaseRef("number", base.line, number=fdat.base_no)
        if base.kind == "number":
            n = base.number
            if n in self.base_data:
                return ("n", n), self.base_data[n], ""
            if n == 0:
                return ("n", 0), np.eye(4), ""
            return None, None, f"BASE_DATA[{n}] is in neither the cell file nor --config-dat"
        if base.kind == "literal":
            return ("lit", base.xyzabc), pose_from_xyzabc(np.array(base.xyzabc)), ""
        return None, None, f"base unknown: {base.reason}"

    def _fdat_reason(self, name: str, fdat: Fdat) -> str:
        if fdat.base_no is None:
            return f"FDAT {name}: {fdat.reason}"
        tool = self.opts.tool_number  # with the cell's tool_data, each FDAT's own tool
        if self.opts.tool_data is not None:
            return ""
        if tool is not None and isinstance(fdat.tool_no, int) and fdat.tool_no != tool:
            return (
                f"FDAT {name} (line {fdat.line}) has TOOL_NO {fdat.tool_no}: the cell's tool, "
                f"which the grid holds for, is {tool}"
            )
        return ""

    def _own_fdat(self, key: str, line: int) -> BaseRef | None:
        """The base of a position's own FDAT (``XP1`` -> ``FP1``), None when it has none."""
        if not key.startswith("X") or "[" in key or "." in key:
            return None
        name = "F" + key[1:]
        return BaseRef("fdat", line, fdat=name) if name in self.fdats else None

    def quick_frames(
        self, s: int, rows: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, dict[int, str]]:
        """``stored_frame`` of the plain stored positions among table rows ``rows`` (n,) of file
        s: a plain name, defined once, used by one motion, no FDAT of its own, not a frame nor
        assigned at run time; ``stored_frame`` says for the others.

        Returns which rows are plain (n,) bool, the index of each one's frame in ``frames``
        (n,) (-1: none), and the reason of those whose motion is under a base that cannot be
        placed (k -> reason)."""
        keys = self.keys[s]
        if len(rows) != len(keys):
            keys = [keys[i] for i in rows.tolist()]
        n = len(keys)
        blocked = self.twice | self.used_twice | self._blocked
        plain = self.plain[s][rows]  # (stored rows: never a motion's empty key)
        if blocked:
            plain &= ~np.fromiter(map(blocked.__contains__, keys), bool, n)
        if self.fdats:  # XP1 with an FDAT FP1 has a base of its own
            plain &= ~np.array([k[:1] == "X" and "F" + k[1:] in self.fdats for k in keys], bool)
        if s == self.aligned:  # the k-th motion to its k-th row
            at = np.asarray(rows, np.int64)
        else:
            at = np.fromiter(map(self.use_of.get, keys, repeat(-1)), np.int64, n)
        plain &= at >= 0
        found = np.full(n, -1, np.int64)
        why: dict[int, str] = {}
        uses = at[plain]
        pairs = self.use_scan[uses] * (1 << 32) + self.use_base[uses]
        unique, inverse = np.unique(pairs, return_inverse=True)
        ids = np.full(len(unique), -1, np.int64)
        reasons = {}
        for j, pair in enumerate(unique.tolist()):
            scan = self.scans[pair >> 32]
            _, frame, reason = self.resolve(scan.bases[pair & 0xFFFFFFFF])
            if reason:
                reasons[j] = reason
            else:
                ids[j] = self.frame_id(frame)
        found[plain] = ids[inverse.reshape(-1)]
        if reasons:
            inverse = inverse.reshape(-1).tolist()
            for k, use, j in zip(
                np.flatnonzero(plain).tolist(), uses.tolist(), inverse, strict=True
            ):
                if j in reasons:
                    why[k] = f"used at line {self.use_line[use]} where the {reasons[j]}"
        return plain, found, why

    def uses(self, key: str) -> list[tuple[int, BaseRef]]:
        """(line, base) of every motion to ``key`` that may be a stored position, in order."""
        if self._uses is None:
            self._uses = {}
            for s, scan in enumerate(self.scans):
                u = scan.use_table
                for i, (name, reason) in enumerate(zip(u.name, u.reason, strict=True)):
                    if not reason and name:
                        self._uses.setdefault(name, []).append((s, i))
        out = []
        for s, i in self._uses.get(key, []):
            scan = self.scans[s]
            out.append((int(scan.use_table.line[i]), scan.bases[scan.use_table.base[i]]))
        return out

    def stored_frame(self, s: int, i: int) -> tuple[np.ndarray | None, str]:
        """robot_T_base of a declared or assigned position, or why it is not corrected."""
        t = self.scans[s].table
        key, name, line = self.keys[s][i], t.name[i], int(t.line[i])
        if key in self.twice:
            lines = [
                int(self.scans[k].table.line[j])
                for k in range(len(self.scans))
                for j, other in enumerate(self.keys[k])
                if other == key
            ]
            return None, f"{name} is defined more than once (lines {', '.join(map(str, lines))})"
        wild = wildcard(key)
        variables = (key, wild, key.split(".")[0], wild.split(".")[0])
        for k in variables:
            if k in self.frame_uses:
                where, use = self.frame_uses[k]
                return None, f"{name} is {use.reason} ({Path(where).name})"
        for k in variables:
            if k in self.assigned:
                where, at = self.assigned[k]
                return None, f"{name} is assigned at run time ({Path(where).name}:{at})"
        found = self.uses(key) + (self.uses(wild) if wild != key else [])
        own = self._own_fdat(key, line)
        if not found:
            return self._unused(s, i, own)
        keys, frame = {}, None
        for use_line, use_base in found:
            base = own if own is not None and use_base is self.initial else use_base
            ident, frame_i, reason = self.resolve(base)
            if reason:
                return None, f"used at line {use_line} where the {reason}"
            keys.setdefault(ident, use_line)
            frame = frame_i
        if len(keys) > 1:
            lines = ", ".join(str(at) for at in keys.values())
            if len({ident[0] for ident in keys}) == 1:
                return None, f"{name} is moved to with different tools (lines {lines})"
            return None, f"{name} is used under different bases (lines {lines})"
        return frame, ""

    def _unused(self, s: int, i: int, own: BaseRef | None) -> tuple[np.ndarray | None, str]:
        """A stored position no motion uses: a position only in a .dat given alone with --base."""
        scan = self.scans[s]
        type_name, name = scan.table.type[i], scan.table.name[i]
        cartesian = type_name in ("POS", "E6POS")
        in_dat = Path(scan.path or "").suffix.lower() == ".dat"
        if self.lone_dat and in_dat and cartesian:
            if self.initial is not None:  # --base N; the position's own FDAT wins over it
                _, frame, reason = self.resolve(own if own is not None else self.initial)
                return frame, reason
            return None, (
                f"{name} is not used by a motion in the given program, so its base is unknown "
                "(give the .src, or --base N)"
            )
        why = f"{name} is not used by a motion in the given files: not a drilling position"
        if self.lone_dat and in_dat and self.initial is not None:
            why += f" (--base N applies to POS/E6POS only, this is {type_name or 'untyped'})"
        return None, why

    def stored_row(self, name: str) -> tuple[int, int] | str:
        """The (file, table row) of the stored position a motion to ``name`` (normalized) goes
        to, defined once in the given files; otherwise why it is not known."""
        if "*" in name:
            return "its index is a variable"
        if name in self.twice:
            return "it is defined more than once"
        return self.stored_rows.get(name, "it is not a position given in these files")

    @cached_property
    def stored_rows(self) -> dict[str, tuple[int, int]]:
        """Each stored position's key -> (file, table row) (of its first definition)."""
        found: dict[str, tuple[int, int]] = {}
        for s, keys in enumerate(self.keys):
            for i, key in enumerate(keys):
                if key:
                    found.setdefault(key, (s, i))
        return found

    def moved_to(self, s: int, i: int) -> bool:
        """Whether a motion commands stored position row i of file s: a motion uses its name
        and it is not a frame or an offset (``:``, ``$TOOL``/``$BASE``, ...)."""
        key = self.keys[s][i]
        wild = wildcard(key)
        names = (key, wild, key.split(".")[0], wild.split(".")[0])
        if any(k in self.frame_uses for k in names):
            return False
        return s == self.aligned or key in self.use_of or wild in self.use_of

    def joint_name(self, name: str) -> bool:
        """Whether a motion's target name is a joint target: declared AXIS/E6AXIS in the given
        files, or a joint aggregate in --config-dat."""
        stored = self.config_named.get(name)
        if stored is not None and stored.reason == JOINT_TARGET:
            return True
        found = self.declared(name.split("[")[0].split(".")[0])
        return found is not None and found[1].type in ("AXIS", "E6AXIS")

    def declared(self, variable: str) -> tuple[str, Declared] | None:
        for scan in self.every:
            found = scan.declared_get(variable)
            if found is not None:
                return scan.path or "", found
        return None

    def unmatched_reason(self, name: str, text: str) -> str:
        """Why a motion to a name corrects nothing ("" when the name is a stored position)."""
        if name in self.named or name in self.wild_named:
            return ""
        stored = self.config_named.get(name)
        if stored is not None:
            return stored.reason or f"{text} is in --config-dat, which is read, not rewritten"
        found = self.declared(name.split("[")[0].split(".")[0])
        if found is not None:
            where, declared = found
            return (
                f"{text} is declared ({declared.type}, {Path(where).name}:{declared.line}) "
                "but given no literal value in the given files: it is set at run time"
            )
        return f"{text} is not declared in the given files"


def _tool_conflicts(scans: list[KrlScan], tool_data: dict | None) -> dict[int, str]:
    """The tools the files set otherwise than the cell declares them: TOOL_DATA number ->
    why (a value not written as a literal, or another TCP than the cell's, by 0.001 mm or
    0.001 deg)."""
    out = {}
    if tool_data is None:
        return out
    for scan in scans:
        where = Path(scan.path or "").name
        for n, (xyzabc, line) in scan.tool_data.items():
            if n not in tool_data or n in out:
                continue
            if xyzabc is None:
                out[n] = f"TOOL_DATA[{n}] is set otherwise than as a literal frame ({where}:{line})"
                continue
            mine = pose_from_xyzabc(np.array(xyzabc))
            cell = tool_data[n]
            turn = float(rotation_angle_deg(mine[None, :3, :3], cell[:3, :3])[0])
            if np.linalg.norm(mine[:3, 3] - cell[:3, 3]) > 1e-3 or turn > 1e-3:
                out[n] = f"TOOL_DATA[{n}] ({where}:{line}) is not the cell's tool {n}"
    return out


def _tool_frame_number(frame: ToolFrame, tools: dict[int, np.ndarray], cell: int | None):
    """The number of the tool in ``tools`` (number -> flange_T_tool (4, 4) mm) that the literal
    ``frame`` is within its written decimals (each of X, Y, Z within half a unit of its last
    decimal; the rotation within the sum of those of A, B, C, a bound on the angle three such
    Euler angle errors make), the cell's tool ``cell`` first, None when none is."""
    written = pose_from_xyzabc(np.array(frame.xyzabc))
    half = np.array(frame.half_units)
    for number in sorted(tools, key=lambda n: (n != cell, n)):
        pose = tools[number]
        turn = float(rotation_angle_deg(written[None, :3, :3], pose[:3, :3])[0])
        near = np.abs(written[:3, 3] - pose[:3, 3]) <= half[:3] * (1 + 1e-9) + 1e-12
        if near.all() and turn <= half[3:].sum() * (1 + 1e-9) + 1e-9:
            return number
    return None


def _upper(names: list[str]) -> list[str]:
    """``normalize_name`` of plain names (a new list): upper case, the same str where a name is
    upper case already."""
    joined = "".join(names)
    if joined.upper() == joined:
        return list(names)
    return [k if k != n else n for k, n in zip(map(str.upper, names), names, strict=True)]


def _reached(chains: Chains, absolute: list[tuple[np.ndarray, np.ndarray]]) -> list:
    """``absolute`` (per file: X, Y, Z (n, 3) mm and A, B, C (n, 3) deg of each table row) with
    the rows of the relative motions whose start is known replaced by where they reach."""
    out = []
    for s, (xyz, abc) in enumerate(absolute):
        rows = chains.rows[s]
        known = chains.start[s][:, 0] >= 0
        if known.any():
            xyz, abc = xyz.copy(), abc.copy()
            xyz[rows[known]] = chains.xyz[s][known]
            abc[rows[known]] = chains.abc[s][known]
        out.append((xyz, abc))
    return out


def _increments(
    chains: Chains,
    scans: list[KrlScan],
    todo: list[np.ndarray],
    targets: list[np.ndarray],
    rows: Rows,
    starts: np.ndarray,
    places: list[int],
) -> list[list[tuple[int, int, str]]]:
    """The edits of the relative motions (``relative.write_increments``), their report rows
    set; their targets in ``targets`` set to NaN (the absolute splice leaves them)."""
    goals, corrected = [], []
    for scan, t, found in zip(scans, todo, targets, strict=True):
        n = len(scan.table)
        goal = np.full((n, 3), np.nan)
        goal[t] = found
        goals.append(goal)
        corrected.append(np.isfinite(goal[:, 0]))
    edits, reached = write_increments(chains, scans, goals, corrected, places)
    for s, relative in enumerate(chains.rows):
        known = chains.start[s][:, 0] >= 0
        r = relative[known]
        at = starts[s] + r
        done = corrected[s][r]
        rows.status[at[done]] = CORRECTED
        rows.new[at] = reached[s][known]
        want = np.where(done[:, None], goals[s][r], rows.old[at])
        residual = np.linalg.norm(reached[s][known] - want, axis=1)
        rows.residual_mm[at] = rows.rounding_mm[at] = residual
        inside = np.searchsorted(todo[s], r)
        targets[s][inside] = np.nan
    return edits


# The KUKA Status word of an aggregate, ",S 6" / "{S 'B110'" / ", s 'H6'", read with array
# operations over the latin-1 bytes, as the pattern [{,]\s*S\s+(?:'B([01]+)'|'H([0-9A-F]+)'|(\d+))
# (case-insensitive) reads it: _BLANK the bytes \s matches, _DIGIT each byte's digit value (99:
# none), so that a byte is a digit of base b where its value is below b.
_BLANK = np.array([re.fullmatch(r"\s", chr(b)) is not None for b in range(256)])
_DIGIT = np.full(256, 99, np.int64)
_DIGIT[48:58] = range(10)
_DIGIT[65:71] = _DIGIT[97:103] = range(10, 16)
_MAX = np.iinfo(np.int64).max  # a Status too large for int64 reads as this
_EXACT = 15  # digits that fit int64 in any base up to 16 (16**15 < 2**63)
_SCAN = 1 << 18  # bytes looked at at a time for S words


def aggregate_status(text: str, agg: np.ndarray) -> np.ndarray:
    """The KUKA Status S (n,) of the aggregates whose ``{`` is at text offsets ``agg`` (n,)
    (-1: no S); ``S 6``, ``S 'B110'`` or ``S 'H6'``, any case, after the ``{`` or a comma. Every
    S or s of the text (latin-1) is checked at once, its word read digit by digit for all of
    them together; the last S word before an aggregate's ``}`` is its Status."""
    out = np.full(len(agg), -1, np.int64)
    if not len(agg):
        return out
    # the text's bytes and NULs: they end every run of blanks or digits, offset -1 reads one
    buf = text_bytes(text)
    if buf is None:  # beyond latin-1: those characters read as "?"
        buf = np.frombuffer(text.encode("latin-1", "replace") + bytes(PAD), np.uint8)
    s, braces = _s_and_braces(buf)
    s = s[_BLANK[buf[s + 1]]]
    start = _skip_blanks(buf, s - 1, -1)  # the "{" or "," before it
    after = (buf[start] == 123) | (buf[start] == 44)
    s, start = s[after], start[after]
    word = _skip_blanks(buf, s + 1, 1)
    quoted = buf[word] == 39
    letter = buf[word + quoted] | 32  # b or h after the quote
    base = np.where(quoted, np.where(letter == 98, 2, np.where(letter == 104, 16, 0)), 10)
    digits = word + 2 * quoted
    value, length = _digits(buf, digits, base)
    found = (length > 0) & (~quoted | (buf[digits + length] == 39))
    at, value = start[found], value[found]
    order = np.argsort(agg, kind="stable")
    starts = agg[order]
    braces = np.append(braces, len(text))
    closes = braces[np.searchsorted(braces, starts)]  # an aggregate's "}": the first after "{"
    k = np.searchsorted(starts, at, side="right") - 1
    inside = k >= 0
    inside[inside] &= at[inside] < closes[k[inside]]
    out[order[k[inside]]] = value[inside]
    return out


def _s_and_braces(buf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The offsets of every S or s and of every ``}`` in ``buf``, found a block of bytes at a
    time (the temporaries stay in the cache: a third faster than over the whole text at once)."""
    s, braces = [], []
    for a in range(0, len(buf), _SCAN):
        part = buf[a : a + _SCAN]
        s.append(np.flatnonzero((part | 32) == 115) + a)  # S or s (the ASCII case bit set)
        braces.append(np.flatnonzero(part == 125) + a)
    return np.concatenate(s), np.concatenate(braces)


def _skip_blanks(buf: np.ndarray, at: np.ndarray, step: int) -> np.ndarray:
    """The first offset from each of ``at`` (k,), going by ``step`` (1 or -1), whose byte is no
    blank (``_BLANK``); ``buf`` ends with NULs."""
    at = at.copy()
    moving = np.flatnonzero(_BLANK[buf[at]])
    while moving.size:  # once per blank of the longest run
        at[moving] += step
        moving = moving[_BLANK[buf[at[moving]]]]
    return at


def _digits(buf: np.ndarray, at: np.ndarray, base: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The number the digits of ``base`` (k,) (2, 10 or 16; 0: none) from each offset ``at``
    (k,) write and how many there are (k,), both int64 (the number at most _MAX), all of them a
    digit place at a time; ``buf`` ends with NULs."""
    value = np.zeros(len(at), np.int64)
    length = np.zeros(len(at), np.int64)
    going = np.ones(len(at), bool)
    for place in count():  # once per digit of the longest number
        digit = _DIGIT[buf[np.minimum(at + place, len(buf) - 1)]]
        going &= digit < base
        if not going.any():
            return value, length
        grown = value * base + digit  # wraps past _MAX, which only a 16th digit can pass
        if place >= _EXACT:
            grown = np.where(value > (_MAX - digit) // np.maximum(base, 1), _MAX, grown)
        value = np.where(going, grown, value)
        length += going


def _splice(
    text: str,
    t: PositionTable,
    todo: np.ndarray,
    targets: np.ndarray,
    rows: Rows,
    first_row: int,
    places: int,
    extra: list[tuple[int, int, str]] = (),
) -> bytearray:
    """The file's bytes with the X, Y, Z of its corrected positions replaced (``places``
    decimals; a number whose value does not change keeps its literal); their rows
    (``first_row`` + table row) updated.

    ``todo`` (n,): placed table rows, ``targets`` (n, 3) mm base frame, NaN rows where not
    corrected; ``extra``: more edits (start, end, new text), spliced in their place."""
    inside = np.flatnonzero(np.isfinite(targets[:, 0]))
    out = ByteSplicer(text)
    if len(extra):
        extra = sorted(extra)
        stops = [] if not len(inside) else t.span[todo[inside[_BLOCK::_BLOCK]], 0].tolist()
        stops = [*stops, len(text)]  # where each block's edits end (the next block's first)
    for a in range(0, len(inside), _BLOCK):
        k = inside[a : a + _BLOCK]
        goal = targets[k]
        new, length, written = literals(goal.ravel(), places)
        written = written.reshape(-1, 3)
        residual = np.linalg.norm(written - goal, axis=1)
        at = first_row + todo[k]
        rows.status[at] = CORRECTED
        rows.new[at] = written
        rows.residual_mm[at] = residual
        rows.rounding_mm[at] = residual
        changed = written.ravel() != t.xyz[todo[k]].ravel()
        spans = t.span[todo[k]].reshape(-1, 2)[changed]
        new, length = new[np.repeat(changed, length)], length[changed]
        if len(extra):
            stop = stops[a // _BLOCK]
            mine = [e for e in extra if e[0] < stop]
            extra = extra[len(mine) :]
            spans, new, length = _merged(spans, new, length, mine)
        out.add(spans[:, 0], spans[:, 1], new, length)
    if len(extra):
        spans, new, length = _merged(np.zeros((0, 2), np.int64), np.zeros(0, np.uint8), [], extra)
        out.add(spans[:, 0], spans[:, 1], new, length)
    return out.finish()


def _merged(spans: np.ndarray, new: np.ndarray, length, edits: list[tuple[int, int, str]]):
    """Spans (m, 2), new bytes and lengths (m,) with ``edits`` (start, end, text) added, sorted
    by (start, end)."""
    if not edits:
        return spans, new, np.asarray(length, np.int64)
    pieces = np.split(new, np.cumsum(length)[:-1]) if len(length) else []
    every = [(int(a), int(b), bytes(p)) for (a, b), p in zip(spans.tolist(), pieces, strict=True)]
    every += [(a, b, text.encode("ascii")) for a, b, text in edits]
    every.sort(key=lambda e: (e[0], e[1]))
    spans = np.array([(a, b) for a, b, _ in every], np.int64).reshape(-1, 2)
    data = b"".join(p for _, _, p in every)
    return spans, np.frombuffer(data, np.uint8), np.array([len(p) for *_, p in every], np.int64)


def add_header(text: str, lines: list[str]) -> str:
    """The program with the header as ``;`` comments right below its ``DEF``/``DEFDAT`` line
    (controller-written files have only ``&`` lines above it), else after the leading ``&``
    lines."""
    block = comment_block(text, lines, "; {}")
    at = _after_def_line(text, len(UTF8_BOM) if text.startswith(UTF8_BOM) else 0)
    if at is not None:
        return text[:at] + block + text[at:]
    return insert_after_lines(text, block, "&")


_DEF_LINE_RE = re.compile(r"[ \t]*+(?:GLOBAL[ \t]++)?+(?:DEF|DEFFCT|DEFDAT)\b", re.I)


def _after_def_line(text: str, pos: int) -> int | None:
    """Offset just after the first ``DEF``/``DEFFCT``/``DEFDAT`` line (None: none, or it is the
    last line without an ending)."""
    while pos < len(text):
        nl = text.find("\n", pos)
        end = len(text) if nl < 0 else nl
        line = text[pos:end]
        if line.strip() and not line.lstrip().startswith(("&", ";")):
            if _DEF_LINE_RE.match(line):
                return None if nl < 0 else nl + 1
            return None
        if nl < 0:
            return None
        pos = nl + 1
    return None
