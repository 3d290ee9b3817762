"""Pre-flight rewrite of a KUKA KRL .src/.dat (see ``codegen.rewrite`` for what a rewrite is).

KRL inline aggregates use the base in effect at that line (see ``codegen.krl.parse``); a position
declared in a .dat takes the base of the motions that use it, and is corrected once however many
motions use it. BASE_DATA[n] comes from ``--config-dat`` (if it defines n), else from the cell's
``base`` and ``base_data``; base 0 ($NULLFRAME, BAS(#BASE,0)) is the robot frame ($WORLD =
$ROBROOT).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from accugrid.codegen.krl.parse import BaseRef, KrlPosition, KrlUse, scan_krl
from accugrid.codegen.program_text import MIN_PLACES_MM, number_texts, precision, splice
from accugrid.codegen.rewrite import (
    Options,
    Result,
    Row,
    check_orientation,
    correct_points,
    outside_reason,
    strict_check,
)
from accugrid.kinematics.frames import pose_from_xyzabc

__all__ = ["rewrite_krl"]

_EXTERNAL_AXES = ("E1", "E2", "E3", "E4", "E5", "E6")
_EXTERNAL = frozenset(_EXTERNAL_AXES)


def rewrite_krl(texts: dict[str, str], opts: Options, config_dat: str | None = None) -> Result:
    """Rewrite a KRL .src and/or .dat (texts by path); ``config_dat`` text adds BASE_DATA."""
    initial = (
        BaseRef("number", 0, number=opts.base_override) if opts.base_override is not None else None
    )
    scans = [
        scan_krl(text, path, initial_base=initial, trust_calls=opts.trust_calls)
        for path, text in texts.items()
    ]
    base_data = dict(opts.base_data)
    if config_dat is not None:
        for n, (xyzabc, _) in scan_krl(config_dat, "$config.dat").base_data.items():
            base_data[n] = pose_from_xyzabc(np.array(xyzabc))
    fdats: dict[str, tuple[int | None, int, str]] = {}
    assigned: dict[str, tuple[str, int]] = {}
    named: dict[str, list[KrlPosition]] = {}
    for scan in scans:
        fdats.update(scan.fdats)
        for key, line in scan.assigned.items():
            assigned.setdefault(key, (scan.path or "", line))
        for pos in scan.positions:
            if pos.kind != "motion":
                named.setdefault(pos.key, []).append(pos)
    uses: dict[str, list[KrlUse]] = {}
    for scan in scans:
        for use in scan.uses:
            if not use.reason and use.name:
                uses.setdefault(use.name, []).append(use)

    resolved: dict[int, tuple[object, np.ndarray | None, str]] = {}

    def resolve(base: BaseRef) -> tuple[object, np.ndarray | None, str]:
        """(identity key, robot_T_base or None, reason), once per base object."""
        found = resolved.get(id(base))
        if found is None:
            found = resolved[id(base)] = _resolve(base)
            keep.append(base)  # the id stays valid while the object lives
        return found

    def _resolve(base: BaseRef) -> tuple[object, np.ndarray | None, str]:
        if base.kind == "fdat":
            entry = fdats.get(base.fdat or "")
            if entry is None:
                return None, None, f"FDAT {base.fdat} (line {base.line}) is not in the given files"
            if entry[0] is None:
                return None, None, entry[2]
            base = BaseRef("number", base.line, number=entry[0])
        if base.kind == "number":
            n = base.number
            if n in base_data:
                return ("n", n), base_data[n], ""
            if n == 0:
                return ("n", 0), np.eye(4), ""
            return None, None, f"BASE_DATA[{n}] is in neither the cell file nor --config-dat"
        if base.kind == "literal":
            return ("lit", base.xyzabc), pose_from_xyzabc(np.array(base.xyzabc)), ""
        return None, None, f"base unknown: {base.reason}"

    keep: list[BaseRef] = []
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
            reason = pos.reason
            frame = None
            if not reason and not opts.ignore_external_axes and not _EXTERNAL.isdisjoint(nums):
                moving = [k for k in _EXTERNAL_AXES if k in nums and nums[k].value != 0.0]
                if moving:
                    reason = (
                        f"external axis {moving[0]} = {pos.numbers[moving[0]].value:g}: the robot "
                        "frame depends on external kinematics (--ignore-external-axes if not)"
                    )
            if not reason and pos.kind == "motion":
                _, frame, reason = resolve(pos.base)
            elif not reason:
                frame, reason = _decl_frame(pos, named, uses, assigned, resolve, opts)
            if reason:
                row.reason = reason
                continue
            placed.append((pos, row, frame))
    for scan in scans:
        for use in scan.uses:
            if use.reason:
                rows.append(Row(scan.path or "", use.line, use.text, "skipped", use.reason))
            elif use.name not in named and not (
                use.name.endswith("[*]") and any(k.startswith(use.name[:-3] + "[") for k in named)
            ):
                rows.append(
                    Row(
                        scan.path or "",
                        use.line,
                        use.text,
                        "skipped",
                        f"{use.text} is not declared in the given files",
                    )
                )
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
    keep = check_orientation(frames[:, :3, :3], abc, [row for _, row, _ in placed], opts)
    if not keep.all():
        placed = [p for p, k in zip(placed, keep.tolist(), strict=True) if k]
        frames = frames[keep]
        if not placed:
            return
    base_xyz = np.array([row.old for _, row, _ in placed])  # (N, 3) mm, base frame
    robot = np.einsum("nij,nj->ni", frames[:, :3, :3], base_xyz) + frames[:, :3, 3]
    inside, corrected = correct_points(robot, opts)
    back = np.einsum("nji,nj->ni", frames[:, :3, :3], corrected - robot)  # R^T e
    targets = base_xyz + back
    for i in np.flatnonzero(~inside).tolist():
        row = placed[i][1]
        row.status, row.reason = "outside", outside_reason(robot[i])
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


def _decl_frame(pos, named, uses, assigned, resolve, opts) -> tuple[np.ndarray | None, str]:
    """The base of a .dat position from the motions that use it."""
    key = pos.key
    if len(named.get(key, ())) > 1:
        lines = ", ".join(str(p.line) for p in named[key])
        return None, f"{pos.name} is defined more than once (lines {lines})"
    wild = key.split("[")[0] + "[*]" if key.endswith("]") else None
    for k in (key, wild):
        if k in assigned:
            where = assigned[k]
            return None, f"{pos.name} is assigned at run time ({Path(where[0]).name}:{where[1]})"
    found = uses.get(key, []) + (uses.get(wild, []) if wild else [])
    if not found:
        if opts.base_override is not None:
            _, frame, reason = resolve(BaseRef("number", 0, number=opts.base_override))
            return frame, reason
        return None, (
            f"{pos.name} is not used by a motion in the given program, so its base is unknown "
            "(give the .src, or --base N)"
        )
    keys, frame = {}, None
    for use in found:
        ident, frame_i, reason = resolve(use.base)
        if reason:
            return None, f"used at line {use.line} where the {reason}"
        keys.setdefault(ident, use.line)
        frame = frame_i
    if len(keys) > 1:
        lines = ", ".join(str(line) for line in keys.values())
        return None, f"{pos.name} is used under different bases (lines {lines})"
    return frame, ""
