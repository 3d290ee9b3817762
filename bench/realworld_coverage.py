"""How much of a corpus of real G-code programs `accugrid rewrite` corrects by default: each file
through the command line (``--allow-partial``, a report), in a cell whose grid (a constant
error over +-5 m) covers every position, so that only what the reader cannot place or correct
is left. Prints per file the positions, those corrected, or the refusal (exit 2, its message),
then the totals and the most frequent reasons.

    .venv/bin/python bench/realworld_coverage.py [FOLDER ...]   (default ../shared/realworld)
"""

from __future__ import annotations

import collections
import contextlib
import csv
import io
import re
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from accugrid.app.cli import main as accugrid  # noqa: E402
from accugrid.codegen.dialects import DIALECTS  # noqa: E402

_LINE_NUMBERS = re.compile(r"\bline \d+|\(line \d+\)")


def write_cell(folder: Path) -> Path:
    """cell.yaml and a grid with the constant error (0.25, -0.125, 0.375) mm over +-5 m."""
    axis = np.arange(-5000.0, 5001.0, 2500.0)
    pts = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
    rows = ["id,x,y,z,x_meas,y_meas,z_meas"]
    for i, p in enumerate(pts):
        m = p - (0.25, -0.125, 0.375)
        rows.append(f"{i}," + ",".join(f"{v:.4f}" for v in (*p, *m)))
    (folder / "grid.csv").write_text("\n".join(rows) + "\n")
    cell = folder / "cell.yaml"
    cell.write_text(
        "robot: kr210\ngrid: grid.csv\ntool: {number: 1, x: 0, y: 0, z: 250, a: 0, b: 0, c: 0}\n"
        "base: {number: 1, x: 0, y: 0, z: 0, a: 0, b: 0, c: 0}\n"
    )
    return cell


def coverage(files: list[Path]) -> None:
    total = corrected = refused = 0
    reasons: collections.Counter[str] = collections.Counter()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        cell = write_cell(folder)
        print(f"{'file':48} {'positions':>9} {'corrected':>9}")
        for path in files:
            report = folder / "report.csv"
            report.unlink(missing_ok=True)
            err = io.StringIO()
            argv = ["rewrite", "--allow-partial", str(path), "--cell", str(cell)]
            argv += ["-o", str(folder / path.name), "--report", str(report), "--force"]
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
                code = accugrid(argv)
            if code != 0:
                refused += 1
                message = err.getvalue().strip().splitlines()[-1:] or ["?"]
                print(f"{path.name:48} refused (exit {code}): {message[0][:100]}")
                continue
            rows = list(csv.DictReader(report.open()))
            done = sum(r["status"] == "corrected" for r in rows)
            total, corrected = total + len(rows), corrected + done
            for r in rows:
                if r["status"] != "corrected":
                    reasons[_LINE_NUMBERS.sub("line N", r["reason"])[:90]] += 1
            print(f"{path.name:48} {len(rows):9d} {done:9d}")
    share = 100.0 * corrected / total if total else 0.0
    print(f"\n{len(files)} files, {refused} refused; {corrected} of {total} positions corrected")
    print(f"({share:.1f} %)")
    for reason, count in reasons.most_common(12):
        print(f"{count:7d}  {reason}")


def g_code_files(folders: list[Path]) -> list[Path]:
    return sorted(
        p
        for f in folders
        for p in f.rglob("*")
        if p.is_file() and p.suffix.lower() in DIALECTS["gcode"].suffixes
    )


if __name__ == "__main__":
    given = [Path(a) for a in sys.argv[1:]] or [ROOT.parent / "shared" / "realworld"]
    coverage(g_code_files(given))
