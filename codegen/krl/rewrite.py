"""Pre-flight rewrite of a KUKA KRL .src/.dat (see ``codegen.rewrite`` for what a rewrite is).

KRL inline aggregates use the base in effect at that line (see ``codegen.krl.parse``). A stored
position (declared or assigned with a literal) is corrected only if a motion uses it, or, in a
.dat given alone with ``--base``, if it is a POS/E6POS; never a frame (``$TOOL``/``$BASE``/
``$LOAD``/``TOOL_DATA``/``BASE_DATA`` value, ``:`` operand) or a CONST. It takes the base of the
motions that use it (its own FDAT wins over ``--base``) and is corrected once however many
motions use it. BASE_DATA[n] comes from ``--config-dat`` (if it defines n), else from the cell's
``base`` and ``base_data``; base 0 ($NULLFRAME, BAS(#BASE,0)) is the robot frame ($WORLD =
$ROBROOT).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from accugrid.codegen.krl.parse import (
    BaseRef,
    Declared,
    Fdat,
    FrameUse,
    KrlPosition,
    KrlScan,
    KrlUse,
    scan_krl,
    wildcard,
)
from accugrid.codegen.program_text import MIN_PLACES_MM, number_texts, precision, splice
from accugrid.codegen.rewrite import (
    Options,
    Result,
    Row,
    correct_points,
    rotations_of,
    strict_check,
)
from accugrid.kinematics.frames import pose_from_xyzabc

__all__ = ["rewrite_krl"]

_EXTERNAL_AXES = ("E1", "E2", "E3", "E4", "E5", "E6")
_EXTERNAL = frozenset(_EXTERNAL_AXES)


def rewrite_krl(texts: dict[str, str], opts: Options, config_dat: str | None = None) -> Result:
    """Rewrite a KRL .src and/or .dat (texts by path); ``config_dat``: the text of a $config.dat
    (its BASE_DATA, FDATs and declarations are read, it is not rewritten)."""
    initial = (
        BaseRef("number", 0, number=opts.base_override) if opts.base_override is not None else None
    )
    scans = [
        scan_krl(text, path, initial_base=initial, trust_calls=opts.trust_calls)
        for path, text in texts.items()
    ]
    config = scan_krl(config_dat, "$config.dat") if config_dat is not None else None
    ctx = _Context(scans, config, initial, opts)
    rows: list[Row] = []
    placed: list[tuple[KrlPosition, Row, np.ndarray]] = []
    for scan in scans:
        path = scan.path or ""
        for pos in scan.positions:
            row = Row(path, pos.line, pos.name, "skipped")
            nums = pos.numbers
            if "X" in nums and "Y" in nums and "Z" in nums:
                row.old = (nums["X"].value, nums["Y"].value, nums["Z"].value)
            rows.append(row)
            reason = pos.reason or _external_axis_reason(pos, opts)
            frame = None
            if not reason and pos.kind == "motion":
                _, frame, reason = ctx.resolve(pos.base)
            elif not reason:
                frame, reason = ctx.stored_frame(pos)
            if reason:
                row.reason = reason
                continue
            placed.append((pos, row, frame))
    for scan in scans:
        for use in scan.uses:
            reason = use.reason or ctx.unmatched_reason(use)
            if reason:
                rows.append(Row(scan.path or "", use.line, use.text, "skipped", reason))
    edits: dict[str, list[tuple[int, int, str]]] = {p: [] for p in texts}
    places_of = {
        scan.path: precision(
            (p.numbers[k].literal for p in scan.positions for k in "XYZ" if k in p.numbers),
            MIN_PLACES_MM,
        )
        for scan in scans
    }
    if placed:
        _correct_krl(placed, texts, edits, places_of, opts)
    strict_check(rows, opts)
    return Result({p: splice(t, edits[p]) for p, t in texts.items()}, rows)


def _external_axis_reason(pos: KrlPosition, opts: Options) -> str:
    nums = pos.numbers
    if opts.ignore_external_axes or _EXTERNAL.isdisjoint(nums):
        return ""
    moving = [k for k in _EXTERNAL_AXES if k in nums and nums[k].value != 0.0]
    if not moving:
        return ""
    return (
        f"external axis {moving[0]} = {nums[moving[0]].value:g}: the robot frame depends on "
        "external kinematics (--ignore-external-axes if not)"
    )


class _Context:
    """What every file given says, merged: which names are positions, under which base.

    A stored position (declared or assigned with a literal) is a drilling position only if a
    motion uses it, or, in a .dat given alone with ``--base``, if it is a POS/E6POS. Never when it
    is a frame (assigned to $TOOL/$BASE/$LOAD/TOOL_DATA/BASE_DATA, an operand of ``:``) or
    declared CONST. Its FDAT (``XP1`` <-> ``FP1``) wins over ``--base``; an FDAT with another
    tool than the cell's, or an external TCP, leaves it uncorrected."""

    def __init__(
        self, scans: list[KrlScan], config: KrlScan | None, initial: BaseRef | None, opts: Options
    ) -> None:
        self.opts = opts
        self.initial = initial
        every = scans + ([config] if config is not None else [])
        self.base_data = dict(opts.base_data)
        if config is not None:
            for n, (xyzabc, _) in config.base_data.items():
                self.base_data[n] = pose_from_xyzabc(np.array(xyzabc))
        self.fdats: dict[str, Fdat] = {}
        self.declared: dict[str, tuple[str, Declared]] = {}
        self.frame_uses: dict[str, tuple[str, FrameUse]] = {}
        self.assigned: dict[str, tuple[str, int]] = {}
        for scan in reversed(every):  # the given files win over $config.dat
            self.fdats.update(scan.fdats)
        for scan in every:
            where = scan.path or ""
            for key, declared in scan.declared.items():
                self.declared.setdefault(key, (where, declared))
            for key, use in scan.frame_uses.items():
                self.frame_uses.setdefault(key, (where, use))
            for key, line in scan.assigned.items():
                self.assigned.setdefault(key, (where, line))
        self.named: dict[str, list[KrlPosition]] = {}
        for scan in scans:
            for pos in scan.positions:
                if pos.kind != "motion":
                    self.named.setdefault(pos.key, []).append(pos)
        self.wild_named = {wildcard(key) for key in self.named}
        self.config_named = {p.key: p for p in config.positions} if config is not None else {}
        self.uses: dict[str, list[KrlUse]] = {}
        for scan in scans:
            for use in scan.uses:
                if not use.reason and use.name:
                    self.uses.setdefault(use.name, []).append(use)
        self.lone_dat = all(Path(s.path or "").suffix.lower() == ".dat" for s in scans)
        self._resolved: dict[BaseRef, tuple[object, np.ndarray | None, str]] = {}

    def resolve(self, base: BaseRef) -> tuple[object, np.ndarray | None, str]:
        """(identity key, robot_T_base or None, reason), once per distinct base."""
        found = self._resolved.get(base)
        if found is None:
            found = self._resolved[base] = self._resolve(base)
        return found

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
        tool = self.opts.tool_number
        if tool is not None and fdat.tool_no is not None and fdat.tool_no != tool:
            return (
                f"FDAT {name} (line {fdat.line}) has TOOL_NO {fdat.tool_no}: the cell's tool, "
                f"which the grid holds for, is {tool}"
            )
        return ""

    def _own_fdat(self, pos: KrlPosition) -> BaseRef | None:
        """The base of a position's own FDAT (``XP1`` -> ``FP1``), None when it has none."""
        key = pos.key
        if not key.startswith("X") or "[" in key or "." in key:
            return None
        name = "F" + key[1:]
        return BaseRef("fdat", pos.line, fdat=name) if name in self.fdats else None

    def stored_frame(self, pos: KrlPosition) -> tuple[np.ndarray | None, str]:
        """robot_T_base of a declared or assigned position, or why it is not corrected."""
        key = pos.key
        if len(self.named.get(key, ())) > 1:
            lines = ", ".join(str(p.line) for p in self.named[key])
            return None, f"{pos.name} is defined more than once (lines {lines})"
        wild = wildcard(key)
        variables = (key, wild, key.split(".")[0], wild.split(".")[0])
        for k in variables:
            if k in self.frame_uses:
                where, use = self.frame_uses[k]
                return None, f"{pos.name} is {use.reason} ({Path(where).name})"
        for k in variables:
            if k in self.assigned:
                where, line = self.assigned[k]
                return None, f"{pos.name} is assigned at run time ({Path(where).name}:{line})"
        found = self.uses.get(key, []) + (self.uses.get(wild, []) if wild != key else [])
        own = self._own_fdat(pos)
        if not found:
            return self._unused(pos, own)
        keys, frame = {}, None
        for use in found:
            base = own if own is not None and use.base is self.initial else use.base
            ident, frame_i, reason = self.resolve(base)
            if reason:
                return None, f"used at line {use.line} where the {reason}"
            keys.setdefault(ident, use.line)
            frame = frame_i
        if len(keys) > 1:
            lines = ", ".join(str(line) for line in keys.values())
            return None, f"{pos.name} is used under different bases (lines {lines})"
        return frame, ""

    def _unused(self, pos: KrlPosition, own: BaseRef | None) -> tuple[np.ndarray | None, str]:
        """A stored position no motion uses: a position only in a .dat given alone with --base."""
        cartesian = pos.type in ("POS", "E6POS")
        in_dat = Path(pos.path or "").suffix.lower() == ".dat"
        if self.lone_dat and in_dat and cartesian:
            if self.initial is not None:  # --base N; the position's own FDAT wins over it
                _, frame, reason = self.resolve(own if own is not None else self.initial)
                return frame, reason
            return None, (
                f"{pos.name} is not used by a motion in the given program, so its base is unknown "
                "(give the .src, or --base N)"
            )
        why = f"{pos.name} is not used by a motion in the given files: not a drilling position"
        if self.lone_dat and in_dat and self.initial is not None:
            why += f" (--base N applies to POS/E6POS only, this is {pos.type or 'untyped'})"
        return None, why

    def unmatched_reason(self, use: KrlUse) -> str:
        """Why a motion to a name corrects nothing ("" when the name is a stored position)."""
        if use.name in self.named or use.name in self.wild_named:
            return ""
        stored = self.config_named.get(use.name)
        if stored is not None:
            return stored.reason or f"{use.text} is in --config-dat, which is read, not rewritten"
        variable = use.name.split("[")[0].split(".")[0]
        found = self.declared.get(variable)
        if found is not None:
            where, declared = found
            return (
                f"{use.text} is declared ({declared.type}, {Path(where).name}:{declared.line}) "
                "but given no literal value in the given files: it is set at run time"
            )
        return f"{use.text} is not declared in the given files"


def _correct_krl(
    placed: list[tuple[KrlPosition, Row, np.ndarray]],
    texts: dict[str, str],
    edits: dict[str, list[tuple[int, int, str]]],
    places_of: dict[str, int],
    opts: Options,
) -> None:
    """Correct the placed positions at once: rows updated, X, Y, Z edits added per file.

    ``placed``: (position, its row, robot_T_base (4, 4)) for N positions; frames are shared
    objects, so the N frames come from a few distinct ones."""
    unique: dict[int, int] = {}
    which = np.array([unique.setdefault(id(f), len(unique)) for _, _, f in placed])
    by_id = {id(f): f for _, _, f in placed}
    frames = np.array([by_id[k] for k in unique])[which]  # (N, 4, 4)
    abc = np.array([[_value(pos, k) for k in "ABC"] for pos, _, _ in placed]).reshape(-1, 3)
    base_xyz = np.array([row.old for _, row, _ in placed])  # (N, 3) mm, base frame
    robot = np.einsum("nij,nj->ni", frames[:, :3, :3], base_xyz) + frames[:, :3, 3]
    rows = [row for _, row, _ in placed]
    corrected = correct_points(robot, rows, opts, rotations_of(frames[:, :3, :3], abc))
    inside = np.isfinite(corrected[:, 0])
    back = np.einsum("nji,nj->ni", frames[:, :3, :3], corrected - robot)  # R^T e
    targets = base_xyz + back
    for file in texts:
        idx = [i for i in np.flatnonzero(inside).tolist() if placed[i][1].file == file]
        if not idx:
            continue
        text = texts[file]
        places = opts.decimals if opts.decimals is not None else places_of[file]
        numbers = [pos.numbers[k] for i in idx for pos in (placed[i][0],) for k in "XYZ"]
        olds = [text[n.start : n.end] for n in numbers]
        news = number_texts(olds, base_xyz[idx].ravel(), targets[idx].ravel(), places)
        written = np.array(list(map(float, news))).reshape(-1, 3)
        residual = np.linalg.norm(written - targets[idx], axis=1).tolist()
        for i, new, res in zip(idx, written.tolist(), residual, strict=True):
            row = placed[i][1]
            row.status, row.new, row.residual_mm = "corrected", tuple(new), res
            row.rounding_mm = res
        edits[file] += [
            (n.start, n.end, new)
            for n, old, new in zip(numbers, olds, news, strict=True)
            if new != old
        ]


def _value(pos: KrlPosition, key: str) -> float:
    number = pos.numbers.get(key)
    return math.nan if number is None else number.value
