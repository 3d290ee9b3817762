"""`accugrid rewrite` on big programs: a 100,000-position KRL .src/.dat pair (E6POS declarations
used by LIN motions, as a controller writes them), a 100,000-position KRL .src with inline
aggregates, and a 100,000-line G-code program (G90 moves and G81 holes). The whole command is
timed: cell and grid loading, parsing, correction, splicing and the atomic write. Target < 3 s.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.timing import measure, table  # noqa: E402
from codegen.cell import load_cell  # noqa: E402
from codegen.cli import main  # noqa: E402
from compensation import GridModel  # noqa: E402
from kinematics.frames import invert, transform_points  # noqa: E402

N = 100_000
CELL = ROOT / "examples" / "cell.yaml"


def positions(n: int, seed: int = 0) -> np.ndarray:
    """Points inside the example grid (robot frame), in the example cell's base frame (mm)."""
    cell = load_cell(CELL)
    grid = GridModel.from_measurements(cell.grid_path)
    rng = np.random.default_rng(seed)
    margin = 0.05 * (grid.upper - grid.origin)
    robot = rng.uniform(grid.origin + margin, grid.upper - margin, size=(n, 3))
    return transform_points(invert(cell.robot_T_base), robot)


def krl_pair(folder: Path) -> list[Path]:
    p = positions(N)
    dat = ["&ACCESS RVP", "DEFDAT big"]
    dat += [
        f"DECL E6POS XP{i}={{X {x:.3f},Y {y:.3f},Z {z:.3f},A 0.000,B 90.000,C 0.000,"
        f"S 'B010',T 'B000010',E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}}"
        for i, (x, y, z) in enumerate(p)
    ]
    src = ["&ACCESS RVP", "DEF big( )", "BAS (#BASE,1)"]
    src += [f"LIN XP{i} C_DIS" for i in range(N)] + ["END"]
    (folder / "big.dat").write_text("\r\n".join(dat + ["ENDDAT"]) + "\r\n")
    (folder / "big.src").write_text("\r\n".join(src) + "\r\n")
    return [folder / "big.src", folder / "big.dat"]


def krl_inline(folder: Path) -> list[Path]:
    p = positions(N, 1)
    src = ["&ACCESS RVP", "DEF inline( )", "$BASE = BASE_DATA[1]"]
    src += [
        f"LIN {{X {x:.3f},Y {y:.3f},Z {z:.3f},A 0.000,B 90.000,C 0.000}} C_DIS ; hole {i}"
        for i, (x, y, z) in enumerate(p)
    ]
    (folder / "inline.src").write_text("\r\n".join(src + ["END"]) + "\r\n")
    return [folder / "inline.src"]


def gcode(folder: Path) -> list[Path]:
    p = positions(N, 2)
    lines = ["%", "G21 G17 G90 G54", "G0 X0.000 Y300.000 Z400.000"]
    for i, (x, y, z) in enumerate(p[: N - 3]):
        if i % 4 == 3:
            lines.append(f"N{i} G99 G81 X{x:.3f} Y{y:.3f} Z{z:.3f} R{z + 20:.3f} F300")
        else:
            lines.append(f"N{i} G1 X{x:.3f} Y{y:.3f} Z{z:.3f} F3000 (move {i})")
    (folder / "big.ngc").write_text("\n".join(lines + ["%"]) + "\n")
    return [folder / "big.ngc"]


def main_bench() -> None:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for name, make in (
            ("KRL .src/.dat, 100k E6POS", krl_pair),
            ("KRL .src, 100k inline LIN", krl_inline),
            ("G-code, 100k lines", gcode),
        ):
            inputs = make(folder)
            size = sum(p.stat().st_size for p in inputs) / 2**20
            out = folder / f"out_{inputs[0].stem}"
            args = ["rewrite", *map(str, inputs), "--cell", str(CELL), "-o", str(out)]
            if len(inputs) == 1:
                args[-1] = str(out / inputs[0].name)

            def run(args=args) -> None:
                assert main([*args, "--force"]) == 0

            seconds, peak = measure(run, repeats=1)
            rows.append((name, f"{size:.1f}", f"{seconds:.2f}", f"{peak:.0f}"))
    print(table(rows, ("program", "size MiB", "rewrite s", "peak MiB (traced)")))


if __name__ == "__main__":
    main_bench()
