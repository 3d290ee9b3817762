"""KUKA KRL for a Program: ``NAME.src`` (motion) and ``NAME.dat`` (the E6POS of every hole); and
the laser-tracker measurement program of a plan (``render_measurement``, the same convention;
``MEASUREMENT``, the plug-in's ``measurement()``).

Templates ``program.src.j2`` and ``program.dat.j2`` (``templates/krl/``), rendered with CRLF line
ends as the controller's own files have. Position names are ``XH<n>_APP|CLR|BOT|RET`` (n = hole
number in the file, so always valid and unique, at most 24 characters); the hole id goes into a
comment. Numbers go through ``fixed`` only: per-hole numbers are formatted once in Python (mm and
deg with ``program.decimals``, $VEL.CP in m/s with 4 decimals, S and T as integers;
``textsafe.fixed_bytes`` for the lines, ``fixed_texts`` for the records) and reach the template as
text; the template formats its scalar settings with the ``fixed`` filter. Jinja renders the frame
of each file; the per-hole lines (``hole_lines``, ``position_lines``) come finished, built as
bytes by numpy from one template per hole (``codegen.linebytes``), while the records ``holes``
and ``positions`` stay available to a user template that loops over them (each is built only if
the template refers to it).

Splitting: when a job would make a ``.src`` or ``.dat`` longer than ``program.lines_per_file``,
the holes go into numbered modules ``NAME_001``, ``NAME_002``, ... (each its own ``.src``/``.dat``
pair with local declarations, like any module the KR C4 loads) and ``NAME.src`` becomes the main
program: INI, base, tool, speeds and the spindle, then one call per module. A module is a global
subprogram on the KR C4, so the main program calls it by name without a declaration. The holes
per module follow from the rendered lines per hole of the template in use. Past 999 modules (a
million holes at 5,000 lines per file) they are numbered with as many digits as needed, as long
as the name stays a KRL name (at most 24 characters); a job whose modules cannot be named, or
whose main program cannot call them all within the line limit, is refused after reading the
points and before correction and IK (``module_split``). Files are rendered one by one as they
are written, the modules' ``.src`` before their ``.dat`` (``KrlFiles``). A KR C4 holds only a
few MiB of programs in its memory at once, so a job of many modules is run a batch of modules at
a time (copied in turn, or loaded on demand).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from types import SimpleNamespace
from typing import NamedTuple

import numpy as np

from accugrid.codegen.cell_record import Cell
from accugrid.codegen.krl.configuration import configuration_words
from accugrid.codegen.krl.names import KRL_NAME_MAX, krl_identifier
from accugrid.codegen.linebytes import SLOT, image_bytes, line_image, number_cells, text_cells
from accugrid.codegen.plugin import MeasureSettings, Rendered
from accugrid.codegen.points import Points
from accugrid.codegen.program import STAGES, Program
from accugrid.codegen.render import (
    environment,
    loaded,
    printed_plainly,
    render,
    render_around,
    template_dir,
    template_uses,
)
from accugrid.infra.csvtable import Table
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import comment_texts, fixed, fixed_texts
from accugrid.kinematics.configuration import Configuration

__all__ = [
    "BLOCK",
    "FILTERS",
    "MEASUREMENT",
    "MODULE_DIGITS",
    "KrlFiles",
    "KrlHole",
    "KrlMeasurement",
    "KrlPosition",
    "MeasureMove",
    "module_split",
    "render_krl",
    "render_measurement",
]

BLOCK = 16384  # holes whose numbers are made at a time
FILTERS = (("ident", krl_identifier),)  # the templates' own filters: ``ident``, a KRL name
MODULE_DIGITS = 3  # NAME_001..NAME_999; a job of more modules numbers them with more digits


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
    integers). ``settings``: TOOL_DATA and BASE_DATA numbers (base 0: $NULLFRAME), PTP %,
    $VEL.CP (``speed_m_s``), ``WAIT FOR $IN[wait_input]`` or ``WAIT SEC wait_sec``."""
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
    names = np.array([f"XMP{k + 1}" for k in range(len(unique))], dtype=object)
    table = np.empty((len(rows), 9), dtype=object)  # KrlPosition fields
    table[:, 0] = names
    table[:, 1:7] = fixed_texts(np.column_stack([points[rows], abc[rows]]), 3)
    table[:, 7:9] = fixed_texts(np.stack([status[rows], turn[rows]], axis=1), 0)
    targets = names[rank[index]].tolist()  # the E6POS of every row
    env = environment(template_dir("krl", templates), newline="\r\n", filters=FILTERS)
    src_uses = template_uses(env, "measure.src.j2")
    dat_uses = template_uses(env, "measure.dat.j2")
    uses = None if src_uses is None or dat_uses is None else src_uses | dat_uses
    context: dict[str, object] = {}
    if uses is None or "points" in uses:
        context["points"] = list(map(KrlPosition._make, table.tolist()))
    if uses is None or "moves" in uses:
        context["moves"] = list(map(MeasureMove, targets, ids))
    if uses is None or "point_lines" in uses:
        line = "DECL E6POS %s={X %s,Y %s,Z %s,A %s,B %s,C %s,S %s,T %s" + _ZERO_E + "}\r\n"
        context["point_lines"] = (line * len(table)) % tuple(table.ravel().tolist())
    if uses is None or "move_lines" in uses:
        context["move_lines"] = _move_lines(targets, ids, settings)
    context |= {
        "name": name,
        "header": header,
        "tool": settings.tool,
        "base": settings.base,
        "ptp_percent": settings.ptp_percent,
        "vel_cp": settings.speed_m_s,
        "wait_sec": settings.wait_sec,
        "wait_input": settings.wait_input,
        "ptp_only": settings.ptp_only,
    }
    return render(env, "measure.src.j2", **context), render(env, "measure.dat.j2", **context)


_ZERO_E = ",E1 0.000,E2 0.000,E3 0.000,E4 0.000,E5 0.000,E6 0.000"  # no external axes


class KrlMeasurement:
    """The KRL measurement program as the plug-in's ``measurement()``
    (``codegen.plugin.MeasurementWriter``): ``NAME.src`` and ``NAME.dat`` (lower-case file
    names), NAME a KRL name (prefixed M where it would not be one); the .src renamed last."""

    listing = "the .dat"

    def name(self, requested: str) -> str:
        return krl_identifier(requested, prefix="M")

    def targets(self, out: Path, name: str) -> list[Path]:
        return [out / f"{name.lower()}{ext}" for ext in _EXTS]

    def motion(self, settings: MeasureSettings) -> str:
        if settings.wait_input is not None:
            wait = f"WAIT FOR $IN[{settings.wait_input}]"
        else:
            wait = f"WAIT SEC {fixed(settings.wait_sec)}"
        moves = "each by PTP" if settings.ptp_only else "first by PTP, then LIN"
        return f"{moves}, each followed by {wait}"

    def render(self, plan, configuration, name, header, settings, templates, out):
        words = configuration_words(configuration)  # (N, 2) S, T
        rows = (plan.points, plan.abc_rows(), plan.ids, words[:, 0], words[:, 1])
        src, dat = render_measurement(*rows, name, header, settings, templates)
        paths = self.targets(out, name)
        return Rendered({paths[0]: src, paths[1]: dat}, [paths[0]])


MEASUREMENT = KrlMeasurement()


def _move_lines(targets: list[str], ids: list[str], settings: MeasureSettings) -> str:
    """The .src lines of every row of a measurement program: PTP to the first (every one with
    ``ptp_only``), LIN to the others, each with the row id as a comment, then the wait."""
    if settings.wait_input is not None:
        wait = f"WAIT FOR $IN[{fixed(settings.wait_input, 0)}] ; tracker done\r\n"
    else:
        wait = f"WAIT SEC {fixed(settings.wait_sec, 3)} ; tracker measures\r\n"
    motion = np.full(len(targets), "PTP" if settings.ptp_only else "LIN", dtype=object)
    motion[:1] = "PTP"
    table = np.empty((len(targets), 3), dtype=object)
    table[:, 0], table[:, 1], table[:, 2] = motion, targets, comment_texts(list(map(str, ids)))
    return (("%s %s ; %s\r\n" + _literal(wait)) * len(targets)) % tuple(table.ravel().tolist())


def render_krl(
    program: Program,
    header: list[str],
    templates=None,
    split: tuple[list[str], int] | None = None,
) -> KrlFiles:
    """File name -> text for the job (``NAME.src``, ``NAME.dat`` and any ``NAME_nnn`` pairs), as
    a mapping that renders each file when it is asked for (see ``KrlFiles``). ``split``: the
    job's ``module_split`` when the caller already made it."""
    cell = program.cell
    header = program.header(header)  # says what is not corrected
    files = _file_renderer(cell, header, _Records(program), templates)
    split = split or module_split(cell, len(program), header, templates)
    return KrlFiles(files, *split, len(program), cell)


def module_split(
    cell: Cell, holes: int, header: list[str], templates=None
) -> tuple[list[str], int]:
    """The modules a job of ``holes`` holes is split into (``NAME_001``, ...; [] for one file
    pair) and the holes per module, known before any correction or IK: InputError (naming the
    cell file) when they cannot be named or called within ``program.lines_per_file``, so such a
    job is refused before the heavy work. ``header``: a header with as many lines as the job's
    will have. The lines per hole come from rendering a 1- and a 2-hole placeholder program with
    the same templates (so the split never waits for the IK check)."""
    records = _Records(_placeholder(cell))
    return _modules(_file_renderer(cell, header, records, templates), cell, holes)


class KrlFiles(Mapping):
    """The files of a KRL job by name: the modules' ``.src`` (``NAME_001.src``, ...), then their
    ``.dat``, then the main program (``NAME.src``, ``NAME.dat``). The ``.src`` files need no
    Status or Turn, so they are made while the program's IK check still runs (``Program.wait``);
    the first ``.dat`` waits for it. Each file is rendered when asked for and not kept, so that
    writing a million-hole job in order holds one file's text at a time; each is checked
    against ``program.lines_per_file`` as it is rendered."""

    def __init__(self, files, modules: list[str], per_part: int, holes: int, cell: Cell) -> None:
        self._files, self._modules, self._holes, self._cell = files, modules, holes, cell
        self._per_part = per_part
        name = cell.dialects["krl"].name
        self._pairs = [*modules, name] if modules else [name]
        self._index = {f"{m}{ext}": (k, ext) for ext in _EXTS for k, m in enumerate(modules)}
        self._index |= {f"{name}{ext}": (len(modules), ext) for ext in _EXTS}

    def __iter__(self):
        return iter(self._index)

    def __len__(self) -> int:
        return len(self._index)

    def __getitem__(self, file: str) -> str:
        return b"".join(self.pieces(file)).decode("utf-8")

    def pieces(self, file: str) -> list[bytes]:
        """The text of ``file`` in pieces of UTF-8, as it is written (the lines the template
        prints as they are go from their bytes into the file, never through a str)."""
        return self._render(*self._index[file])

    def at(self, folder: Path) -> Mapping:
        """The same files keyed by their path in ``folder``, in pieces (``pieces``), still
        rendered as asked for."""
        files = self

        class InFolder(Mapping):
            def __iter__(self):
                return (folder / name for name in files)

            def __len__(self) -> int:
                return len(files)

            def __getitem__(self, path: Path) -> list[bytes]:
                return files.pieces(Path(path).name)

        return InFolder()

    def _render(self, k: int, ext: str) -> list[bytes]:
        name, modules, per = self._pairs[k], self._modules, self._per_part
        if not modules:
            pieces, lines = self._files(name, "single", 0, self._holes, ext)
        elif k < len(modules):
            lo, hi = k * per, min(self._holes, (k + 1) * per)
            pieces, lines = self._files(name, "part", lo, hi, ext)
        else:
            pieces, lines = self._files(name, "main", 0, 0, ext, modules)
        limit = self._cell.dialects["krl"].lines_per_file
        if lines > limit:
            raise InputError(
                f"{name}{ext} would have {lines} lines, more than program.lines_per_file "
                f"({limit}); the main program's calls or a template's lines do not fit",
                self._cell.path,
            )
        return pieces


_EXTS = (".src", ".dat")


def _file_renderer(cell: Cell, header: list[str], records: _Records, templates):
    """files(name, role, lo, hi, ext, calls=()) -> the ``ext`` (".src" or ".dat") text of
    holes lo..hi-1 in pieces of UTF-8, and its number of lines. Where the template prints its
    per-hole lines as they are, its text is rendered around them and they stay bytes."""
    env = environment(template_dir("krl", templates), newline="\r\n", filters=FILTERS)
    krl = cell.dialects["krl"]
    common = {
        "header": header,
        "decimals": krl.decimals,
        "base": cell.base_number,
        "tool": cell.tool_number,
        "ptp_percent": krl.ptp_percent,
        "apo_cdis": krl.apo_cdis_mm,
        "apo_cptp": krl.apo_ptp_percent,
        "spindle": krl.spindle_output,
        "clamp": krl.clamp_output,
        "travel": krl.travel_motion,
        "travel_m_s": cell.drilling.travel_mm_s / 1000.0,
        "approach_m_s": cell.drilling.approach_mm_s / 1000.0,
        "dwell": cell.drilling.dwell_s,
        "ext": krl.external_axes,
    }
    kinds = {}  # ext -> template, its variables (None: any), its lines variable, printed as is
    for ext, lines in ((".src", "hole_lines"), (".dat", "position_lines")):
        template = f"program{ext}.j2"
        uses = template_uses(env, template)
        plain = uses is not None and printed_plainly(env, template, lines)
        kinds[ext] = (loaded(env, template), uses, lines, plain)

    def files(name: str, role: str, lo: int, hi: int, ext: str, calls=()):
        template, uses, lines, plain = kinds[ext]
        context = {"name": name, **common}
        if ext == ".src":
            context |= {"role": role, "calls": list(calls)}
        if not plain:
            text = render(env, template, **records.context(lo, hi, uses), **context)
            return [text.encode()], _lines(text)
        context |= records.context(lo, hi, uses - {lines})
        frame = render_around(env, template, lines, **context)
        block = records.lines_bytes(lines, lo, hi)
        pieces = [frame[0].encode()]
        for part in frame[1:]:
            pieces += [block, part.encode()]
        count = sum(map(_lines, frame)) + (len(frame) - 1) * records.line_count(lines, lo, hi)
        return pieces, count

    return files


def _modules(files, cell: Cell, n: int) -> tuple[list[str], int]:
    """Names of the modules a job of n holes is split into ([]: one file pair) and the holes per
    module. Modules are
    numbered NAME_001.. (more digits past 999 modules, as long as the name stays a KRL name of
    at most 24 characters); InputError when they cannot be named or the main program cannot
    call them all within the line limit."""
    krl = cell.dialects["krl"]
    name, limit = krl.name, krl.lines_per_file
    if n < 2 or n <= _capacity(files, name, "single", limit):
        return [], n
    per_part = _capacity(files, f"{name}_001", "part", limit)
    parts = -(-n // per_part)
    digits = max(MODULE_DIGITS, len(str(parts)))
    if len(name) + 1 + digits > KRL_NAME_MAX:
        raise InputError(
            f"{n} holes need {parts} modules of {per_part} holes; their names "
            f"{name}_{1:0{digits}d}.. would be longer than {KRL_NAME_MAX} characters: shorten "
            "program.name or raise program.lines_per_file",
            cell.path,
        )
    modules = [f"{name}_{k + 1:0{digits}d}" for k in range(parts)]
    main = max(files(name, "main", 0, 0, ext, modules)[1] for ext in _EXTS)
    if main > limit:
        raise InputError(
            f"{n} holes need {parts} modules of {per_part} holes; the main program calling them "
            f"would have {main} lines, more than program.lines_per_file ({limit}): raise it",
            cell.path,
        )
    return modules, per_part


def _capacity(files, name: str, role: str, limit: int) -> int:
    """Holes that fit one file pair of ``role``, from rendering it with 1 and 2 holes."""
    one = [files(name, role, 0, 1, ext)[1] for ext in _EXTS]
    two = [files(name, role, 0, 2, ext)[1] for ext in _EXTS]
    fits = []
    for a, b in zip(one, two, strict=True):
        per_hole = max(b - a, 1)
        fits.append((limit - (a - per_hole)) // per_hole)
    per_part = min(fits)
    if per_part < 1:
        raise InputError(f"program.lines_per_file ({limit}) cannot hold one hole per file")
    return int(per_part)


def _placeholder(cell: Cell) -> Program:
    """A 2-hole program of the cell with placeholder numbers, for counting rendered lines."""
    zeros = np.zeros((2, 4, 3))
    table = Table(os.fspath(cell.path), ["x", "y", "z"], [["0", "0", "0"]] * 2, [2, 3])
    points = Points(
        path=table.path,
        table=table,
        ids=["1", "2"],
        xyz=zeros[:, 0],
        abc=None,
        axis=np.tile([0.0, 0.0, 1.0], (2, 1)),
        diameter=np.full(2, np.nan),
        depth=np.full(2, np.nan),
        feed=np.full(2, np.nan),
    )
    return Program(
        cell=cell,
        points=points,
        positions=zeros,
        rotations=np.tile(np.eye(3), (2, 1, 1)),
        correction=zeros[:, 0],
        feed_mm_s=np.full(2, cell.drilling.feed_mm_s),
        depth_mm=np.full(2, cell.drilling.depth_mm),
        configuration=Configuration.of_code(np.zeros((2, 4), int), np.zeros((2, 4, 6), int)),
        warnings=[],
        corrected=False,
    )


class _Records:
    """Template records of a program, numbers formatted by ``fixed`` (mm and deg with the cell's
    decimals, $VEL.CP m/s with 4, S and T as integers). Per hole, either records (``holes``,
    ``positions``: for templates that loop over them) or the finished CRLF lines (``hole_lines``,
    ``position_lines``: what the built-in templates print), whichever the template uses, made
    file by file (a million-hole job never holds them all) from a block of ``BLOCK`` holes made
    at once (``_block_of``): the lines as one line image per kind for the block
    (``codegen.linebytes``, numbers by ``textsafe.fixed_bytes``), cut into the files' rows."""

    def __init__(self, program: Program) -> None:
        self.program = program
        cell = program.cell
        krl = cell.dialects["krl"]
        self.decimals = krl.decimals
        self.stages = (
            [0, 1, 2] if cell.drilling.retract_mm == cell.drilling.approach_mm else [0, 1, 2, 3]
        )
        self.names = [STAGES[k] for k in self.stages]
        self._block: tuple = (0, 0, None)
        ext = "".join(
            f",E{k + 1} {fixed(v, krl.decimals)}" for k, v in enumerate(krl.external_axes)
        )
        self.position_template = "".join(
            f"DECL E6POS XH{SLOT}_{s}={{X {SLOT},Y {SLOT},Z {SLOT},A {SLOT},B {SLOT},C {SLOT},"
            f"S {SLOT},T {SLOT}{ext}}}\r\n"
            for s in self.names
        )
        self.hole_template = _hole_template(cell, self.names)
        self._named: tuple = (None, None, [])

    def context(self, lo: int, hi: int, uses: frozenset[str] | None) -> dict[str, object]:
        """Template variables of holes lo..hi-1 that ``uses`` names (None: all)."""
        wanted = {"holes", "positions", "hole_lines", "position_lines"}
        if uses is not None:
            wanted &= uses
        out: dict[str, object] = {}
        n, k = hi - lo, len(self.stages)
        if "positions" in wanted:
            pos, abc = self._numbers(lo, hi, "pos", "abc")
            table = np.empty((n, k, 9), dtype=object)
            for j, column in enumerate(self._names(lo, hi)):
                table[:, j, 0] = column
            table[:, :, 1:4] = fixed_texts(pos, self.decimals)
            table[:, :, 4:7] = fixed_texts(abc, self.decimals, distinct=True)[:, None, :]
            table[:, :, 7:9] = fixed_texts(self.status_turn(lo, hi), 0, distinct=True)
            out["positions"] = list(map(KrlPosition._make, table.reshape(n * k, 9).tolist()))
        if "position_lines" in wanted:
            out["position_lines"] = self.lines_bytes("position_lines", lo, hi).decode("ascii")
        if "holes" in wanted:
            labels, feed_m_s = self._numbers(lo, hi, "labels", "feed_m_s")
            names = self._names(lo, hi)
            retract = names[3] if k == 4 else names[0]
            feed = fixed_texts(feed_m_s, 4, distinct=True).tolist()
            out["holes"] = list(map(KrlHole, labels, *names[:3], retract, feed))
        if "hole_lines" in wanted:
            out["hole_lines"] = self.lines_bytes("hole_lines", lo, hi).decode("ascii")
        return out

    def status_turn(self, lo: int, hi: int) -> np.ndarray:
        """KUKA Status and Turn (hi - lo, stages, 2) of holes lo..hi-1: the .dat needs them (the
        .src does not), so this is where a job waits for the program's IK check to reach
        them (``Program.configuration_of``)."""
        words = configuration_words(self.program.configuration_of(lo, hi))  # S 0..7, T 0..63
        return words[:, self.stages].astype(np.int16)

    def _block_of(self, lo: int, hi: int) -> tuple[int, SimpleNamespace]:
        """The first hole and the block that holds holes lo..hi-1 (a new one when a file first
        asks past the last block): its size ``n``, the feed ``feed_m_s`` (n,) m/s, the line
        ``images`` made so far by kind, and the parts ``_part`` makes on first use."""
        start, end, block = self._block
        if block is None or not start <= lo <= hi <= end:
            start, end = lo, max(hi, min(lo + BLOCK, len(self.program)))
            feed_m_s = self.program.feed_mm_s[start:end] / 1000.0
            block = SimpleNamespace(n=end - start, feed_m_s=feed_m_s, images={})
            self._block = (start, end, block)
        return start, block

    def _part(self, start: int, block: SimpleNamespace, name: str):
        """A part of the block from ``start``, made on first use (the ``.src`` need the labels,
        the ``.dat`` the numbers): positions ``pos`` (n, stages, 3) mm in the BASE frame, A,B,C
        ``abc`` (n, 3) deg, the hole ``labels`` (n,); or the ``feed_m_s``."""
        if not hasattr(block, name):
            program, end = self.program, start + block.n
            if name == "labels":
                block.labels = program.labels(start, end)
            else:
                pos, block.abc = program.in_frame(program.cell.robot_T_base, start, end)
                block.pos = pos[:, self.stages]
        return getattr(block, name)

    def _numbers(self, lo: int, hi: int, *names: str) -> list:
        """The parts ``names`` (see ``_part``) of holes lo..hi-1."""
        start, block = self._block_of(lo, hi)
        part = slice(lo - start, hi - start)
        return [self._part(start, block, name)[part] for name in names]

    def lines_bytes(self, kind: str, lo: int, hi: int) -> bytes:
        """The ``hole_lines`` or ``position_lines`` of holes lo..hi-1, ASCII: rows of the
        block's line image of that kind, made once per block."""
        start, block = self._block_of(lo, hi)
        if kind not in block.images:
            make = self._hole_image if kind == "hole_lines" else self._position_image
            block.images[kind] = make(start, block)
        return image_bytes(block.images[kind][lo - start : hi - start])

    def line_count(self, kind: str, lo: int, hi: int) -> int:
        """The lines ``lines_bytes`` has for holes lo..hi-1 (labels are one-line comments)."""
        per_hole = self.hole_template.count("\n") if kind == "hole_lines" else len(self.stages)
        return (hi - lo) * per_hole

    def _position_image(self, start: int, block: SimpleNamespace) -> np.ndarray:
        """The line image of the .dat lines of the block of holes from ``start``: per hole, one
        DECL E6POS line per stage."""
        n, k = block.n, len(self.stages)
        pos, abc = self._part(start, block, "pos"), self._part(start, block, "abc")
        mm = number_cells(np.concatenate([pos.reshape(n, 3 * k), abc], axis=1), self.decimals)
        number = number_cells(np.arange(start + 1, start + n + 1), 0)
        st = _ST_CELLS[self.status_turn(start, start + n)]  # (n, k, 2, w): S 0..7, T 0..63
        cells = []
        for j in range(k):
            cells += [number, *(mm[:, 3 * j + c] for c in range(3))]
            cells += [*(mm[:, 3 * k + c] for c in range(3)), st[:, j, 0], st[:, j, 1]]
        return line_image(self.position_template, cells)

    def _hole_image(self, start: int, block: SimpleNamespace) -> np.ndarray:
        """The line image of the .src lines of the block of holes from ``start``: per hole, the
        lines of ``_hole_template``."""
        n = block.n
        number = number_cells(np.arange(start + 1, start + n + 1), 0)
        comments = text_cells(comment_texts(self._part(start, block, "labels")))
        feed = number_cells(block.feed_m_s, 4)
        return line_image(self.hole_template, [comments, number, number, feed, number, number])

    def _names(self, lo: int, hi: int) -> list[list[str]]:
        """Position names of holes lo..hi-1, one list per stage (made once for the .src and the
        .dat of a file)."""
        if self._named[:2] != (lo, hi):
            numbers = range(lo + 1, hi + 1)
            self._named = (lo, hi, [list(map(f"XH{{}}_{s}".format, numbers)) for s in self.names])
        return self._named[2]


_ST_CELLS = number_cells(np.arange(64), 0)  # the text of every KUKA Status (0..7) and Turn (0..63)


def _hole_template(cell, stages: list[str]) -> str:
    """The .src lines of one hole as a template of ``linebytes.line_image`` over (comment label,
    hole number, hole number, feed, hole number, hole number), with the cell's settings filled
    in; CRLF line ends."""
    approach = f"$VEL.CP = {fixed(cell.drilling.approach_mm_s / 1000.0, 4)}"
    krl = cell.dialects["krl"]
    if krl.travel_motion == "ptp":
        travel = [f"PTP XH{SLOT}_APP C_PTP"]
    else:
        travel = [
            f"$VEL.CP = {fixed(cell.drilling.travel_mm_s / 1000.0, 4)}",
            f"LIN XH{SLOT}_APP C_DIS",
        ]
    clamp = unclamp = []
    if krl.clamp_output is not None:
        clamp = [f"$OUT_C[{fixed(krl.clamp_output, 0)}] = TRUE ; clamp"]
        unclamp = [f"$OUT[{fixed(krl.clamp_output, 0)}] = FALSE ; unclamp"]
    lines = [
        f"; hole {SLOT}",
        *travel,
        approach,
        f"LIN XH{SLOT}_CLR",
        *clamp,
        f"$VEL.CP = {SLOT}",
        f"LIN XH{SLOT}_BOT",
        f"WAIT SEC {fixed(cell.drilling.dwell_s, 3)}",
        *unclamp,
        approach,
        f"LIN XH{SLOT}_{stages[3] if len(stages) == 4 else stages[0]} C_DIS",
    ]
    return "\r\n".join(lines) + "\r\n"


def _literal(text: str) -> str:
    """``text`` as literal text of a %-template."""
    return text.replace("%", "%%")


def _lines(text: str) -> int:
    return text.count("\n")
