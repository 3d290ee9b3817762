"""What a pre-flight rewrite is (``accugrid rewrite``), the same for every dialect: options, report
rows, the correction of robot-frame points, the job rule, the report CSV and the header, and the
rewrite itself over a dialect's plug-in (``rewrite``: its ``scan``, the one correction, its
``splice``; ``codegen.plugin``).

Each Cartesian position that can be placed in the robot frame is corrected with the grid model
(P' = P + e, in the robot frame, converted back to the program's frame) and only its X, Y, Z
numbers are replaced in the text; every other byte is kept (``codegen.program_text``). What cannot
be placed is reported with the reason, never guessed. Whether a placed position is corrected is
the correction policy's verdict (``compensation.policy``); a position it does not correct
(outside the grid, orientation or Status the grid does not hold for, ...) fails the job unless
``allow_partial``, which leaves it as it is and marks it in the report, and so does a rewrite that
corrects nothing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from accugrid.codegen.header import grid_lines, input_line
from accugrid.codegen.header import header_lines as make_header
from accugrid.codegen.plugin_types import CORRECTED, OUTSIDE, SKIPPED, STATUSES, Options, Row, Rows
from accugrid.codegen.program_text import distinct_ints
from accugrid.compensation.policy import CORRECTED as POLICY_CORRECTED
from accugrid.compensation.policy import (
    FIXES,
    NOT_PLACED,
    OUTSIDE_GRID,
    REASONS,
    TOO_LONG,
)
from accugrid.infra.digest import file_sha256
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix

if TYPE_CHECKING:
    from accugrid.codegen.plugin import DialectPlugin

__all__ = [
    "REPORT_COLUMNS",
    "Result",
    "correct_points",
    "header_lines",
    "last_known",
    "partial_check",
    "report_csv",
    "rewrite",
    "rotations_of",
    "warning_lines",
]

REPORT_COLUMNS = (
    "file,line,name,status,reason,x,y,z,x_new,y_new,z_new,dx,dy,dz,correction_mm,residual_mm,u95_mm"
)
_DECIDE = 1 << 16  # positions the policy decides at a time


@dataclass
class Result:
    """The rewritten programs by input path (their latin-1 bytes), the report rows and the
    largest correction."""

    data: dict[str, bytes | bytearray]
    rows: Rows

    @property
    def texts(self) -> dict[str, str]:
        """The rewritten programs as text (decoded on each call)."""
        return {path: data.decode("latin-1") for path, data in self.data.items()}

    @property
    def corrected(self) -> list[Row]:
        return [self.rows[i] for i in np.flatnonzero(self.rows.status == CORRECTED).tolist()]

    def largest(self) -> tuple[float, Row | None]:
        """The longest correction written (mm) and its row (the first of equals)."""
        rows = self.rows
        idx = np.flatnonzero(rows.status == CORRECTED)
        if not idx.size:
            return 0.0, None
        approx = np.linalg.norm(rows.new[idx] - rows.old[idx], axis=1)
        best, where = 0.0, None
        for i in idx[approx >= approx.max() * (1 - 1e-9)].tolist():  # exact as math.dist
            d = math.dist(rows.new[i].tolist(), rows.old[i].tolist())
            if d > best:
                best, where = d, i
        return best, None if where is None else rows[where]


def rewrite(plugin: DialectPlugin, texts: dict[str, str], opts: Options, placement) -> Result:
    """Rewrite the programs ``texts`` (path -> latin-1 text) of one dialect: its ``scan``, the
    one correction (``correct_points``), its ``splice``, the job rule (``partial_check``).
    ``placement``: the dialect's record of the frames (``plugin.placement``)."""
    scan = plugin.scan(texts, opts, placement)
    status = None if scan.code is None else last_known(scan.code, scan.rows.file[scan.at])
    corrected = correct_points(scan.robot, scan.rows, scan.at, opts, scan.rotations, status=status)
    scan.rotations = scan.code = None  # the splice needs neither: memory for its output
    data = plugin.splice(scan, corrected, opts)
    partial_check(scan.rows, opts)
    rows = scan.rows if scan.others is None else Rows.concat([scan.rows, scan.others])
    return Result(data, rows)


def last_known(status: np.ndarray, file: np.ndarray) -> np.ndarray:
    """Each position's configuration code (M,) from its own (M,) (-1: none) or, where it has none,
    the last one written before it in its file (a motion that names none keeps the configuration the
    robot is in), -1 where none is; ``file`` (M,) the file of each, the positions of a file together
    in text order."""
    n = len(status)
    status = np.asarray(status)
    if not n:
        return status
    start = np.ones(n, bool)
    start[1:] = file[1:] != file[:-1]
    source = np.where((status >= 0) | start, np.arange(n), 0)
    np.maximum.accumulate(source, out=source)
    return status[source]


def correct_points(
    points_robot: np.ndarray,
    rows: Rows,
    at: np.ndarray,
    opts: Options,
    rotations: np.ndarray | None = None,
    mark: bool = True,
    status: np.ndarray | None = None,
) -> np.ndarray:
    """Correct robot-frame points (N, 3) mm by the policy's verdict (``opts.policy``); (N, 3)
    commands, NaN rows where a point is not corrected.

    ``at`` (N,): the report row of each point in ``rows`` (an error names its file and line).
    ``rotations`` (N, 3, 3): each point's orientation, robot frame (NaN rows: none; with a model and
    ``opts.reference_abc`` such a point takes the reference). ``status`` (N,): each point's own
    configuration code (``Configuration.code``; -1: the job's). With ``mark``, rows not corrected
    get status "outside" (outside the grid) or stay "skipped", with the policy's code and words as
    the reason; flagged rows a ``flag:`` reason. InputError at the row when a correction is longer
    than the safety limit."""
    out = np.full_like(points_robot, np.nan)
    if not len(points_robot):
        return out
    if opts.calibrated is not None and opts.reference_abc is not None:
        reference = abc_to_matrix(np.array(opts.reference_abc))
        if rotations is None:
            rotations = np.broadcast_to(reference, (len(points_robot), 3, 3))
        else:
            given = np.isfinite(rotations[:, 0, 0])
            rotations = np.where(given[:, None, None], rotations, reference)
    tools = rows.tool[at] if opts.tool_data is not None else np.zeros(0, np.int64)
    if not (tools >= 0).any():  # the cell's tool alone
        _decide(points_robot, rows, at, opts, rotations, mark, status, -1, out)
        return out
    for number in (k - 1 for k in distinct_ints(tools + 1)):
        sub = np.flatnonzero(tools == number)
        _decide(
            points_robot[sub],
            rows,
            at[sub],
            opts,
            None if rotations is None else rotations[sub],
            mark,
            None if status is None else np.asarray(status)[sub],
            number,
            out,
            sub,
        )
    return out


def _decide(points, rows, at, opts, rotations, mark, status, tool, out, sub=slice(None)) -> None:
    """``correct_points`` for the points of one tool (-1: the cell's), written to ``out[sub]``:
    the policy's verdicts a block of ``_DECIDE`` points at a time (its temporaries, a few arrays
    of (N, 8) and (N, 3, 3) at a million points, stay those of one block)."""
    if tool >= 0 and tool != opts.tool_number and tool not in opts.tool_data:
        if mark:  # not placed: where its TCP is is not known
            rows.code[at] = NOT_PLACED
            for i in at.tolist():
                rows.reason[i] = f"tool {tool} is not declared in the cell file (tool, tool_data)"
        return
    index = np.arange(len(out))[sub]
    worst = None  # (value, verdict, first point) of the block with the longest correction over
    for a in range(0, len(points), _DECIDE):  # the safety limit
        b = slice(a, a + _DECIDE)
        verdict = _verdict(
            opts,
            tool,
            points[b],
            None if rotations is None else rotations[b],
            None if status is None or np.ndim(status) == 0 else status[b],
        )
        over = np.flatnonzero(verdict.code == TOO_LONG)
        if over.size and (worst is None or verdict.value[over].max() > worst[0]):
            worst = (verdict.value[over].max(), verdict, a)
        if worst is not None:
            continue  # the job fails: what is left is only looked at for a longer correction
        block = at[b]
        if mark:
            refused = verdict.refused
            rows.code[block[refused]] = verdict.code[refused]
            rows.status[block[refused[verdict.code[refused] == OUTSIDE_GRID]]] = OUTSIDE
            # refused or flagged (``np.union1d`` would import numpy.ma, 10 ms of start-up)
            either = (verdict.code != POLICY_CORRECTED) | (verdict.flags != 0)
            for i in np.flatnonzero(either).tolist():
                words = verdict.reason(i)
                rows.reason[block[i]] = words if verdict.code[i] else f"flag: {words}"
        use = np.flatnonzero(verdict.code == POLICY_CORRECTED)
        out[index[b][use]] = verdict.command[use]
        if "u95" in verdict.numbers:
            rows.u95_mm[block[use]] = verdict.numbers["u95"][use]
    if worst is not None:  # the safety limit (the rows' verdicts are counted for the whole job)
        _, verdict, a = worst
        verdict.enforce(
            lambda i: rows.name[at[a + i]], lambda i: rows.where(at[a + i]), allow_partial=True
        )


def _verdict(opts: Options, tool: int, points, rotations, status):
    """The policy's verdict on points (n, 3) mm robot frame of tool number ``tool`` (-1: the
    cell's), their rotations (n, 3, 3) or None and Status (n,) or None."""
    if tool < 0 or tool == opts.tool_number:
        return opts.policy.decide(points, rotations, status=status)
    return opts.policy.decide_tool(tool, opts.tool_data[tool], points, rotations, status=status)


def rotations_of(frames: np.ndarray, abc: np.ndarray) -> np.ndarray:
    """Robot-frame orientations (N, 3, 3) of A, B, C (N, 3) deg written in frames (N, 3, 3) or
    one (3, 3); NaN rows where a position gives no orientation."""
    return frames @ abc_to_matrix(abc)


def warning_lines(result: Result, opts: Options) -> list[str]:
    """What the user must know although nothing failed: rounding that eats the tolerance,
    positions flagged for their orientation."""
    out = []
    rows = result.rows
    corrected = np.flatnonzero(rows.status == CORRECTED)
    rounding = rows.rounding_mm[corrected]
    rounded = corrected[rounding > opts.tolerance_mm / 10]
    if rounded.size:
        worst = int(rounded[np.argmax(rows.rounding_mm[rounded])])
        file, line = rows.where(worst)
        out.append(
            f"rounding to the written decimals leaves {rounded.size} position(s) more than a "
            f"tenth of the tolerance ({opts.tolerance_mm:g} mm) off, up to "
            f"{rows.rounding_mm[worst]:.3f} mm ({Path(file).name} line {line}): give "
            "more --decimals"
        )
    flagged = (
        [i for i in corrected.tolist() if rows.reason[i].startswith("flag: ")]
        if any(rows.reason)
        else []
    )
    if flagged:
        file, line = rows.where(flagged[0])
        out.append(
            f"{len(flagged)} corrected position(s) flagged (see the report), first "
            f"{Path(file).name} line {line}: {rows.reason[flagged[0]][6:]}"
        )
    refused = np.flatnonzero(rows.code != POLICY_CORRECTED)
    if refused.size:  # the job went on: --allow-partial
        out.append(f"{refused.size} position(s) left uncorrected ({_counts(rows)})")
    return out


def _counts(rows: Rows) -> str:
    """The positions the policy did not correct, counted by reason."""
    codes, count = np.unique(rows.code[rows.code != POLICY_CORRECTED], return_counts=True)
    return ", ".join(f"{c} {REASONS[int(k)][0]}" for k, c in zip(codes, count, strict=True))


def partial_check(rows: Rows, opts: Options) -> None:
    """The policy's job rule over the whole rewrite. A position a motion commands (``commanded``)
    that could not be placed in the robot frame (skipped, with its reason) lands off by the
    robot's error like one the policy refused: it gets the code ``NOT_PLACED`` and counts.
    Joint targets, tool and base frames, offsets and data no motion uses are not positions to
    correct and do not count. A position the splice left uncorrected has no 95 % bound (the
    policy's was for its correction). InputError at the worst position whose bound exceeds the
    policy's ``max_u95_mm``, at the first position not corrected, with the counts by reason, and
    when nothing at all is corrected, unless ``opts.allow_partial``."""
    rows.u95_mm[rows.status != CORRECTED] = np.nan
    unplaced = rows.commanded & (rows.status == SKIPPED) & (rows.code == POLICY_CORRECTED)
    if unplaced.any():
        rows.code[unplaced] = NOT_PLACED
        for i in np.flatnonzero(unplaced).tolist():
            rows.reason[i] = rows.reason[i] or "its position is not known"
    if opts.allow_partial:
        return
    limit = opts.policy.max_u95_mm
    over = np.flatnonzero(rows.u95_mm > limit) if limit is not None else np.zeros(0, int)
    if over.size:
        i = int(over[np.argmax(rows.u95_mm[over])])
        raise InputError(
            f"{over.size} position(s) beyond the largest 95 % bound; the worst {rows.name[i]}: "
            f"95 % bound {rows.u95_mm[i]:.4f} mm beyond --max-u95 {limit:g} mm "
            "(--allow-partial writes them corrected and flagged)",
            *rows.where(i),
        )
    refused = np.flatnonzero(rows.code != POLICY_CORRECTED)
    if refused.size:
        i = int(refused[0])
        fix = FIXES.get(
            int(rows.code[i]),
            "--allow-partial writes the program with them as they are, marked in the report",
        )
        raise InputError(
            f"{refused.size} position(s) cannot be corrected ({_counts(rows)}); first "
            f"{rows.name[i]}: {rows.reason[i]} ({fix})",
            *rows.where(i),
        )
    if not len(rows):  # a program of calls, or of data only: its holes are elsewhere
        raise InputError(
            "no position corrected: the program commands no position that a rewrite can read "
            "(its motions may be in routines it calls; --allow-partial writes it unchanged)",
            rows.files[0] if rows.files else None,
        )
    if not rows.count(CORRECTED):
        i = 0
        raise InputError(
            f"no position corrected: {len(rows)} position(s) read, none placed and corrected; "
            f"first {rows.name[i]}: {rows.reason[i] or 'not corrected'} (see --report; "
            "--allow-partial writes the program unchanged)",
            *rows.where(i),
        )


def header_lines(result: Result, program: str, cell: str, opts: Options) -> list[str]:
    """The header of docs/guarantees.md: version, input and grid SHA-256, grid step, largest
    correction.

    File names only (no directories, no dates), so the same inputs give the same bytes."""
    largest, where = result.largest()
    model = opts.model
    at = "" if where is None else f" at {where.name} line {where.line}"
    inputs = [
        input_line("program", program, file_sha256(program)),
        input_line("cell", cell, file_sha256(cell)),
    ]
    if model is not None:
        grid = Path(model.source_path).name if model.source_path else "arrays"
        inputs += grid_lines(grid, model.source_sha256, model.step)
    if opts.model_file is not None:
        inputs.insert(2, input_line("model", opts.model_file, file_sha256(opts.model_file)))
    rows = result.rows
    closing = [f"positions corrected {rows.count(CORRECTED)}"]
    for i in np.flatnonzero(rows.code != POLICY_CORRECTED).tolist():
        closing.append(f"not corrected: line {rows.line[i]} {rows.name[i]}: {rows.reason[i]}")
    return make_header("rewrite", inputs, (), largest, at, closing, rows.u95_mm)


def report_csv(rows: Rows, decimals: int = 4) -> str:
    """The report as CSV text (docs/formats.md style: header row, mm, ``decimals`` places; the
    95 % bound of a corrected position empty where unknown)."""
    corrected = ",".join([f"%.{decimals}f"] * 12)  # x..z, new x..z, dx..dz, length, residual, u95
    old_only = ",".join([f"%.{decimals}f"] * 3) + ",,,,,,,,,"
    files = [_csv(Path(f).name) for f in rows.files]
    out = [REPORT_COLUMNS]
    for file, line, name, status, reason, old, new, residual, u95 in zip(
        rows.file.tolist(),
        rows.line.tolist(),
        rows.name,
        rows.status.tolist(),
        rows.reason,
        rows.old.tolist(),
        rows.new.tolist(),
        rows.residual_mm.tolist(),
        rows.u95_mm.tolist(),
        strict=True,
    ):
        head = f"{files[file]},{line},{_csv(name)},{STATUSES[status]},{_csv(reason)},"
        if status == CORRECTED:
            (x, y, z), (u, v, w) = old, new
            dx, dy, dz = u - x, v - y, w - z
            length = math.sqrt(dx * dx + dy * dy + dz * dz)
            numbers = corrected % (x, y, z, u, v, w, dx, dy, dz, length, residual, u95)
        elif old[0] == old[0] and old[1] == old[1] and old[2] == old[2]:
            numbers = old_only % tuple(old)
        else:
            numbers = ",,,,,,,,,,,"
        out.append(head + numbers.replace("-0.0000,", "0.0000,").replace("nan", ""))
    return "\n".join(out) + "\n"


def _csv(text: str) -> str:
    if "," not in text and '"' not in text and "\n" not in text and "\r" not in text:
        return text
    text = text.replace("\r", " ").replace("\n", " ")
    if any(c in text for c in ',"'):
        return '"' + text.replace('"', '""') + '"'
    return text
