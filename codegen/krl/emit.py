"""KUKA KRL for a Program: ``NAME.src`` (motion) and ``NAME.dat`` (the E6POS of every hole); and
the laser-tracker measurement program of a plan (``render_measurement``, the same convention).

Templates ``program.src.j2`` and ``program.dat.j2`` (``templates/krl/``), rendered with CRLF line
ends as the controller's own files have. Position names are ``XH<n>_APP|CLR|BOT|RET`` (n = hole
number in the file, so always valid and unique, at most 24 characters); the hole id goes into a
comment. Numbers go through ``fixed`` only: per-hole numbers are formatted once in Python (mm and
deg with ``program.decimals``, $VEL.CP in m/s with 4 decimals, S and T as integers) and reach the
template as text; the template formats its scalar settings with the ``fixed`` filter. Jinja renders
the frame of each file; the per-hole lines come finished from one %-template per hole or position
(``hole_lines``, ``position_lines``), while the records ``holes`` and ``positions`` stay available
to a user template that loops over them (each is built only if the template refers to it).

Splitting: when a job would make a ``.src`` or ``.dat`` longer than ``program.lines_per_file``,
the holes go into numbered modules ``NAME_001``, ``NAME_002``, ... (each its own ``.src``/``.dat``
pair with local declarations, like any module the KR C4 loads) and ``NAME.src`` becomes the main
program: INI, base, tool, speeds and the spindle, then one call per module. A module is a global
subprogram on the KR C4, so the main program calls it by name without a declaration. The holes
per module follow from the rendered lines per hole of the template in use.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from accugrid.codegen.program import STAGES, Program
from accugrid.codegen.render import environment, render, template_dir, template_uses
from accugrid.codegen.textsafe import comment_texts, fixed, fixed_format, fixed_ready, fixed_texts
from accugrid.kinematics.errors import InputError

__all__ = [
    "MAX_PARTS",
    "KrlHole",
    "KrlPosition",
    "MeasureMove",
    "MeasureSettings",
    "render_krl",
    "render_measurement",
]

MAX_PARTS = 999  # NAME_001..NAME_999 keeps names <= 24 characters with a 20-character NAME


class KrlHole(NamedTuple):
    """One hole in the .src: comment text (sanitized by the template), position names, feed."""

    label: str
    app: str
    clr: str
    bot: str
    ret: str
    feed: str  # $VEL.CP in m/s, already formatted by ``fixed``


class KrlPosition(NamedTuple):
    """One E6POS of the .dat; numbers already formatted by ``fixed``."""

    name: str
    x: str
    y: str
    z: str
    a: str
    b: str
    c: str
    s: str
    t: str


class MeasureMove(NamedTuple):
    """One row of a measurement program: the E6POS name and the plan row id (comment text)."""

    point: str
    label: str


@dataclass(frozen=True)
class MeasureSettings:
    """TOOL_DATA and BASE_DATA numbers (base 0: the robot frame), PTP %, $VEL.CP m/s, and the
    wait after each position: ``wait_input`` ($IN number) or ``wait_sec`` s."""

    tool: int
    base: int
    ptp_percent: float
    vel_cp: float
    wait_sec: float
    wait_input: int | None
    ptp_only: bool = False  # every move PTP (poses that reorient), else PTP to the first, then LIN


def render_measurement(
    points: np.ndarray,
    abc: np.ndarray,
    ids: list[str],
    status: np.ndarray,
    turn: np.ndarray,
    name: str,
    header: list[str],
    settings: MeasureSettings,
    templates=None,
) -> tuple[str, str]:
    """(.src, .dat) of a laser-tracker measurement program (``measure.src.j2``,
    ``measure.dat.j2``): positions (N, 3) mm at KUKA A,B,C ((3,) or (N, 3) deg) with Status and
    Turn (N,); one E6POS ``XMP<k>`` per distinct pose (0.0001 mm / deg) in order of first visit,
    then a PTP to the first row and LIN (or PTP with ``settings.ptp_only``) to every other, each
    followed by the wait. Numbers are formatted here (mm and deg with 3 decimals, S and T as
    integers)."""
    points = np.asarray(points, dtype=float)
    abc = np.broadcast_to(np.asarray(abc, dtype=float), points.shape)
    key = np.round(np.column_stack([points, abc]), 4)
    unique, index = np.unique(key, axis=0, return_inverse=True)
    index = index.reshape(-1)
    first_visit = np.full(len(unique), len(points))
    np.minimum.at(first_visit, index, np.arange(len(points)))
    order = np.argsort(first_visit)
    rank = np.empty(len(unique), dtype=int)
    rank[order] = np.arange(len(unique))
    rows = first_visit[order]
    names = [f"XMP{k + 1}" for k in range(len(unique))]
    pose = fixed_texts(np.column_stack([points[rows], abc[rows]]), 3)
    st = fixed_texts(np.stack([status[rows], turn[rows]], axis=1), 0)
    positions = [KrlPosition(names[k], *pose[k], *st[k]) for k in range(len(rows))]
    moves = [MeasureMove(names[rank[index[r]]], ids[r]) for r in range(len(points))]
    env = environment(template_dir("krl", templates), newline="\r\n")
    context = {
        "name": name,
        "header": header,
        "tool": settings.tool,
        "base": settings.base,
        "ptp_percent": settings.ptp_percent,
        "vel_cp": settings.vel_cp,
        "wait_sec": settings.wait_sec,
        "wait_input": settings.wait_input,
        "moves": moves,
        "points": positions,
        "ptp_only": settings.ptp_only,
    }
    return render(env, "measure.src.j2", **context), render(env, "measure.dat.j2", **context)


def render_krl(program: Program, header: list[str], templates=None) -> dict[str, str]:
    """File name -> text for the job (``NAME.src``, ``NAME.dat`` and any ``NAME_nnn`` pairs)."""
    env = environment(template_dir("krl", templates), newline="\r\n")
    cell = program.cell
    pos, abc = program.in_frame(cell.robot_T_base)
    records = _Records(program, pos, abc)
    common = {
        "header": header,
        "decimals": cell.decimals,
        "base": cell.base_number,
        "tool": cell.tool_number,
        "ptp_percent": cell.ptp_percent,
        "apo_cdis": cell.apo_cdis_mm,
        "apo_cptp": cell.apo_ptp_percent,
        "spindle": cell.spindle_output,
        "clamp": cell.clamp_output,
        "travel": cell.travel_motion,
        "travel_m_s": cell.travel_mm_s / 1000.0,
        "approach_m_s": cell.approach_mm_s / 1000.0,
        "dwell": cell.dwell_s,
        "ext": cell.external_axes,
    }

    src_uses = template_uses(env, "program.src.j2")
    dat_uses = template_uses(env, "program.dat.j2")

    def files(name: str, role: str, lo: int, hi: int, calls=()) -> tuple[str, str]:
        src = render(
            env,
            "program.src.j2",
            name=name,
            role=role,
            calls=list(calls),
            **records.context(lo, hi, src_uses),
            **common,
        )
        dat = render(
            env, "program.dat.j2", name=name, **records.context(lo, hi, dat_uses), **common
        )
        return src, dat

    name, limit, n = cell.program_name, cell.lines_per_file, len(program)
    if n < 2 or n <= _capacity(files, name, "single", limit):
        out = dict(zip((f"{name}.src", f"{name}.dat"), files(name, "single", 0, n), strict=True))
    else:
        per_part = _capacity(files, f"{name}_001", "part", limit)
        parts = -(-n // per_part)
        if parts > MAX_PARTS:
            raise InputError(
                f"{n} holes need {parts} sub-programs of {per_part} holes, more than "
                f"{MAX_PARTS}: raise program.lines_per_file",
                cell.path,
            )
        out = {}
        calls = [f"{name}_{k + 1:03d}" for k in range(parts)]
        for k, part in enumerate(calls):
            out[f"{part}.src"], out[f"{part}.dat"] = files(
                part, "part", k * per_part, min(n, (k + 1) * per_part)
            )
        out[f"{name}.src"], out[f"{name}.dat"] = files(name, "main", 0, 0, calls)
    for file, text in out.items():
        if _lines(text) > limit:
            raise InputError(
                f"{file} would have {_lines(text)} lines, more than program.lines_per_file "
                f"({limit}); the main program's calls or a template's lines do not fit",
                cell.path,
            )
    return out


def _capacity(files, name: str, role: str, limit: int) -> int:
    """Holes that fit one file pair of ``role``, from rendering it with 1 and 2 holes."""
    one = [_lines(t) for t in files(name, role, 0, 1)]
    two = [_lines(t) for t in files(name, role, 0, 2)]
    fits = []
    for a, b in zip(one, two, strict=True):
        per_hole = max(b - a, 1)
        fits.append((limit - (a - per_hole)) // per_hole)
    per_part = min(fits)
    if per_part < 1:
        raise InputError(f"program.lines_per_file ({limit}) cannot hold one hole per file")
    return int(per_part)


class _Records:
    """Template records of a program, numbers formatted by ``fixed`` (mm and deg with the cell's
    decimals, $VEL.CP m/s with 4, S and T as integers); angles, S, T and feeds, which repeat,
    once per distinct value for the whole program. Per hole, either records (``holes``,
    ``positions``: for templates that loop over them) or the finished CRLF lines (``hole_lines``,
    ``position_lines``: what the built-in templates print), whichever the template uses."""

    def __init__(self, program: Program, pos: np.ndarray, abc: np.ndarray) -> None:
        self.program = program
        cell = program.cell
        self.decimals = cell.decimals
        self.stages = [0, 1, 2] if cell.retract_mm == cell.approach_mm else [0, 1, 2, 3]
        self.names = [STAGES[k] for k in self.stages]
        self.pos = pos[:, self.stages]
        self.abc = fixed_texts(abc, self.decimals, distinct=True)
        status, turn = program.configuration.to_kuka()
        self.st = fixed_texts(
            np.stack([status[:, self.stages], turn[:, self.stages]], axis=2),
            0,
            distinct=True,
        )
        self.feed = fixed_texts(program.feed_mm_s / 1000.0, 4, distinct=True)
        ext = _literal(
            "".join(
                f",E{k + 1} {fixed(v, cell.decimals)}" for k, v in enumerate(cell.external_axes)
            )
        )
        mm = fixed_format(self.decimals)
        self.position_block = "".join(
            f"DECL E6POS XH%d_{s}={{X {mm},Y {mm},Z {mm},A %s,B %s,C %s,S %s,T %s{ext}}}\r\n"
            for s in self.names
        )
        self.hole_block = _hole_block(cell, self.names)
        self._named: tuple = (None, None, [])

    def context(self, lo: int, hi: int, uses: frozenset[str] | None) -> dict[str, object]:
        """Template variables of holes lo..hi-1 that ``uses`` names (None: all)."""
        wanted = {"holes", "positions", "hole_lines", "position_lines"}
        if uses is not None:
            wanted &= uses
        out: dict[str, object] = {}
        n, k = hi - lo, len(self.stages)
        number = np.arange(lo + 1, hi + 1, dtype=object)
        if "positions" in wanted:
            table = np.empty((n, k, 9), dtype=object)
            for j, column in enumerate(self._names(lo, hi)):
                table[:, j, 0] = column
            table[:, :, 1:4] = fixed_texts(self.pos[lo:hi], self.decimals)
            table[:, :, 4:7] = self.abc[lo:hi, None, :]
            table[:, :, 7:9] = self.st[lo:hi]
            out["positions"] = list(map(KrlPosition._make, table.reshape(n * k, 9).tolist()))
        if "position_lines" in wanted:
            table = np.empty((n, k, 9), dtype=object)
            table[:, :, 0] = number[:, None]
            table[:, :, 1:4] = fixed_ready(self.pos[lo:hi], self.decimals)
            table[:, :, 4:7] = self.abc[lo:hi, None, :]
            table[:, :, 7:9] = self.st[lo:hi]
            out["position_lines"] = (self.position_block * n) % tuple(table.ravel().tolist())
        labels = self.program.labels(lo, hi) if wanted & {"holes", "hole_lines"} else []
        if "holes" in wanted:
            names = self._names(lo, hi)
            retract = names[3] if k == 4 else names[0]
            out["holes"] = list(
                map(KrlHole, labels, *names[:3], retract, self.feed[lo:hi].tolist())
            )
        if "hole_lines" in wanted:
            table = np.empty((n, 6), dtype=object)  # in the order the lines print them
            table[:, 0] = comment_texts(labels)
            table[:, [1, 2, 4, 5]] = number[:, None]
            table[:, 3] = self.feed[lo:hi]
            out["hole_lines"] = (self.hole_block * n) % tuple(table.ravel().tolist())
        return out

    def _names(self, lo: int, hi: int) -> list[list[str]]:
        """Position names of holes lo..hi-1, one list per stage (made once for the .src and the
        .dat of a file)."""
        if self._named[:2] != (lo, hi):
            numbers = range(lo + 1, hi + 1)
            self._named = (lo, hi, [list(map(f"XH{{}}_{s}".format, numbers)) for s in self.names])
        return self._named[2]


def _hole_block(cell, stages: list[str]) -> str:
    """The .src lines of one hole as a %-template over (comment label, hole number, hole number,
    feed, hole number, hole number), with the cell's settings filled in; CRLF line ends."""
    approach = f"$VEL.CP = {fixed(cell.approach_mm_s / 1000.0, 4)}"
    if cell.travel_motion == "ptp":
        travel = ["PTP XH%d_APP C_PTP"]
    else:
        travel = [
            _literal(f"$VEL.CP = {fixed(cell.travel_mm_s / 1000.0, 4)}"),
            "LIN XH%d_APP C_DIS",
        ]
    clamp = unclamp = []
    if cell.clamp_output is not None:
        clamp = [_literal(f"$OUT_C[{fixed(cell.clamp_output, 0)}] = TRUE ; clamp")]
        unclamp = [_literal(f"$OUT[{fixed(cell.clamp_output, 0)}] = FALSE ; unclamp")]
    lines = [
        "; hole %s",
        *travel,
        _literal(approach),
        "LIN XH%d_CLR",
        *clamp,
        "$VEL.CP = %s",
        "LIN XH%d_BOT",
        _literal(f"WAIT SEC {fixed(cell.dwell_s, 3)}"),
        *unclamp,
        _literal(approach),
        f"LIN XH%d_{stages[3] if len(stages) == 4 else stages[0]} C_DIS",
    ]
    return "\r\n".join(lines) + "\r\n"


def _literal(text: str) -> str:
    """``text`` as literal text of a %-template."""
    return text.replace("%", "%%")


def _lines(text: str) -> int:
    return text.count("\n")
