"""KUKA KRL for a Program: ``NAME.src`` (motion) and ``NAME.dat`` (the E6POS of every hole).

Templates ``program.src.j2`` and ``program.dat.j2`` (``templates/krl/``), rendered with CRLF line
ends as the controller's own files have. Position names are ``XH<n>_APP|CLR|BOT|RET`` (n = hole
number in the file, so always valid and unique, at most 24 characters); the hole id goes into a
comment. Numbers go through ``fixed`` only: mm and deg with ``program.decimals``, speeds in m/s with
4 decimals, S and T as integers.

Splitting: when a job would make a ``.src`` or ``.dat`` longer than ``program.lines_per_file``,
the holes go into numbered modules ``NAME_001``, ``NAME_002``, ... (each its own ``.src``/``.dat``
pair with local declarations, like any module the KR C4 loads) and ``NAME.src`` becomes the main
program: INI, base, tool, speeds and the spindle, then one call per module. A module is a global
subprogram on the KR C4, so the main program calls it by name without a declaration. The holes
per module follow from the rendered lines per hole of the template in use.
"""

from __future__ import annotations

from typing import NamedTuple

from codegen.program import Program
from codegen.render import environment, render, template_dir
from kinematics.errors import InputError

MAX_PARTS = 999  # NAME_001..NAME_999 keeps names <= 24 characters with a 20-character NAME


class KrlHole(NamedTuple):
    label: str
    app: str
    clr: str
    bot: str
    ret: str
    feed_m_s: float


class KrlPosition(NamedTuple):
    name: str
    x: float
    y: float
    z: float
    a: float
    b: float
    c: float
    s: int
    t: int


def render_krl(program: Program, header: list[str], templates=None) -> dict[str, str]:
    """File name -> text for the job (``NAME.src``, ``NAME.dat`` and any ``NAME_nnn`` pairs)."""
    env = environment(template_dir("krl", templates), newline="\r\n")
    cell = program.cell
    pos, abc = program.in_frame(cell.robot_T_base)
    same_ret = cell.retract_mm == cell.approach_mm
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

    def files(name: str, role: str, lo: int, hi: int, calls=()) -> tuple[str, str]:
        holes, positions = _holes(program, pos, abc, lo, hi, same_ret)
        src = render(
            env, "program.src.j2", name=name, role=role, holes=holes, calls=list(calls), **common
        )
        dat = render(env, "program.dat.j2", name=name, positions=positions, **common)
        return src, dat

    name, limit, n = cell.program_name, cell.lines_per_file, len(program)
    src, dat = files(name, "single", 0, n)
    if max(_lines(src), _lines(dat)) <= limit:
        return {f"{name}.src": src, f"{name}.dat": dat}
    per_part = _holes_per_part(files, name, limit)
    parts = -(-n // per_part)
    if parts > MAX_PARTS:
        raise InputError(
            f"{n} holes need {parts} sub-programs of {per_part} holes, more than {MAX_PARTS}: "
            "raise program.lines_per_file",
            cell.path,
        )
    out: dict[str, str] = {}
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


def _holes_per_part(files, name: str, limit: int) -> int:
    """Holes per module from the rendered size of a 1- and a 2-hole module."""
    one = [_lines(t) for t in files(f"{name}_001", "part", 0, 1)]
    two = [_lines(t) for t in files(f"{name}_001", "part", 0, 2)]
    fits = []
    for a, b in zip(one, two, strict=True):
        per_hole, fixed_part = max(b - a, 1), a - max(b - a, 1)
        fits.append((limit - fixed_part) // per_hole)
    per_part = min(fits)
    if per_part < 1:
        raise InputError(f"program.lines_per_file ({limit}) cannot hold one hole per file")
    return int(per_part)


def _holes(program: Program, pos, abc, lo: int, hi: int, same_ret: bool):
    """Template records of holes lo..hi-1: KrlHole list and KrlPosition list."""
    labels = program.labels(lo, hi)
    status, turn = program.status.tolist(), program.turn.tolist()
    stages = ("APP", "CLR", "BOT") if same_ret else ("APP", "CLR", "BOT", "RET")
    holes, positions = [], []
    coords = pos[lo:hi].tolist()
    angles = abc[lo:hi].tolist()
    for i in range(lo, hi):
        names = [f"XH{i + 1}_{s}" for s in stages]
        ret = names[0] if same_ret else names[3]
        holes.append(
            KrlHole(labels[i - lo], names[0], names[1], names[2], ret, program.feed_mm_s[i] / 1000)
        )
        a, b, c = angles[i - lo]
        for k, nm in enumerate(names):
            x, y, z = coords[i - lo][k]
            positions.append(KrlPosition(nm, x, y, z, a, b, c, status[i][k], turn[i][k]))
    return holes, positions


def _lines(text: str) -> int:
    return text.count("\n")
