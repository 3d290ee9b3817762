"""Whole commands against their I/O floor (issue 14): each row runs the real `accugrid` process
and, in the same run, a floor: a bare Python process that imports what the row names or reads the
same input files and writes the same number of files and bytes. Ratio = command / floor. The
rewrite rows' floor also imports numpy (the rewrite speed bar: within 5x of that process).

Medians of 5 runs (3 for the 1e5 jobs, 1 for the 1e6 jobs); peak RSS of the process from
wait4. Before timing, the package's bytecode is refreshed (``compileall`` of its folders, which
writes the .pyc whatever PYTHONDONTWRITEBYTECODE says): the rows measure the product as
installed, whose modules are compiled once, not a compile of every module edited since
(ACCUGRID_BENCH_EXE runs another checkout: its bytecode is that checkout's to refresh).
`python bench/bench_commands.py --million` adds the 1e6 rows (minutes, GiB); `--only=rewrite`
(any word of the command column) runs only the rows that name it.
"""

from __future__ import annotations

import compileall
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.timing import table  # noqa: E402

CELL = ROOT / "examples" / "cell.yaml"
RAPID_CELL = ROOT / "examples" / "cell_irb6700.yaml"  # the same holes for an IRB 6700
# Issue 14's measurements of the code before the speed work (wall s, peak RSS MiB; "-" where
# the issue has none), printed beside each row's new numbers, and the target per row.
BEFORE = {
    "accugrid --help": ("0.75", "-"),
    "accugrid correct, 1 point": ("0.75", "-"),
    "accugrid krl, 1e5 holes": ("5.0", "284"),
    "accugrid krl, 1e6 holes": ("68", "2150"),
    "accugrid gcode, 1e5 holes": ("7.6", "-"),
    "accugrid rewrite, 1e5 KRL pair": ("8.1", "802"),
    "accugrid rewrite, 1e6 KRL pair": ("83", "7475"),
}
TARGET = {
    "accugrid --help": "<= 1.5x",
    "accugrid rewrite, 1e5": "<= 5x",
    "accugrid correct, 1 point": "<= 1.2x",
    "1e5": "<= 1.0 s, <= 8x",
    "accugrid correct, 1e5 points": "<= 0.5 s, <= 8x",
    "1e6": "linear, <= 977 MiB",
}
GRID = ROOT / "examples" / "grid_200mm.csv"
RAPID_GRID = ROOT / "examples" / "grid_irb6700_200mm.csv"
# the accugrid executable timed: this environment's, or ACCUGRID_BENCH_EXE (e.g. a wrapper that
# runs a checkout of an earlier commit, for a before/after table measured on the same machine)
ACCUGRID = os.environ.get("ACCUGRID_BENCH_EXE") or str(Path(sys.executable).with_name("accugrid"))

# The floor process: read every input file whole, write the given files with as many bytes. The
# files are listed in a manifest (a million-hole KRL job has thousands of them): "<" input path,
# or output size and path, one per line.
FLOOR_IO = """
import sys
if sys.argv[2:] == ["numpy"]:
    import numpy
with open(sys.argv[1]) as manifest:
    entries = [line.rstrip("\\n").split("\\t") for line in manifest]
for entry in entries:
    if entry[0] == "<":
        with open(entry[1], "rb") as f:
            f.read()
    else:
        with open(entry[1], "wb") as f:
            f.write(b"x" * int(entry[0]))
"""


# Writes one bench input: argv = project root, generator "module.name", target, n. A target
# with a suffix is a file and the generator returns its text; else a folder the generator writes
# its files into, returning them. Prints the paths written.
MAKE_INPUT = """
import sys
from pathlib import Path
sys.path.insert(0, sys.argv[1])
module, name = sys.argv[2].rsplit(".", 1)
make = getattr(__import__(module, fromlist=[name]), name)
target, n = Path(sys.argv[3]), int(sys.argv[4])
if target.suffix:
    target.write_text(make(n))
    print(target)
else:
    print("\\n".join(map(str, make(target, n))))
"""


# the package's sources (pyproject.toml maps them into ``accugrid``), as `make bytecode` lists them
PACKAGE = ("__init__.py", "app", "codegen", "compensation", "infra", "kinematics", "templates")


def refresh_bytecode() -> None:
    """Write the .pyc of every module of the package, as an installed package has them."""
    for name in PACKAGE:
        path = ROOT / name
        if path.is_dir():
            compileall.compile_dir(path, quiet=1)
        else:
            compileall.compile_file(path, quiet=1)


def make_input(generator: str, target: Path, n: int) -> list[Path]:
    """The input files ``generator`` makes for n rows at ``target``, made in a child process:
    the bench process never holds a large input, because a child's peak RSS (``wait4``) starts
    from its parent's at the fork (a 1e6-row text held here would show in every later row)."""
    argv = [sys.executable, "-c", MAKE_INPUT, str(ROOT), generator, str(target), str(n)]
    done = subprocess.run(argv, capture_output=True, text=True, check=True)
    return [Path(line) for line in done.stdout.splitlines()]


def run(argv: list[str]) -> tuple[float, float]:
    """(wall s, peak RSS MiB) of one process; SystemExit if it fails."""
    start = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    seconds = time.perf_counter() - start
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"{' '.join(argv[:3])}... failed: {proc.stderr.read().decode()[:300]}")
    proc.stderr.close()
    return seconds, usage.ru_maxrss / 1024


def median_run(argv: list[str], repeats: int) -> tuple[float, float]:
    runs = [run(argv) for _ in range(repeats)]
    return statistics.median(r[0] for r in runs), max(r[1] for r in runs)


def outputs_of(target: Path) -> list[Path]:
    return sorted(p for p in target.rglob("*") if p.is_file()) if target.is_dir() else [target]


def io_floor(inputs: list[Path], written: list[Path], scratch: Path, repeats: int, *imports):
    """The floor of a job that read ``inputs`` and wrote ``written`` (same count and sizes),
    after importing ``imports`` (only "numpy")."""
    scratch.mkdir(exist_ok=True)
    manifest = scratch.parent / "floor_manifest.txt"
    lines = [f"<\t{p}" for p in inputs]
    lines += [f"{p.stat().st_size}\t{scratch / f'f{i}'}" for i, p in enumerate(written)]
    manifest.write_text("\n".join(lines) + "\n")
    return median_run([sys.executable, "-c", FLOOR_IO, str(manifest), *imports], repeats)


def job_row(name, args, inputs, target, tmp, repeats):
    seconds, peak = median_run([ACCUGRID, *args, "--force"], repeats)
    imports = ["numpy"] if args[0] == "rewrite" else []
    floor, _ = io_floor(inputs, outputs_of(target), tmp / "floor", repeats, *imports)
    what = "numpy + same I/O" if imports else "same I/O in Python"
    return name, seconds, peak, what, floor


def main(million: bool, only: str = "") -> None:
    refresh_bytecode()
    rows = []
    with tempfile.TemporaryDirectory(prefix="accugrid-bench-") as folder:
        tmp = Path(folder)
        one = tmp / "one.csv"
        one.write_text("x,y,z\n1700,0,1500\n")
        if only in "accugrid --help":
            seconds, peak = median_run([ACCUGRID, "--help"], 5)
            floor, _ = median_run([sys.executable, "-c", "import numpy"], 5)
            rows.append(("accugrid --help", seconds, peak, "import numpy", floor))
        if only in "accugrid correct, 1 point":
            seconds, peak = median_run(
                [ACCUGRID, "correct", str(one), "--grid", str(GRID), "-o", str(tmp / "c1.csv")]
                + ["--force"],
                5,
            )
            floor, _ = median_run([sys.executable, "-c", "import numpy, scipy.spatial"], 5)
            rows.append(("accugrid correct, 1 point", seconds, peak, "import numpy, scipy", floor))

        sizes = [(100_000, 3)] + ([(1_000_000, 1)] if million else [])
        for n, repeats in sizes if only in "accugrid krl gcode rapid holes correct points" else ():
            label = f"{n:.0e}".replace("+0", "")
            (holes,) = make_input("bench.bench_programs.points_csv", tmp / f"holes{n}.csv", n)
            for command, out, cell, grid in (
                ("krl", tmp / f"krl{n}", CELL, GRID),
                ("gcode", tmp / f"holes{n}.ngc", CELL, GRID),
                ("rapid", tmp / f"HOLES{n}.mod", RAPID_CELL, RAPID_GRID),
            ):
                if only not in f"accugrid {command} holes":
                    continue
                args = [command, str(holes), "--cell", str(cell), "-o", str(out)]
                name = f"accugrid {command}, {label} holes"
                rows.append(job_row(name, args, [holes, cell, grid], out, tmp, repeats))
            if only not in "accugrid correct points":
                continue
            (robot_holes,) = make_input(
                "bench.bench_programs.robot_points_csv", tmp / f"robot{n}.csv", n
            )
            out = tmp / f"corrected{n}.csv"
            args = ["correct", str(robot_holes), "--grid", str(GRID), "-o", str(out)]
            name = f"accugrid correct, {label} points"
            rows.append(job_row(name, args, [robot_holes, GRID], out, tmp, repeats))
        for n, repeats in sizes if only in "accugrid rewrite KRL pair G-code RAPID module" else ():
            # rewrite: a KRL .src/.dat pair, a G-code file and a RAPID module of n positions
            label = f"{n:.0e}".replace("+0", "")
            folder = tmp / f"rewrite{n}"
            folder.mkdir()
            pair = make_input("bench.bench_rewrite.krl_pair", folder, n)
            out = tmp / f"rewritten{n}"
            args = ["rewrite", *map(str, pair), "--cell", str(CELL), "-o", str(out)]
            args += ["--max-mb", "512"]  # a 1e6-position .dat is 138 MiB (default limit 64)
            name = f"accugrid rewrite, {label} KRL pair"
            rows.append(job_row(name, args, [*pair, CELL, GRID], out, tmp, repeats))
            (ngc,) = make_input("bench.bench_rewrite.gcode", folder, n)
            out_ngc = tmp / f"rewritten{n}.ngc"
            args = ["rewrite", str(ngc), "--cell", str(CELL), "-o", str(out_ngc)]
            args += ["--max-mb", "512"]
            name = f"accugrid rewrite, {label} G-code"
            rows.append(job_row(name, args, [ngc, CELL, GRID], out_ngc, tmp, repeats))
            (module,) = make_input("bench.bench_rewrite.rapid_module", folder, n)
            out_mod = tmp / f"rewritten{n}.mod"
            args = ["rewrite", str(module), "--cell", str(RAPID_CELL), "-o", str(out_mod)]
            args += ["--max-mb", "512"]
            name = f"accugrid rewrite, {label} RAPID module"
            rows.append(
                job_row(name, args, [module, RAPID_CELL, RAPID_GRID], out_mod, tmp, repeats)
            )
            for path in [*pair, ngc, module]:
                path.unlink()
    print(
        table(
            [
                (name, *BEFORE.get(name, ("-", "-")), f"{s:.2f}", f"{peak:.0f}", floor_name)
                + (f"{floor:.2f}", f"{s / floor:.1f}x", target_of(name))
                for name, s, peak, floor_name, floor in rows
            ],
            ("command", "issue s", "issue MiB", "median s", "peak RSS MiB", "floor", "floor s")
            + ("ratio", "target"),
        )
    )


def target_of(name: str) -> str:
    """The issue's target for a row: by its name, else by its size."""
    return TARGET.get(name) or next(t for key, t in TARGET.items() if key in name)


if __name__ == "__main__":
    flags = sys.argv[1:]
    main("--million" in flags, next((f[7:] for f in flags if f.startswith("--only=")), ""))
