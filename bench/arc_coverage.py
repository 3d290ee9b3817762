"""How many arcs, the moves that start them, and canned cycles in the G18/G19 planes
``accugrid rewrite`` corrects in real G-code programs (../shared/realworld/gcode, plus any
programs given as arguments), with the example cell (its measured-like grid, 200 mm step).

    .venv/bin/python bench/arc_coverage.py [--decimals N] [PROGRAM ...]

Each program is rewritten by the command line with ``--allow-partial --report``; the report has
one row per move the reader finds, in order, so the rows are matched with the reader's moves:
an arc is a G2/G3 row, its start moves are the moves that last set its start X, Y and Z; the
plane of a cycle is read here from the G17/G18/G19 words of the lines (comments removed).
Prints one line per program and the totals (corrected / all).
"""

from __future__ import annotations

import csv
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from accugrid.codegen.gcode.parse import CYCLES, parse_gcode  # noqa: E402

CELL = ROOT / "examples" / "cell_heatsink.yaml"
REALWORLD = ROOT.parent / "shared" / "realworld" / "gcode"
ACCUGRID = Path(sys.executable).parent / "accugrid"
_COMMENT = re.compile(r"\([^)]*\)|;.*")
_PLANE = re.compile(r"G0*(17|18|19)(?![\d.])", re.I)


def planes(text: str) -> list[str]:
    """The plane in effect after each line (1-based list index = line number - 1)."""
    plane, out = "17", []
    for line in text.splitlines():
        found = _PLANE.findall(_COMMENT.sub(" ", line))
        plane = found[-1] if found else plane
        out.append(plane)
    return out


def coverage(program: Path, folder: Path, options: list[str]) -> dict[str, list[int]]:
    """[corrected, all] of arcs, arc starts, G18/G19 cycles and every move of one program
    (``options``: more options of the command)."""
    out, report = folder / program.name, folder / (program.name + ".csv")
    run = subprocess.run(
        [str(ACCUGRID), "rewrite", "--allow-partial", str(program), "--cell", str(CELL)]
        + ["-o", str(out), "--report", str(report), "--force", *options],
        capture_output=True,
        text=True,
        check=False,
    )
    if run.returncode != 0:
        print(f"{program.name}: exit {run.returncode}: {run.stderr.strip()[:200]}")
        return {}
    rows = list(csv.DictReader(report.open(newline="")))
    text = program.read_bytes().decode("latin-1")
    moves = parse_gcode(text, program)
    assert len(rows) == len(moves), program
    done = [r["status"] == "corrected" for r in rows]
    arcs = [i for i, m in enumerate(moves) if m.is_arc]
    starts = sorted({j for i in arcs for j in moves[i].setters if j is not None})
    plane = planes(text)
    side = [i for i, m in enumerate(moves) if m.motion[1:] in CYCLES and plane[m.line - 1] != "17"]
    count = {"arcs": arcs, "arc starts": starts, "G18/G19 cycles": side}
    count["moves"] = list(range(len(moves)))
    return {k: [sum(done[i] for i in v), len(v)] for k, v in count.items()}


def main(args: list[str]) -> None:
    options = args[:2] if args[:1] == ["--decimals"] else []
    programs = sorted(REALWORLD.iterdir()) + [Path(p) for p in args[len(options) :]]
    totals: dict[str, list[int]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for program in programs:
            numbers = coverage(program, Path(tmp), options)
            if numbers:
                shown = ", ".join(f"{k} {a}/{b}" for k, (a, b) in numbers.items())
                print(f"{program.name}: {shown}")
            for k, (a, b) in numbers.items():
                totals.setdefault(k, [0, 0])
                totals[k][0] += a
                totals[k][1] += b
    print("total: " + ", ".join(f"{k} {a}/{b}" for k, (a, b) in totals.items()))


if __name__ == "__main__":
    main(sys.argv[1:])
