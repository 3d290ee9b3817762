"""RS274NGC (LinuxCNC dialect) for a Program: one ``.ngc`` from ``templates/gcode/program.ngc.j2``.

Positions are the TCP in the program frame (``robot_T_program`` of the cell's G-code section,
default BASE), mm; orientation as A B C words = the KUKA A, B, C of the tool in that frame, deg
(stated in the file header). Per hole: ``G0`` to the approach point with A B C; where the drill axis
is the program's -Z (all four positions of the hole share X and Y at the printed precision) and
``gcode.canned_cycles`` is on, a canned cycle from the clearance plane R: ``G83`` with peck Q when
``drilling.peck`` > 0, else ``G82`` with the dwell P, else ``G81``; ``G98`` returns to the approach
height, then ``G0 Z`` to the retract point if that differs. Otherwise explicit moves along the drill
axis: ``G1`` to the clearance point at approach speed, ``G1`` to the bottom at the feed, ``G4``
dwell, ``G1`` back to the retract point at approach speed. Feeds are mm/min (``G94``).

Numbers go through ``fixed`` only: per-hole numbers are formatted once in Python
(``program.decimals`` for mm and deg, 1 decimal for F; ``textsafe.fixed_bytes`` for the hole
lines, ``fixed_texts`` for the records) and reach the template as text; the template formats its
scalar settings with the ``fixed`` filter. Jinja renders the frame of the file; the built-in
template prints ``hole_lines``, every hole's lines built as bytes by numpy from one template per
kind of hole (``codegen.linebytes``), while the records ``holes`` stay available to a user
template that loops over them (built only if the template refers to them).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import NamedTuple

import numpy as np

from accugrid.codegen.cell_record import Cell
from accugrid.codegen.linebytes import (
    SLOT,
    image_bytes,
    line_image,
    merge_images,
    number_cells,
    text_cells,
)
from accugrid.codegen.program import Program
from accugrid.codegen.render import (
    environment,
    printed_plainly,
    render,
    render_around,
    template_dir,
    template_uses,
)
from accugrid.infra.textsafe import comment_texts, fixed, fixed_same, fixed_texts

__all__ = ["BLOCK", "GcodeHole", "canned", "gcode_text", "render_gcode"]


class GcodeHole(NamedTuple):
    """One hole; coordinates (X, Y, Z), A B C and the feed already formatted by ``fixed``."""

    label: str
    app: tuple[str, str, str]
    clr: tuple[str, str, str]
    bot: tuple[str, str, str]
    ret: tuple[str, str, str]
    abc: tuple[str, str, str]
    feed: str  # mm/min
    canned: bool
    retract_move: bool


def canned(pos: np.ndarray, decimals: int) -> np.ndarray:
    """Holes (N,) that allow a canned cycle, from their positions ``pos`` (N, 4, 3) mm (APP, CLR,
    BOT, RET) printed with ``decimals``: the same printed X and Y, and Z going down from approach
    over clearance to the bottom (the drill axis is the program's -Z), with the retract above the
    clearance."""
    same_xy = fixed_same(pos[:, :, :2], pos[:, :1, :2], decimals).all(axis=(1, 2))
    z = pos[:, :, 2]
    return same_xy & (z[:, 0] > z[:, 1]) & (z[:, 1] > z[:, 2]) & (z[:, 3] > z[:, 1])


def render_gcode(program: Program, header: list[str], templates=None) -> str:
    """The ``.ngc`` text of the job."""
    return b"".join(gcode_text(program, header, templates)).decode("utf-8")


def gcode_text(program: Program, header: list[str], templates=None) -> Iterator[bytes]:
    """The ``.ngc`` text of the job in pieces of UTF-8, for writing a million-hole job without
    holding it whole: where the template prints ``hole_lines`` as it is (``{{ hole_lines }}``),
    the frame is rendered (now: template errors are raised here, the templates noted as inputs)
    around a marker, and the hole lines follow in blocks of ``BLOCK`` holes as the pieces are
    taken."""
    cell = program.cell
    header = program.header(header)  # says what is not corrected
    env = environment(template_dir("gcode", templates))
    uses = template_uses(env, "program.ngc.j2")
    context = {
        "header": header,
        "decimals": cell.dialects["gcode"].decimals,
        "spindle_rpm": cell.dialects["gcode"].spindle_rpm,
        "approach_mm_min": cell.drilling.approach_mm_s * 60.0,
        "dwell": cell.drilling.dwell_s,
        "peck": cell.drilling.peck_mm,
    }
    if uses is None or "holes" in uses:  # a template that loops over the holes: all at once
        blocks = [_holes(program, lo) for lo in range(0, len(program), BLOCK)]
        context["holes"] = [
            hole for block in blocks for hole in _records(block, cell.dialects["gcode"].decimals)
        ]
        context["hole_lines"] = b"".join(_lines(block, cell) for block in blocks).decode("ascii")
        return iter([render(env, "program.ngc.j2", **context).encode()])
    if "hole_lines" not in uses:
        return iter([render(env, "program.ngc.j2", **context).encode()])
    if not printed_plainly(env, "program.ngc.j2", "hole_lines"):  # filtered, cut, measured
        context["hole_lines"] = b"".join(_hole_lines(program)).decode("ascii")
        return iter([render(env, "program.ngc.j2", **context).encode()])
    frame = render_around(env, "program.ngc.j2", "hole_lines", **context)
    return _around([piece.encode() for piece in frame], program)


def _around(frame: list[bytes], program: Program) -> Iterator[bytes]:
    """The pieces of the frame with the hole lines between them."""
    yield frame[0]
    for piece in frame[1:]:
        yield from _hole_lines(program)
        yield piece


BLOCK = 16384  # holes formatted at a time


def _hole_lines(program: Program) -> Iterator[bytes]:
    """The lines of every hole, ASCII, a block of ``BLOCK`` holes at a time."""
    for lo in range(0, len(program), BLOCK):
        yield _lines(_holes(program, lo), program.cell)


class _Holes(NamedTuple):
    """Holes of a block: positions (n, 4, 3) mm and A B C (n, 3) deg in the program frame,
    whether each takes a canned cycle and a retract move (n,), labels, feeds (n,) mm/min."""

    pos: np.ndarray
    abc: np.ndarray
    cycle: np.ndarray
    retract_move: np.ndarray
    labels: list[str]
    feed_mm_min: np.ndarray


def _holes(program: Program, lo: int) -> _Holes:
    """Holes lo..lo+BLOCK-1."""
    cell = program.cell
    hi = min(lo + BLOCK, len(program))
    pos, abc = program.in_frame(cell.dialects["gcode"].robot_T_program, lo, hi)
    d = cell.dialects["gcode"].decimals
    cycle = canned(pos, d) if cell.dialects["gcode"].canned_cycles else np.zeros(len(pos), bool)
    retract_move = ~fixed_same(pos[:, 3, 2], pos[:, 0, 2], d)
    feed = program.feed_mm_s[lo:hi] * 60.0
    return _Holes(pos, abc, cycle, retract_move, program.labels(lo, hi), feed)


def _records(holes: _Holes, decimals: int) -> list[GcodeHole]:
    """The ``GcodeHole`` records of a block, for a template that loops over them."""
    coords = [list(map(tuple, hole)) for hole in fixed_texts(holes.pos, decimals).tolist()]
    return list(
        map(
            GcodeHole,
            holes.labels,
            *zip(*coords, strict=True),
            map(tuple, fixed_texts(holes.abc, decimals, distinct=True).tolist()),
            fixed_texts(holes.feed_mm_min, 1, distinct=True).tolist(),
            holes.cycle.tolist(),
            holes.retract_move.tolist(),
        )
    )


def _lines(holes: _Holes, cell: Cell) -> bytes:
    """The lines of a block's holes, ASCII, built as one line image (``codegen.linebytes``); each
    kind of hole has its template (``_hole_templates``)."""
    n = len(holes.pos)
    if not n:
        return b""
    numbers = number_cells(
        np.concatenate([holes.pos[:, 0], holes.abc, holes.pos[:, 1:].reshape(n, 9)], axis=1),
        cell.dialects["gcode"].decimals,
    )
    comments = text_cells(comment_texts(holes.labels, prefix="hole "))
    feeds = number_cells(holes.feed_mm_min, 1)
    cycle, retract_move = holes.cycle, holes.retract_move
    kinds = (cycle & retract_move, cycle & ~retract_move, ~cycle)
    templates = _hole_templates(cell)
    for mask, (template, columns) in zip(kinds, templates, strict=True):
        if mask.all():  # every hole of the block alike (the usual)
            return image_bytes(line_image(template, _columns(columns, comments, numbers, feeds)))
    images = []  # each kind's rows, then every hole's lines in place
    for mask, (template, columns) in zip(kinds, templates, strict=True):
        rows = np.flatnonzero(mask)
        cells = _columns(columns, comments[rows], numbers[rows], feeds[rows])
        images.append(line_image(template, cells))
    return image_bytes(merge_images(kinds, images))


def _columns(
    columns: list[int], comments: np.ndarray, numbers: np.ndarray, feeds: np.ndarray
) -> list[np.ndarray]:
    """The cells (n, w) of ``columns`` (see ``_hole_templates``) from the comments (n, w), the
    numbers of columns 1-15 (n, 15, w) and the feeds (n, w)."""
    return [comments if c == 0 else feeds if c == 16 else numbers[:, c - 1] for c in columns]


def _hole_templates(cell: Cell) -> list[tuple[str, list[int]]]:
    """Templates (``linebytes.line_image``) of one hole's lines, each with the columns it prints,
    for a canned cycle with a retract move, a canned cycle without, and explicit moves. Columns:
    0 comment, 1-3 APP X Y Z, 4-6 A B C, 7-9 CLR, 10-12 BOT, 13-15 RET, 16 feed."""
    xyz = f"X{SLOT} Y{SLOT} Z{SLOT}"
    start = (f"({SLOT})\nG0 {xyz} A{SLOT} B{SLOT} C{SLOT}\n", [0, 1, 2, 3, 4, 5, 6])
    wait = f"P{fixed(cell.drilling.dwell_s, 3)}"
    if cell.drilling.peck_mm > 0:
        peck = fixed(cell.drilling.peck_mm, cell.dialects["gcode"].decimals)
        cycle = f"G98 G83 {xyz} R{SLOT} Q{peck} F{SLOT}\nG80\n"
    elif cell.drilling.dwell_s > 0:
        cycle = f"G98 G82 {xyz} R{SLOT} {wait} F{SLOT}\nG80\n"
    else:
        cycle = f"G98 G81 {xyz} R{SLOT} F{SLOT}\nG80\n"
    cycle_columns = [10, 11, 12, 9, 16]
    approach = f" F{fixed(cell.drilling.approach_mm_s * 60.0, 1)}\n"
    explicit = (
        f"G1 {xyz}{approach}G1 {xyz} F{SLOT}\n"
        + (f"G4 {wait}\n" if cell.drilling.dwell_s > 0 else "")
        + f"G1 {xyz}{approach}"
    )
    return [
        (start[0] + cycle + f"G0 Z{SLOT}\n", start[1] + cycle_columns + [15]),
        (start[0] + cycle, start[1] + cycle_columns),
        (start[0] + explicit, start[1] + [7, 8, 9, 10, 11, 12, 16, 13, 14, 15]),
    ]
