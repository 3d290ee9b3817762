"""`make bench`: run every bench/bench_*.py script in turn; each prints its own table.

Benchmarks measure, they never assert a time: the machines are shared and noisy. Each script
compares against a peer measured in the same run where one exists.
"""

from __future__ import annotations

import runpy
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main(names: list[str]) -> None:
    scripts = sorted(HERE.glob("bench_*.py"))
    names = [n for n in names if not n.startswith("--")]  # flags (--million) go to the scripts
    if names:
        scripts = [s for s in scripts if any(n in s.stem for n in names)]
    for script in scripts:
        print(f"\n== {script.stem} ==", flush=True)
        runpy.run_path(str(script), run_name="__main__")


if __name__ == "__main__":
    main(sys.argv[1:])
