"""Pre-flight rewrite of FANUC TP programs (``.ls``); see ``codegen.rewrite`` for what a rewrite
is, ``parse`` for how a program is read.

A /POS position is corrected when it is a Cartesian position of group 1 that only ``J``, ``L``,
``C`` or ``A`` moves go to, in the cell's user frame (``base.number``, whose frame is the
cell's base) or in user frame 0 (the world frame: a FANUC robot file's robot frame), with the
cell's tool frame (``tool.number``; the tool numbers of the cell's ``tool_data`` too). Left as
they are, with the reason in the report: joint positions (``J1 = .. deg``), remote-TCP
positions, positions in another user frame, in a user frame or tool frame the body sets at run
time (``UFRAME[n]=..``, ``UTOOL[n]=..``) or selects by a register, in a user frame the body
never selects while it selects others, positions moved with ``Offset``/``Tool_Offset``/``INC``
(the register's value is not in the file), by coordinated (``COORD``) or remote-TCP (``RTCP``)
motion, read by another instruction, with other motion groups or extended axes (unless
``--ignore-external-axes``), or not used by a motion. A motion to a position register
(``PR[n]``), to an indirect position (``P[R[n]]``) or to a P[n] /POS does not hold is a row of
its own, never corrected; like a commanded position left as it is, it fails the job unless
``--allow-partial``. Only the X, Y, Z numbers of a corrected position change (the file's
decimals, at least 0.01 mm); W, P, R, CONFIG and every other byte stay. The policy holds each
position against the configuration its CONFIG names (``configuration``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from accugrid.codegen.fanuc.configuration import read_configuration, words_of_config
from accugrid.codegen.fanuc.emit import header_remarks
from accugrid.codegen.fanuc.parse import LsProgram, read_ls
from accugrid.codegen.plugin_types import CORRECTED, Options, Rows, Scan
from accugrid.codegen.program_text import MIN_PLACES_MM, check_text, precision
from accugrid.codegen.splice import ByteSplicer, literals
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix

__all__ = ["FanucPlacement", "add_header", "scan_positions", "splice_positions"]

_LINE_COUNT = re.compile(r"^(?:LINE_COUNT|ZEILEN)\s*=\s*(\d+)", re.M)


@dataclass(frozen=True)
class FanucPlacement:
    """What places /POS positions in the robot frame besides the program's text (the plug-in's
    ``placement``): the cell's FANUC ``section`` (its user frame, tool frame and the user
    frame's pose) and whether positions with other motion groups or extended axes are
    corrected (``ignore_external_axes``)."""

    section: object
    ignore_external_axes: bool = False


@dataclass
class _Found:
    """The positions of one program as columns: a row per Cartesian or remote-TCP /POS entry
    (``positions``), in its order, then a row per motion to a position that is not in /POS
    (``unplaced``: line, name, reason: a register, an indirect or a missing P[n]); the joint
    positions as report rows of data never corrected (``others``: line, name, reason)."""

    text: str
    path: str
    program: LsProgram
    positions: list
    reason: list[str]
    commanded: np.ndarray
    frame: np.ndarray  # 0 world, 1 the cell's user frame, -1 not placed
    places: int
    others: list[tuple[int, str, str]]
    unplaced: list[tuple[int, str, str]]


def _uses(program: LsProgram) -> dict[int, list]:
    """P number -> the instructions that name it, with how (``"move"``/``"read"``)."""
    uses: dict[int, list] = {}
    for ins in program.instructions:
        for n in ins.targets:
            uses.setdefault(n, []).append(("move", ins))
        for n in ins.reads:
            uses.setdefault(n, []).append(("read", ins))
    return uses


def _frame_reason(program: LsProgram, kind: str, number: int) -> str:
    """Why the body leaves user frame (``kind`` "uf") or tool frame ("ut") ``number`` unknown,
    "" when it does not."""
    what = "user frame" if kind == "uf" else "tool frame"
    for line, value in program.assigns[kind]:
        if not value.isdigit() or int(value) == number:
            return f"{what} {number} is set at run time (line {line})"
    literal = [int(v) for _, v in program.selects[kind] if v.isdigit()]
    for line, value in program.selects[kind]:
        if not value.isdigit():
            return f"the {what} is selected by {value} at run time (line {line})"
    if literal and number not in literal:
        chosen = ", ".join(map(str, sorted(set(literal))))
        return f"{what} {number} is never selected (the program selects {chosen})"
    return ""


def _judge(path: str, text: str, section, opts: Options, ignore_external_axes: bool) -> _Found:
    """Every /POS position of one program read and judged."""
    check_text(text, path)
    program = read_ls(path, text)
    uses = _uses(program)
    positions = [p for p in program.positions if p.kind in ("cartesian", "remote")]
    others = [
        (p.line, f"P[{p.number}]", _reason(program, p, [], [], section, opts, False))
        for p in program.positions
        if p.kind not in ("cartesian", "remote")
    ]
    n = len(positions)
    reason = [""] * n
    commanded = np.zeros(n, bool)
    frame = np.full(n, -1, np.int64)
    for i, p in enumerate(positions):
        mine = uses.get(p.number, [])
        moves = [ins for how, ins in mine if how == "move"]
        commanded[i] = bool(moves)
        reason[i] = _reason(program, p, mine, moves, section, opts, ignore_external_axes)
        if not reason[i]:
            frame[i] = 0 if p.uf == 0 else 1
    places = precision([t for p in positions for t in p.literals], MIN_PLACES_MM)
    recorded = {p.number for p in program.positions}
    unplaced = [
        (ins.line, name, _WHY_UNKNOWN[name[:2]])
        for ins in program.instructions
        for name in ins.unknown
    ]
    unplaced += [
        (ins.line, f"P[{n}]", "no position P[n] in /POS")
        for ins in program.instructions
        for n in ins.targets
        if n not in recorded
    ]
    return _Found(
        text, path, program, positions, reason, commanded, frame, places, others, unplaced
    )


_WHY_UNKNOWN = {
    "PR": "a position register: its value is not in the file",
    "P[": "an indirect position: its number is known at run time",
}


def _reason(program, p, mine, moves, section, opts, ignore_external_axes) -> str:
    """Why position ``p`` is left as it is, "" when it is placed in the robot frame."""
    if p.kind == "joint":
        return "joint position (J1..J6): never corrected"
    if p.kind == "remote":
        return "remote-TCP position (RX..RR): relative to a stationary tool"
    if p.kind == "none":
        return "no position of motion group 1"
    if not mine:
        return "not used by a motion"
    for how, ins in mine:
        if how == "read":
            return f"read at line {ins.line}, not only a motion's target"
    for ins in moves:
        if ins.offset:
            return (
                f"moved with {ins.offset} at line {ins.line}: the register's value is not in "
                "the file"
            )
        if ins.coord:
            return f"coordinated motion (COORD) at line {ins.line}: relative to the leader"
        if ins.rtcp:
            return f"remote-TCP motion (RTCP) at line {ins.line}"
    if not ignore_external_axes and (p.groups or p.extended):
        what = ", ".join([f"GP{g}" for g in p.groups] + list(p.extended))
        return f"other axes in the position ({what}; --ignore-external-axes corrects it)"
    if p.uf not in (0, section.uframe):
        return (
            f"user frame {p.uf} is not the cell's ({section.uframe}, base.number) nor the world "
            "frame 0"
        )
    if p.config and words_of_config(p.config) is None:
        return f"CONFIG '{p.config}' is not one accugrid reads"
    why = _frame_reason(program, "uf", p.uf) if p.uf else ""
    why = why or _frame_reason(program, "ut", p.ut)
    if why:
        return why
    if opts.tool_data is None and p.ut != section.utool:
        return (
            f"tool frame {p.ut} is not the cell's ({section.utool}, tool.number): declare it in "
            "the cell file's tool_data"
        )
    return ""


def scan_positions(texts: dict[str, str], opts: Options, placement: FanucPlacement) -> Scan:
    """The /POS positions of TP programs (path -> latin-1 text) placed in the frames of the
    cell's FANUC section; InputError where a program has no position (unless
    ``opts.allow_partial``)."""
    section = placement.section.check()
    frames = np.stack([np.eye(4), section.robot_T_uframe])
    parts, others, found_all, robot, rotations, status, at = [], [], [], [], [], [], []
    start = 0
    for path, text in texts.items():
        found = _judge(path, text, section, opts, placement.ignore_external_axes)
        positions = found.positions
        n, u = len(positions), len(found.unplaced)
        if not n + u and not opts.allow_partial:
            what = f"; {len(found.others)} joint position(s) left" if found.others else ""
            raise InputError(
                f"no Cartesian /POS position in this program: nothing to correct{what}", path, 1
            )
        xyz = np.full((n + u, 3), np.nan)
        wpr = np.full((n, 3), np.nan)
        for i, p in enumerate(positions):
            if p.kind == "cartesian":
                xyz[i], wpr[i] = p.values[:3], p.values[3:]
        rows = Rows(
            [path],
            np.zeros(n + u, np.int64),
            np.array([p.line for p in positions] + [r[0] for r in found.unplaced], np.int64),
            [f"P[{p.number}]" for p in positions] + [r[1] for r in found.unplaced],
            found.reason + [r[2] for r in found.unplaced],
            xyz,
        )
        rows.commanded[:n] = found.commanded
        rows.commanded[n:] = True  # a motion goes there
        rows.tool[:n] = [p.ut if p.ut != section.utool else -1 for p in positions]
        mine = np.flatnonzero(found.frame >= 0)
        t = frames[found.frame[mine]]
        robot.append(np.einsum("nij,nj->ni", t[:, :3, :3], xyz[mine]) + t[:, :3, 3])
        rotations.append(t[:, :3, :3] @ abc_to_matrix(wpr[mine][:, ::-1]))  # A, B, C = R, P, W
        status.append(_codes([positions[i].config for i in mine.tolist()]))
        at.append(start + mine)
        parts.append(rows)
        k = len(found.others)
        others.append(
            Rows(
                [path],
                np.zeros(k, np.int64),
                np.array([o[0] for o in found.others], np.int64),
                [o[1] for o in found.others],
                [o[2] for o in found.others],
                np.full((k, 3), np.nan),
            )
        )
        found_all.append((found, start, mine, xyz))
        start += n + u
    return Scan(
        Rows.concat(parts),
        np.concatenate(at or [np.zeros(0, np.int64)]),
        np.concatenate(robot or [np.zeros((0, 3))]),
        np.concatenate(rotations or [np.zeros((0, 3, 3))]),
        np.concatenate(status or [np.zeros(0, np.int64)]),
        others=Rows.concat(others),
        state=(frames, found_all),
    )


def _codes(configs: list[str]) -> np.ndarray:
    """The configuration codes (N,) of CONFIG texts (N,) ("": none, -1), so that the policy
    holds each position against the configuration its grid was measured in."""
    out = np.full(len(configs), -1, np.int64)
    given = [i for i, text in enumerate(configs) if text]
    if given:
        words = np.array([words_of_config(configs[i]) for i in given], np.int64)
        out[given] = read_configuration(words).code
    return out


def splice_positions(scan: Scan, corrected: np.ndarray, opts: Options) -> dict[str, bytearray]:
    """Every program's bytes with the X, Y, Z of its corrected positions (``corrected`` (M, 3) mm
    robot frame, NaN rows: not corrected) written back in their user frames."""
    frames, found_all = scan.state
    rows, data, k = scan.rows, {}, 0
    for found, start, mine, xyz in found_all:
        t = frames[found.frame[mine]]
        e = corrected[k : k + mine.size] - scan.robot[k : k + mine.size]
        k += mine.size
        back = np.einsum("nji,nj->ni", t[:, :3, :3], e)  # R^T e: the correction in the frame
        done = np.flatnonzero(np.isfinite(e[:, 0]))
        rows_done = mine[done]
        new = xyz[rows_done] + back[done]
        places = found.places if opts.decimals is None else opts.decimals
        text_bytes, lengths, written = literals(new.ravel(), places)
        written = written.reshape(-1, 3)
        rows.status[start + rows_done] = CORRECTED
        rows.new[start + rows_done] = written
        rows.rounding_mm[start + rows_done] = np.linalg.norm(written - new, axis=1)
        spans = np.array([found.positions[i].spans for i in rows_done.tolist()], np.int64).reshape(
            -1, 2
        )
        out = ByteSplicer(found.text)
        if len(spans):
            out.add(spans[:, 0], spans[:, 1], text_bytes, lengths)
        data[found.path] = out.finish()
    return data


def add_header(text: str, lines: list[str]) -> str:
    """The program with the header as remarks at the top of /MN, numbered from 1, the lines
    after it numbered on (their digits only change), in the program's line ending."""
    program = read_ls("", text)
    newline = "\r\n" if "\r\n" in text else "\n"
    remarks = header_remarks(lines)
    block = "".join(f"{k + 1:4d}:  !{r} ;{newline}" for k, r in enumerate(remarks))
    at = program.mn
    if text.startswith("\r\n", at):
        at += 2
    elif text.startswith(("\n", "\r"), at):
        at += 1
    else:
        block = newline + block
    shift = len(remarks)
    count = _LINE_COUNT.search(text, 0, program.mn)
    if count is not None:  # /ATTR's count of the /MN lines
        head = text[: count.start(1)] + str(int(count.group(1)) + shift) + text[count.end(1) : at]
    else:
        head = text[:at]
    pieces, last = [head, block], at
    for start, end, number in program.numbers:  # the digits only: every other byte stays
        pieces += (text[last:start], str(number + shift))
        last = end
    pieces.append(text[last:])
    return "".join(pieces)
