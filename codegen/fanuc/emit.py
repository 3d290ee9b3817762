"""FANUC TP for a Program: one ASCII program ``NAME.ls`` (``templates/fanuc/program.ls.j2``).

``/PROG NAME`` (the cell's ``fanuc.program``, else the output file's stem, upper-cased: a name
the controller takes, ``names``), ``/ATTR``, ``/MN`` and ``/POS``. The /MN lines are numbered
1, 2, ... in order (right-aligned in four columns, as the controller writes them): the header
as remarks of at most 32 characters, ``UFRAME_NUM`` and ``UTOOL_NUM`` (the cell's base and
tool numbers), the spindle output on, then per hole a remark (id, depth, diameter), ``J`` to the
approach point (``fanuc.joint_percent`` %, ``CNT`` ``fanuc.cnt``), ``L`` to the clearance point
at the approach speed ``FINE``, ``L`` to the bottom at the hole's feed ``FINE``, ``WAIT`` the
dwell, ``L`` back to the retract point; the spindle off. Linear speeds are whole mm/sec, as the
controller takes them.

Every pose is a Cartesian ``P[n]`` of GP1 in the user frame and tool frame of the cell (its
base frame and TCP), X, Y, Z mm and W, P, R deg: fixed angles about X, Y, Z (R = Rz(R) Ry(P)
Rx(W), scipy's extrinsic ``"xyz"``), with the ``CONFIG`` of the joint angles the program's IK
check solved it with (``configuration``). Numbers go through ``textsafe`` only; hole ids only into
remarks (sanitised). The lines of the holes are made by numpy from one template per hole
(``codegen.linebytes``), a block of ``BLOCK`` holes at a time as the pieces are taken.
"""

from __future__ import annotations

import os
import textwrap
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from accugrid.codegen.fanuc.configuration import configuration_words
from accugrid.codegen.fanuc.names import program_name_problem
from accugrid.codegen.fanuc.section import WHOLE_SPEED
from accugrid.codegen.linebytes import (
    SLOT,
    image_bytes,
    line_image,
    number_cells,
    text_cells,
)
from accugrid.codegen.program import Program
from accugrid.codegen.program_text import stem_name
from accugrid.codegen.render import environment, printed_plainly, render_around, template_dir
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import comment_text, comment_texts, fixed
from accugrid.kinematics.frames import matrix_to_abc

__all__ = [
    "BLOCK",
    "HOLE_LINES",
    "REMARK_MAX",
    "header_remarks",
    "program_name",
    "render_fanuc",
]

BLOCK = 16384  # holes whose lines are made at a time
HOLE_LINES = 6  # /MN lines of a hole
REMARK_MAX = 32  # characters of a remark (! ...)
_NEWLINE = "\r\n"
_HOLES = "\x00accugrid holes\x00"  # where the hole lines go (no program text holds a NUL)
_POSITIONS = "\x00accugrid positions\x00"
_COUNT = "\x00accugrid line count\x00"


def program_name(section_program: str | None, out: Path) -> str:
    """The program name: the cell's ``fanuc.program`` (validated when the cell was read), else
    the stem of the output file, upper-cased; InputError naming the file when the controller
    refuses it."""
    if section_program is not None:
        return section_program
    return stem_name(out, "program", "fanuc.program", program_name_problem).upper()


def header_remarks(lines: list[str]) -> list[str]:
    """The header ``lines`` as remarks of at most ``REMARK_MAX`` characters, each line wrapped
    into as many as it needs (made safe first)."""
    out = []
    for line in lines:
        out += textwrap.wrap(comment_text(line, 200), REMARK_MAX) or [""]
    return out


def render_fanuc(
    program: Program, header: list[str], templates=None, out: Path = Path("ACCUGRID.ls")
) -> dict[Path, Iterator[str | bytes]]:
    """{out: the program's text in pieces}: the frame rendered by Jinja around the hole lines and
    the positions, which follow in blocks of ``BLOCK`` holes as the pieces are taken, the CONFIG
    of each as soon as the program's IK check has reached it. InputError at the hole whose
    feed is not a whole number of mm/sec."""
    cell = program.cell
    section = cell.dialects["fanuc"].check()
    feed = program.points.feed  # the points' own feeds (the cell's: checked with the cell)
    slow = np.flatnonzero(np.isfinite(feed) & ((feed != np.round(feed)) | (feed < 1)))
    if slow.size:
        i = int(slow[0])
        raise InputError(
            f"{program.points.name(i)}: feed {feed[i]:g} mm/s: {WHOLE_SPEED}",
            *program.points.table.where(i, "feed"),
        )
    env = environment(template_dir("fanuc", templates), newline=_NEWLINE)
    template = "program.ls.j2"
    for name in ("hole_lines", "position_lines"):
        if not printed_plainly(env, template, name):
            raise InputError(
                f"the template prints {name} other than plainly ({{{{ {name} }}}}), once",
                os.fspath(template_dir("fanuc", templates) / template),
            )
    context = dict(
        program=program_name(section.program, out),
        header=header_remarks(program.header(header)),
        uframe=section.uframe,
        utool=section.utool,
        spindle=section.spindle,
        line_count=_COUNT,
        position_lines=_POSITIONS,
    )
    pieces = render_around(env, template, "hole_lines", **context)
    if len(pieces) != 2 or pieces[1].count(_POSITIONS) != 1:
        raise InputError(
            "the template must print hole_lines and position_lines once each, in this order",
            os.fspath(template_dir("fanuc", templates) / template),
        )
    before, rest = pieces
    between, after = rest.split(_POSITIONS)
    mn_at = before.find(f"/MN{_NEWLINE}")
    if mn_at < 0:
        raise InputError(
            "the template has no /MN line", os.fspath(template_dir("fanuc", templates))
        )
    mn_at += len(f"/MN{_NEWLINE}")
    pos_at = between.find("/POS")
    head_lines = _lines(before[mn_at:])
    tail_lines = _lines(between[:pos_at])
    first = len(head_lines) + 1  # the number of the first hole line
    after_holes = first + HOLE_LINES * len(program)
    count = after_holes - 1 + len(tail_lines)
    head = before[:mn_at].replace(_COUNT, str(count)) + _numbered(head_lines, 1)
    middle = _numbered(tail_lines, after_holes) + between[pos_at:]
    return {out: _pieces(program, cell, section, head, middle, after, first)}


def _lines(text: str) -> list[str]:
    """The instruction lines of a piece of /MN (empty lines dropped)."""
    return [line for line in text.split(_NEWLINE) if line.strip()]


def _numbered(lines: list[str], start: int) -> str:
    """``lines`` numbered from ``start``, as the controller writes them (``%4d:``)."""
    return "".join(f"{start + k:4d}:{line}{_NEWLINE}" for k, line in enumerate(lines))


def _pieces(program, cell, section, head, middle, after, first) -> Iterator[str | bytes]:
    """The program: ``head`` (to the last numbered line before the holes), the hole lines,
    ``middle`` (to /POS), the positions, ``after`` (from /END)."""
    yield head
    blocks = range(0, len(program), BLOCK)
    for lo in blocks:
        yield _hole_bytes(program, cell, section, lo, first)
    yield middle
    for lo in blocks:
        yield _position_bytes(program, section, lo)
    yield after.removeprefix(_NEWLINE)  # the line end after the positions: theirs


def _line_numbers(numbers: np.ndarray) -> np.ndarray:
    """Cells (n, w) of line numbers right-aligned in four columns: the NULs of the last four
    columns made spaces (the rest are dropped)."""
    cells = number_cells(numbers, 0)
    if cells.shape[-1] < 4:
        pad = np.zeros((*cells.shape[:-1], 4 - cells.shape[-1]), np.uint8)
        cells = np.concatenate([pad, cells], axis=-1)
    tail = cells[..., -4:]
    tail[tail == 0] = ord(" ")
    return cells


def _hole_template(section, approach: str, dwell: str) -> str:
    """The /MN lines of one hole for ``linebytes.line_image``: slots for the line numbers, the
    remark, the P numbers and the feed."""
    n = _NEWLINE
    return (
        f"{SLOT}:  !{SLOT} ;{n}"
        f"{SLOT}:J P[{SLOT}] {section.joint_percent}% CNT{section.cnt} ;{n}"
        f"{SLOT}:L P[{SLOT}] {approach}mm/sec FINE ;{n}"
        f"{SLOT}:L P[{SLOT}] {SLOT}mm/sec FINE ;{n}"
        f"{SLOT}:  WAIT {dwell}(sec) ;{n}"
        f"{SLOT}:L P[{SLOT}] {approach}mm/sec CNT{section.cnt} ;{n}"
    )


def _hole_bytes(program, cell, section, lo: int, first: int) -> bytes:
    """The /MN lines of holes lo..lo+BLOCK-1."""
    hi = min(lo + BLOCK, len(program))
    holes = np.arange(lo, hi)
    lines = _line_numbers(first + HOLE_LINES * holes[:, None] + np.arange(HOLE_LINES))
    points = number_cells(4 * holes[:, None] + np.arange(1, 5), 0)
    labels = text_cells(comment_texts(program.labels(lo, hi), REMARK_MAX))
    feed = number_cells(program.feed_mm_s[lo:hi], 0)
    cells = [lines[:, 0], labels, lines[:, 1], points[:, 0], lines[:, 2], points[:, 1]]
    cells += [lines[:, 3], points[:, 2], feed, lines[:, 4], lines[:, 5], points[:, 3]]
    approach = fixed(cell.drilling.approach_mm_s, 0)
    template = _hole_template(section, approach, fixed(cell.drilling.dwell_s, 2))
    return image_bytes(line_image(template, cells))


_POSITION = (
    f"P[{SLOT}]{{{_NEWLINE}"
    f"   GP1:{_NEWLINE}"
    f"\tUF : %d, UT : %d,\t\tCONFIG : '{SLOT} {SLOT} {SLOT}, {SLOT}, {SLOT}, {SLOT}',{_NEWLINE}"
    f"\tX = {SLOT}  mm,\tY = {SLOT}  mm,\tZ = {SLOT}  mm,{_NEWLINE}"
    f"\tW = {SLOT} deg,\tP = {SLOT} deg,\tR = {SLOT} deg{_NEWLINE}"
    f"}};{_NEWLINE}"
)


_LETTERS = np.array([[ord("N"), ord("F")], [ord("D"), ord("U")], [ord("T"), ord("B")]], np.uint8)


def _position_bytes(program, section, lo: int) -> bytes:
    """The /POS entries of holes lo..lo+BLOCK-1, four per hole (P numbers 4h+1 .. 4h+4)."""
    hi = min(lo + BLOCK, len(program))
    words = configuration_words(program.configuration_of(lo, hi)).reshape(-1, 6)
    letters = [_LETTERS[k][words[:, k], None] for k in range(3)]  # (n, 1) each
    turns = words[:, 3:]
    wpr = matrix_to_abc(program.rotations[lo:hi])[:, ::-1]  # W, P, R = C, B, A
    places = section.decimals
    numbers = number_cells(np.arange(4 * lo + 1, 4 * hi + 1), 0)
    turn = number_cells(turns, 0)
    xyz = number_cells(program.positions[lo:hi].reshape(-1, 3), places)
    angles = np.repeat(number_cells(wpr, 3), 4, axis=0)  # one orientation per hole
    cells = [numbers, *letters]
    cells += [turn[:, k] for k in range(3)] + [xyz[:, k] for k in range(3)]
    cells += [angles[:, k] for k in range(3)]
    template = _POSITION % (section.uframe, section.utool)
    return image_bytes(line_image(template, cells))
