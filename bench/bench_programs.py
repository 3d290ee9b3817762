"""100,000 drilling holes to KUKA KRL, to G-code and to FANUC TP, including the grid correction
and the IK of every pose (issue target: under 5 s each). Stages timed separately, then the whole
job.

Holes: a 400 x 250 pattern at 1.5 mm pitch on the example wing panel (examples/cell.yaml, drill
axis normal to the 4 m radius skin), corrected with examples/grid_200mm.csv; for FANUC the same
holes in examples/cell_fanuc.yaml (an R-2000iC/165F), corrected with its grid_r2000ic_200mm.csv.
The last three rows are the whole commands (CSV file in, program files out). Best of 3; peak MiB
is traced Python memory.
Each render row is compared with its floor, measured in the same run: the numbers it prints made
into text alone, each value once per hole (``numbers_floor``, ``fanuc_numbers_floor``), without
the lines around them.
"""

from __future__ import annotations

import contextlib
import io
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from accugrid.app.cli import main as cli  # noqa: E402
from accugrid.codegen.cell import load_cell  # noqa: E402
from accugrid.codegen.fanuc.configuration import configuration_words as fanuc_words  # noqa: E402
from accugrid.codegen.fanuc.emit import HOLE_LINES, render_fanuc  # noqa: E402
from accugrid.codegen.gcode.emit import render_gcode  # noqa: E402
from accugrid.codegen.krl.configuration import configuration_words  # noqa: E402
from accugrid.codegen.krl.emit import render_krl  # noqa: E402
from accugrid.codegen.points import parse_points  # noqa: E402
from accugrid.codegen.program import build_program  # noqa: E402
from accugrid.compensation import GridModel  # noqa: E402
from accugrid.infra.decimals import read_decimals, words_at  # noqa: E402
from accugrid.infra.textsafe import fixed_bytes, fixed_many  # noqa: E402
from accugrid.kinematics.robot import load_robot  # noqa: E402
from bench.timing import measure, table  # noqa: E402

HOLES = 100_000
RADIUS_MM = 4000.0
NUMBERS = 1_500_000  # fixed_bytes rows: numbers formatted in one call


def points_csv(n: int = HOLES) -> str:
    """Points CSV text: n holes on the skin patch X -12.5..586, Y 100..475 mm (BASE frame): 400
    per row at 1.5 mm pitch, rows 1.5 mm apart, for n <= 100,000; a larger n fills the same patch
    with sqrt(n / 1e5) times as many columns and rows (a 1e6 job stays inside the grid, all holes
    within 5 deg of the grid's orientation, so no warnings)."""
    scale = max(1.0, np.sqrt(n / HOLES))
    cols, pitch = round(400 * scale), 1.5 / scale
    k = np.arange(n)
    x = -12.5 + pitch * (k % cols)
    y = 100.0 + pitch * (k // cols)
    z = np.sqrt(RADIUS_MM**2 - (x - 287.5) ** 2) - RADIUS_MM
    i, kk = -(x - 287.5) / RADIUS_MM, -(z + RADIUS_MM) / RADIUS_MM
    # test data, not a program: plain formatting is fine here
    rows = [
        f"B{h + 1:06d},{a:.3f},{b:.3f},{c:.4f},{d:.6f},0,{e:.6f},4.83,6"
        for h, (a, b, c, d, e) in enumerate(zip(x, y, z, i, kk, strict=True))
    ]
    return "id,x,y,z,i,j,k,diameter,depth\n" + "\n".join(rows) + "\n"


def robot_points_csv(n: int = HOLES) -> str:
    """The holes of ``points_csv(n)`` in the ROBOT frame (through the example cell's base), for
    ``accugrid correct``: x,y,z with 4 decimals, drill axis i,j,k with 6."""
    cell = load_cell(ROOT / "examples" / "cell.yaml")
    rot, org = cell.robot_T_base[:3, :3], cell.robot_T_base[:3, 3]
    holes = np.loadtxt(io.StringIO(points_csv(n)), delimiter=",", skiprows=1, usecols=range(1, 7))
    xyz, axis = holes[:, :3] @ rot.T + org, holes[:, 3:] @ rot.T
    rows = [  # test data, not a program: plain formatting is fine here
        f"B{h + 1:06d},{a:.4f},{b:.4f},{c:.4f},{d:.6f},{e:.6f},{f:.6f},4.83,6"
        for h, (a, b, c, d, e, f) in enumerate(np.column_stack([xyz, axis]).tolist())
    ]
    return "id,x,y,z,i,j,k,diameter,depth\n" + "\n".join(rows) + "\n"


def numbers_floor(program, krl: bool) -> int:
    """Bytes of the text of every number a program prints, each value once per hole, made a
    block of 16,384 holes at a time as the renderers do: positions (n, stages, 3) and A B C
    (n, 3) in the dialect's frame with its decimals, the feed (n,), and for KRL the hole number
    and the S and T of each position, NULs dropped."""
    cell = program.cell
    frame, places = (
        (cell.robot_T_base, cell.dialects["krl"].decimals)
        if krl
        else (cell.dialects["gcode"].robot_T_program, cell.dialects["gcode"].decimals)
    )
    stages = [0, 1, 2, 3]
    if krl and cell.drilling.retract_mm == cell.drilling.approach_mm:
        stages = [0, 1, 2]  # the RET position is the APP one
    status, turn = np.moveaxis(configuration_words(program.configuration), -1, 0)
    size = 0
    for lo in range(0, len(program), 16384):
        hi = min(lo + 16384, len(program))
        pos, abc = program.in_frame(frame, lo, hi)
        mm = np.concatenate([pos[:, stages].reshape(-1), abc.reshape(-1)])
        cells = [
            fixed_bytes(mm, places)[0],
            fixed_bytes(program.feed_mm_s[lo:hi], 4 if krl else 1)[0],
        ]
        if krl:
            ints = [np.arange(lo + 1, hi + 1), status[lo:hi, stages], turn[lo:hi, stages]]
            cells.append(fixed_bytes(np.concatenate([i.reshape(-1) for i in ints]), 0)[0])
        size += sum(len(c.tobytes().translate(None, b"\0")) for c in cells)
    return size


def fanuc_numbers_floor(program) -> int:
    """``numbers_floor`` of a FANUC TP program: positions (n, 4, 3) in the user frame (the base)
    and W P R (n, 3) with the cell's decimals, the feed (n,), and the line numbers, the P
    numbers and the turn numbers of every position."""
    places = program.cell.dialects["fanuc"].decimals
    size = 0
    for lo in range(0, len(program), 16384):
        hi = min(lo + 16384, len(program))
        pos, abc = program.in_frame(program.cell.robot_T_base, lo, hi)
        mm = np.concatenate([pos.reshape(-1), abc.reshape(-1)])
        turns = fanuc_words(program.configuration_of(lo, hi))[..., 3:]
        ints = [np.arange(HOLE_LINES * lo, HOLE_LINES * hi), np.arange(4 * lo, 4 * hi), turns]
        cells = [
            fixed_bytes(mm, places)[0],
            fixed_bytes(program.feed_mm_s[lo:hi], 0)[0],
            fixed_bytes(np.concatenate([i.reshape(-1) for i in ints]), 0)[0],
        ]
        size += sum(len(c.tobytes().translate(None, b"\0")) for c in cells)
    return size


def main() -> None:
    cell = load_cell(ROOT / "examples" / "cell.yaml")
    grid = GridModel.from_measurements(ROOT / "examples" / "grid_200mm.csv")
    robot = load_robot(cell.robot_name).with_tool(cell.flange_T_tool)
    text = points_csv()
    points = parse_points(text, "bench.csv")
    program = build_program(points, cell, robot, grid)
    header = ["bench"]
    fanuc_cell = load_cell(ROOT / "examples" / "cell_fanuc.yaml")
    fanuc_robot = load_robot(fanuc_cell.robot_name).with_tool(fanuc_cell.flange_T_tool)
    fanuc = build_program(points, fanuc_cell, fanuc_robot)  # the cell's grid

    def fanuc_render() -> int:
        return sum(len(piece) for piece in render_fanuc(fanuc, header)[Path("ACCUGRID.ls")])

    tmp = Path(tempfile.mkdtemp(prefix="accugrid-bench-"))
    points_file = tmp / "holes.csv"
    points_file.write_text(text)
    common = [str(points_file), "--cell", str(ROOT / "examples" / "cell.yaml"), "--force"]

    def krl_job():
        assert cli(["krl", *common, "-o", str(tmp / "krl")]) == 0

    def gcode_job():
        assert cli(["gcode", *common, "-o", str(tmp / "holes.ngc")]) == 0

    def fanuc_job():
        cell_args = ["--cell", str(ROOT / "examples" / "cell_fanuc.yaml"), "--force"]
        args = [str(points_file), *cell_args, "-o", str(tmp / "HOLES.ls")]
        assert cli(["fanuc", *args]) == 0

    stages = [
        ("parse points CSV", lambda: parse_points(text, "bench.csv")),
        ("correction + IK (program model)", lambda: build_program(points, cell, robot, grid)),
        ("render KRL (.src/.dat)", lambda: sum(map(len, render_krl(program, header).values()))),
        ("floor: KRL numbers as text", lambda: numbers_floor(program, True)),
        ("render G-code (.ngc)", lambda: render_gcode(program, header)),
        ("floor: G-code numbers as text", lambda: numbers_floor(program, False)),
        ("render FANUC (.ls)", fanuc_render),
        ("floor: FANUC numbers as text", lambda: fanuc_numbers_floor(fanuc)),
        ("accugrid krl (read, correct, IK, render, write)", krl_job),
        ("accugrid gcode (read, correct, IK, render, write)", gcode_job),
        ("accugrid fanuc (read, correct, IK, render, write)", fanuc_job),
    ]
    rows = []
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        for name, func in stages:
            seconds, peak = measure(func, repeats=3)
            rows.append((name, f"{seconds:.2f}", f"{peak:.0f}"))
    shutil.rmtree(tmp)
    files = render_krl(program, header)
    size = sum(len(t) for t in files.values()) / 2**20
    print(
        f"{HOLES} holes; KRL: {len(files)} files, {size:.1f} MiB; lines_per_file "
        f"{cell.dialects['krl'].lines_per_file}"
    )
    print(table(rows, ("stage", "best s", "peak MiB")))
    best = {name: float(seconds) for name, seconds, _ in rows}
    print(
        "render / floor: KRL "
        f"{best['render KRL (.src/.dat)'] / best['floor: KRL numbers as text']:.1f}x, G-code "
        f"{best['render G-code (.ngc)'] / best['floor: G-code numbers as text']:.1f}x, FANUC "
        f"{best['render FANUC (.ls)'] / best['floor: FANUC numbers as text']:.1f}x"
    )
    print()
    print(number_table())


def number_table(n: int = NUMBERS) -> str:
    """``textsafe.fixed_bytes`` (every number a program or CSV gets) on n numbers in one call, in
    ns per number (best of 5), against its floor measured in the same run: ``np.rint`` and
    ``astype`` of the same scaled array, the least that finds the digits; the %-formatting it
    replaces (``fixed_many``, best of 1) for scale. Then the reader of such texts."""
    rng = np.random.default_rng(0)
    coordinates, holes = rng.uniform(-3000.0, 3000.0, n), np.arange(1.0, n + 1.0)

    def ns(func, repeats=5):
        return measure(func, repeats)[0] * 1e9 / n

    rows = []
    for name, values, places in [
        ("+-3000 mm, 3 places", coordinates, 3),
        ("+-3000 mm, 0 places", coordinates, 0),
        (f"hole numbers 1..{n}, 0 places", holes, 0),
    ]:
        floor = ns(lambda v=values, p=places: np.rint(v * 10.0**p).astype(np.int64))
        fast = ns(lambda v=values, p=places: fixed_bytes(v, p))
        rows.append((name, f"{floor:.1f}", f"{fast:.1f}", f"{fast / floor:.1f}"))
    slow = ns(lambda: fixed_many(coordinates, 3), repeats=1)
    rows.append(("+-3000 mm, 3 places: %-formatting (fixed_many)", "", f"{slow:.1f}", ""))
    # and back: infra.decimals.read_decimals of those texts, one per line; its floor the
    # gather of the 8 bytes that end each text (words_at), the least a reader touches
    cells, _ = fixed_bytes(coordinates, 3)
    text = np.concatenate([cells, np.full((n, 1), ord("\n"), np.uint8)], axis=1).ravel()
    text = text[text != 0]
    end = np.flatnonzero(text == ord("\n"))
    start = np.concatenate([[0], end[:-1] + 1])
    floor = ns(lambda: words_at(text, end - 8))
    fast = ns(lambda: read_decimals(text, start, end))
    rows.append(
        (
            "read_decimals of their texts (3 places)",
            f"{floor:.1f}",
            f"{fast:.1f}",
            f"{fast / floor:.1f}",
        )
    )
    return f"fixed_bytes and read_decimals, {n} numbers per call\n" + table(
        rows, ("numbers", "floor ns/number", "ns/number", "/ floor")
    )


if __name__ == "__main__":
    main()
