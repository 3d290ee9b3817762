"""Pre-flight correction of an existing KRL or G-code program (``accugrid rewrite``).

Each Cartesian position that can be placed in the robot frame is corrected with the grid model
(P' = P + e, in the robot frame, converted back to the program's frame) and only its X, Y, Z
numbers are replaced in the text; every other byte is kept. Files are handled as bytes decoded
as latin-1 (one character per byte, so any encoding and any line ending survives unchanged).

Rules (never guess; what cannot be placed is reported with the reason):
- KRL inline aggregates use the base in effect at that line (see ``codegen.krl.parse``); a
  position declared in a .dat takes the base of the motions that use it, and is corrected once
  however many motions use it. Unused .dat positions have no base unless ``base_override``.
- BASE_DATA[n] comes from ``--config-dat`` (if it defines n), else from the cell's ``base`` and
  ``base_data``; base 0 ($NULLFRAME, BAS(#BASE,0)) is the robot frame ($WORLD = $ROBROOT).
- G-code positions are in the cell's program frame (G54); A, B, C words are the tool
  orientation (as ``accugrid gcode`` writes them) and stay as written. A canned cycle's hole
  (X, Y, Z) is corrected, and its R plane by the Z correction at (X, Y, R). Axes a line does not
  write keep their commanded value; the report gives the remaining difference (``residual_mm``).
  Under G91 the increments are recomputed from the commanded (rewritten) previous position, so
  every later move lands where it should. Arcs are not corrected, nor the moves that set an
  arc's start.
- Positions outside the grid box stay as they are (an error with ``strict``).
"""

from __future__ import annotations

import hashlib
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accugrid.codegen import __version__
from accugrid.codegen.gcode.parse import GcodeMove, parse_gcode
from accugrid.codegen.krl.parse import BaseRef, KrlPosition, KrlUse, decimals_of, scan_krl
from accugrid.codegen.textsafe import comment_text, fixed, fixed_many
from accugrid.compensation import GridModel
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.inputfile import read_input_bytes

MAX_BYTES = 64 * 2**20
REPORT_COLUMNS = (
    "file,line,name,status,reason,x,y,z,x_new,y_new,z_new,dx,dy,dz,correction_mm,residual_mm"
)
KRL_SUFFIXES = (".src", ".dat", ".sub")
NAN3 = (math.nan, math.nan, math.nan)
_EXTERNAL_AXES = ("E1", "E2", "E3", "E4", "E5", "E6")
_EXTERNAL = frozenset(_EXTERNAL_AXES)
_FRACTION_RE = re.compile(r"\.(\d*)")


@dataclass
class Options:
    """How to rewrite. Frames are (4, 4) mm poses."""

    model: GridModel
    base_data: dict[int, np.ndarray]  # BASE_DATA[n] -> robot_T_base
    robot_T_program: np.ndarray  # G-code program frame
    iterations: int = 1
    power: float = 1.0
    decimals: int | None = None  # None: the file's precision (see ``precision``)
    strict: bool = False
    base_override: int | None = None
    trust_calls: bool = False
    ignore_external_axes: bool = False
    max_bytes: int = MAX_BYTES


@dataclass(slots=True)
class Row:
    """One position (or unresolved motion target) in the report."""

    file: str
    line: int
    name: str
    status: str  # "corrected", "outside", "skipped"
    reason: str = ""
    old: tuple[float, float, float] = NAN3  # position as written (program/base frame, mm)
    new: tuple[float, float, float] = NAN3  # as rewritten (corrected rows)
    residual_mm: float = math.nan


@dataclass
class Result:
    """Rewritten texts by input path (latin-1 str), the report rows and the largest correction."""

    texts: dict[str, str]
    rows: list[Row]

    @property
    def corrected(self) -> list[Row]:
        return [r for r in self.rows if r.status == "corrected"]

    def largest(self) -> tuple[float, Row | None]:
        best, where = 0.0, None
        for row in self.corrected:
            d = math.dist(row.new, row.old)
            if d > best:
                best, where = d, row
        return best, where


def read_program(path: str | os.PathLike[str], max_bytes: int = MAX_BYTES) -> str:
    """A program's bytes as latin-1 text (byte-preserving); InputError when unreadable or huge."""
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > max_bytes:
            raise InputError(
                f"file is {size / 2**20:.1f} MiB, over the limit of {max_bytes / 2**20:.1f} MiB "
                "(--max-mb)",
                os.fspath(path),
            )
        return read_input_bytes(path, max_bytes).decode("latin-1")
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror or exc}", os.fspath(path)) from None


def dialect(path: str | os.PathLike[str]) -> str:
    """ "krl" for .src/.dat/.sub, else "gcode"."""
    return "krl" if Path(path).suffix.lower() in KRL_SUFFIXES else "gcode"


def splice(text: str, edits: list[tuple[int, int, str]]) -> str:
    """Replace ``text[start:end]`` by each new string (non-overlapping edits, any order)."""
    if not edits:
        return text
    edits.sort()
    parts, last = [], 0
    for start, end, new in edits:
        parts.append(text[last:start])
        parts.append(new)
        last = end
    parts.append(text[last:])
    return "".join(parts)


def precision(literals) -> int:
    """A file's precision: the most decimals among its X, Y, Z literals (3 when it has none).

    CAM posts drop trailing zeros (``X25.``, ``X24.5``, ``X24.125`` are one precision), so a
    corrected number gets the file's precision, not its own digits."""
    joined = "\n".join(literals)
    if not joined:
        return 3
    if "e" in joined or "E" in joined:
        return max(map(decimals_of, joined.split("\n")))
    return max(map(len, _FRACTION_RE.findall(joined)), default=0)


def number_texts(
    old_texts: list[str], old_values: np.ndarray, new_values: np.ndarray, places: int
) -> list[str]:
    """New literals (N,) with ``places`` decimals; the old literal where the value is unchanged."""
    new_texts = fixed_many(new_values, places)
    same = np.array(list(map(float, new_texts))) == old_values
    return [o if k else n for o, n, k in zip(old_texts, new_texts, same.tolist(), strict=True)]


def _number_text(old_text: str, old_value: float, new_value: float, places: int) -> str:
    """The new literal with ``places`` decimals; the old one when the value does not change."""
    new_text = fixed(new_value, places)
    return old_text if float(new_text) == old_value else new_text


def _correct(points_robot: np.ndarray, opts: Options) -> tuple[np.ndarray, np.ndarray]:
    """(inside (N,) bool, corrected robot-frame points (N,3); NaN rows outside)."""
    out = np.full_like(points_robot, np.nan)
    if not len(points_robot):
        return np.zeros(0, bool), out
    inside = opts.model.contains(points_robot)
    if inside.any():
        out[inside] = opts.model.correct(
            points_robot[inside], iterations=opts.iterations, power=opts.power
        )
    return inside, out


def _outside_reason(robot_xyz: np.ndarray) -> str:
    x, y, z = (fixed(v) for v in robot_xyz)
    return f"outside the grid (robot frame {x}, {y}, {z} mm): left as is"


def _strict_check(rows: list[Row], opts: Options) -> None:
    if opts.strict:
        outside = [r for r in rows if r.status == "outside"]
        if outside:
            r = outside[0]
            raise InputError(
                f"{len(outside)} position(s) outside the grid (--strict); first: {r.name}: "
                f"{r.reason}",
                r.file,
                r.line,
            )


# ---------------------------------------------------------------- KRL


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
            p.numbers[k].literal for p in scan.positions for k in "XYZ" if k in p.numbers
        )
        for scan in scans
    }
    if placed:
        _correct_krl(placed, texts, edits, places_of, opts)
    _strict_check(rows, opts)
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
    base_xyz = np.array([row.old for _, row, _ in placed])  # (N, 3) mm, base frame
    unique: dict[int, int] = {}
    which = np.array([unique.setdefault(id(f), len(unique)) for _, _, f in placed])
    by_id = {id(f): f for _, _, f in placed}
    frames = np.array([by_id[k] for k in unique])[which]  # (N, 4, 4)
    robot = np.einsum("nij,nj->ni", frames[:, :3, :3], base_xyz) + frames[:, :3, 3]
    inside, corrected = _correct(robot, opts)
    back = np.einsum("nji,nj->ni", frames[:, :3, :3], corrected - robot)  # R^T e
    targets = base_xyz + back
    for i in np.flatnonzero(~inside).tolist():
        row = placed[i][1]
        row.status, row.reason = "outside", _outside_reason(robot[i])
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
        edits[file] += [
            (n.start, n.end, new)
            for n, old, new in zip(numbers, olds, news, strict=True)
            if new != old
        ]


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


# ---------------------------------------------------------------- G-code


def rewrite_gcode(path: str, text: str, opts: Options) -> Result:
    """Rewrite one RS274NGC program."""
    moves = parse_gcode(text, path)
    rows = [Row(path, m.line, m.motion, "skipped", m.reason) for m in moves]
    for m, row in zip(moves, rows, strict=True):
        row.old = m.target
    _protect_arc_starts(moves, rows)
    todo = [i for i, r in enumerate(rows) if not r.reason]
    desired = np.array([m.target for m in moves], dtype=float).reshape(-1, 3)
    if todo:
        prog = desired[todo]
        t = opts.robot_T_program
        robot = prog @ t[:3, :3].T + t[:3, 3]
        inside, corrected = _correct(robot, opts)
        back = (corrected - robot) @ t[:3, :3]  # R^T e, row-wise
        for j, i in enumerate(todo):
            if inside[j]:
                rows[i].status = "corrected"
                desired[i] = prog[j] + back[j]
            else:
                rows[i].status, rows[i].reason = "outside", _outside_reason(robot[j])
    r_planes = _corrected_r_planes(moves, rows, opts)
    edits = _gcode_edits(text, moves, rows, desired, r_planes, opts)
    _strict_check(rows, opts)
    return Result({path: splice(text, edits)}, rows)


def _protect_arc_starts(moves: list[GcodeMove], rows: list[Row]) -> None:
    """An arc keeps its start point: the moves that set it are not corrected either."""
    for i, m in enumerate(moves):
        if not m.is_arc:
            continue
        if m.incremental:
            for j in range(i):
                rows[j].reason = rows[j].reason or (
                    f"precedes the incremental arc at line {m.line}, whose start must not move"
                )
            continue
        why = f"sets the start of the arc at line {m.line}, which is not corrected"
        for j in m.setters:
            if j is not None and not rows[j].reason:
                rows[j].reason = why


def _corrected_r_planes(moves: list[GcodeMove], rows: list[Row], opts: Options) -> np.ndarray:
    """(N,) corrected R plane (mm) of each corrected cycle that writes R; NaN: keep R.

    The R point is (X, Y, R) of the hole; only its Z correction can be written."""
    out = np.full(len(moves), np.nan)
    idx = [
        i
        for i, (m, r) in enumerate(zip(moves, rows, strict=True))
        if m.is_cycle and "R" in m.words and r.status == "corrected"
    ]
    if idx:
        pts = np.array([[moves[i].target[0], moves[i].target[1], moves[i].r_mm] for i in idx])
        t = opts.robot_T_program
        robot = pts @ t[:3, :3].T + t[:3, 3]
        inside, corrected = _correct(robot, opts)
        back = (corrected - robot) @ t[:3, :3]
        for j, i in enumerate(idx):
            if inside[j]:
                out[i] = pts[j, 2] + back[j, 2]
    return out


def _gcode_edits(
    text: str,
    moves: list[GcodeMove],
    rows: list[Row],
    desired: np.ndarray,
    r_planes: np.ndarray,
    opts: Options,
) -> list[tuple[int, int, str]]:
    """Walk the program with the commanded (rewritten) position; new word numbers.

    ``desired`` (N, 3) mm: where each move should land (program frame); ``r_planes`` (N,) mm:
    corrected R planes (NaN: keep). Absolute words are formatted in one pass beforehand; only
    increments (which depend on what was written before) are formatted on the way."""
    edits: list[tuple[int, int, str]] = []
    if opts.decimals is not None:
        places = opts.decimals
    else:
        places = precision(w.literal for m in moves for k, w in m.words.items() if k in "XYZ")
    scales = np.array([m.scale for m in moves]).reshape(-1, 1)
    corrected = np.array([r.status == "corrected" for r in rows]).reshape(-1, 1)
    absolute = _formatted(np.where(corrected, desired / scales, np.nan).ravel(), places)
    r_texts = _formatted(r_planes / scales[:, 0], places)
    reached_rows: list[tuple[Row, list[float]]] = []
    reached_at: list[int] = []  # the move of each reached_rows entry
    cmd = [math.nan] * 3
    cycle_z = r_cmd = math.nan
    for n, (move, row) in enumerate(zip(moves, rows, strict=True)):
        if move.motion in ("G28", "G30", "G53"):
            cmd = [math.nan] * 3
            continue
        changed = row.status == "corrected"
        incremental = move.incremental and not move.is_cycle
        end = list(cmd)
        for i, k in enumerate("XYZ"):
            word = move.words.get(k)
            if word is None:
                continue
            old_text = new_text = word.literal
            if incremental:
                goal = float(desired[n, i])
                if not (math.isnan(cmd[i]) or math.isnan(goal)):
                    value = (goal - cmd[i]) / move.scale
                    new_text = _number_text(old_text, word.value, value, places)
            elif changed and absolute[3 * n + i] is not None:
                new_text = absolute[3 * n + i]
                if float(new_text) == word.value:
                    new_text = old_text
            if new_text != old_text:
                edits.append((word.start, word.end, new_text))
            written = float(new_text) * move.scale
            if move.is_cycle and i == 2:
                cycle_z = written
            elif incremental:
                end[i] = cmd[i] + written
            else:
                end[i] = written
        if move.is_cycle and "R" in move.words:
            word = move.words["R"]
            new_text = word.literal
            if r_texts[n] is not None and float(r_texts[n]) != word.value:
                new_text = r_texts[n]
                edits.append((word.start, word.end, new_text))
            r_cmd = float(new_text) * move.scale
        if move.is_cycle:
            reached = [end[0], end[1], cycle_z]
            if move.incremental or math.isnan(move.r_mm):
                end = [end[0], end[1], math.nan]
            elif move.retract == "G99":
                end = [end[0], end[1], r_cmd]
            else:
                end = [end[0], end[1], max(cmd[2], r_cmd)]
        else:
            reached = end
        if changed:
            reached_rows.append((row, reached))
            reached_at.append(n)
        cmd = end
    if reached_rows:
        reached = np.array([new for _, new in reached_rows])
        residual = np.linalg.norm(reached - desired[reached_at], axis=1).tolist()
        for (row, new), res in zip(reached_rows, residual, strict=True):
            row.new, row.residual_mm = tuple(new), res
    return edits


def _formatted(values: np.ndarray, places: int) -> list[str | None]:
    """``fixed`` text of each value (N,), None where NaN."""
    finite = np.flatnonzero(np.isfinite(values))
    out: list[str | None] = [None] * len(values)
    for i, text in zip(finite.tolist(), fixed_many(values[finite], places), strict=True):
        out[i] = text
    return out


# ---------------------------------------------------------------- files


def header_lines(result: Result, program: str, cell: str, opts: Options) -> list[str]:
    """DESIGN.md header: accugrid version, input and grid SHA-256, grid step, largest correction.

    File names only (no directories, no dates), so the same inputs give the same bytes."""
    largest, where = result.largest()
    model = opts.model
    step = " x ".join(fixed(s) for s in model.step)
    at = "" if where is None else f" at {where.name} line {where.line}"
    grid = Path(model.source_path).name if model.source_path else "arrays"
    return [
        f"accugrid {__version__} rewrite",
        f"program {Path(program).name} sha256 {_sha256(program)}",
        f"cell {Path(cell).name} sha256 {_sha256(cell)}",
        f"grid {grid} sha256 {model.source_sha256}",
        f"grid step {step} mm",
        f"largest correction {fixed(largest)} mm{at}",
        f"positions corrected {len(result.corrected)}",
    ]


def _sha256(path: str) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def add_header(text: str, lines: list[str], kind: str) -> str:
    """Insert comment lines after the leading ``&`` (KRL) or ``%`` (G-code) lines."""
    newline = "\r\n" if "\r\n" in text else "\n"
    body = [comment_text(line, 200) for line in lines]
    block = "".join((f"; {b}" if kind == "krl" else f"({b})") + newline for b in body)
    pos = 3 if text.startswith("\xef\xbb\xbf") else 0  # after a UTF-8 byte-order mark
    lead = "&" if kind == "krl" else "%"
    while text.startswith(lead, pos):
        nl = text.find("\n", pos)
        if nl < 0:
            return text + newline + block
        pos = nl + 1
    return text[:pos] + block + text[pos:]


def report_csv(rows: list[Row], decimals: int = 4) -> str:
    """The report as CSV text (DESIGN.md style: header row, mm, ``decimals`` places)."""
    corrected = ",".join([f"%.{decimals}f"] * 11)  # x..z, x_new..z_new, dx..dz, length, residual
    old_only = ",".join([f"%.{decimals}f"] * 3) + ",,,,,,,,"
    names: dict[str, str] = {}
    out = [REPORT_COLUMNS]
    for r in rows:
        file = names.get(r.file) or names.setdefault(r.file, _csv(Path(r.file).name))
        head = f"{file},{r.line},{_csv(r.name)},{r.status},{_csv(r.reason)},"
        if r.status == "corrected":
            (x, y, z), (u, v, w) = r.old, r.new
            dx, dy, dz = u - x, v - y, w - z
            length = math.sqrt(dx * dx + dy * dy + dz * dz)
            numbers = corrected % (x, y, z, u, v, w, dx, dy, dz, length, r.residual_mm)
        elif r.old[0] == r.old[0] and r.old[1] == r.old[1] and r.old[2] == r.old[2]:
            numbers = old_only % r.old
        else:
            numbers = ",,,,,,,,,,"
        out.append(head + numbers.replace("-0.0000,", "0.0000,").replace("nan", ""))
    return "\n".join(out) + "\n"


def _csv(text: str) -> str:
    if "," not in text and '"' not in text and "\n" not in text and "\r" not in text:
        return text
    text = text.replace("\r", " ").replace("\n", " ")
    if any(c in text for c in ',"'):
        return '"' + text.replace('"', '""') + '"'
    return text
