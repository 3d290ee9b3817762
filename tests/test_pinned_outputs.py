"""KRL, G-code and RAPID outputs pinned: the SHA-256 of every file the command line writes for
the demo's jobs, the speed bench's inputs (made by the bench's own generators, at 2,000
positions) and every KRL, G-code and RAPID program in ../shared/realworld, with each command's
exit code, recorded in tests/data/pinned_outputs.json (group -> input -> output name -> digest).
The outputs of the demo's model path are numerically derived and pinned by their structure and
numbers with a tolerance instead (tests/pins.py).

Everything runs through the command line (``accugrid`` resolved from its console-script entry
point and called in this process with argv), so moving modules between folders does not touch
this test. A change to the pins must be explained in the commit message that makes it. To
regenerate them on purpose (the outputs changed and that is intended):

    ACCUGRID_REPIN=1 .venv/bin/python -m pytest -q tests/test_pinned_outputs.py

which rewrites the JSON and then fails every test it ran, so regenerating can never pass; run
the tests again without the variable and commit the JSON with the reason.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from importlib.metadata import entry_points
from pathlib import Path

import pytest
from conftest import EXAMPLES, ROOT
from pins import digests, first_difference, numbers
from rewrite_helpers import (
    REALWORLD_BASE_DATA,
    REALWORLD_RAPID,
    REALWORLD_REWRITES,
    write_cell,
    write_rapid_cell,
)

PINS = Path(__file__).parent / "data" / "pinned_outputs.json"
REPIN = "ACCUGRID_REPIN"
BENCH_POSITIONS = 2_000  # the bench's generators at this size (the bench itself uses 1e5)


def accugrid(*argv) -> int:
    """Exit code of ``accugrid argv`` run in this process through the console script's entry
    point (wherever the CLI module lives)."""
    (script,) = entry_points(group="console_scripts", name="accugrid")
    return script.load()([str(a) for a in argv])


def job(folder: Path, *argv) -> dict:
    """``accugrid argv`` (its outputs inside ``folder``, a new folder): {"exit": code, then
    every file written under ``folder``: digest}."""
    folder.mkdir(parents=True)
    code = accugrid(*argv)
    return {"exit": code, **digests(folder)}


def check(group: str, actual: dict[str, dict]) -> None:
    """``actual`` (input -> output name -> digest or exit code) equals the JSON's ``group``; with
    ACCUGRID_REPIN=1 the JSON's ``group`` is replaced by ``actual`` and the test fails."""
    pins = json.loads(PINS.read_text()) if PINS.exists() else {}
    if os.environ.get(REPIN) == "1":
        pins[group] = actual
        PINS.parent.mkdir(exist_ok=True)
        PINS.write_text(json.dumps(dict(sorted(pins.items())), indent=1) + "\n")
        pytest.fail(f"{REPIN}=1: pins of {group} rewritten in {PINS}; run again without it")
    pinned = pins.get(group, {})
    for name in list(actual) + [n for n in pinned if n not in actual]:
        problem = first_difference(actual.get(name, {}), pinned.get(name, {}))
        if problem:
            pytest.fail(f"{group}, {name}: {problem} (pins: {PINS}, see {Path(__file__).name})")


def test_demo_outputs_are_pinned(tmp_path):
    """The demo's drilling programs (examples/demo.sh; its grids are examples/grid_200mm.csv and
    grid_irb6700_200mm.csv, which the demo checks it simulates byte for byte), its pre-flight
    rewrites and its KRL measurement program of the experiment plan."""
    points, cell = EXAMPLES / "wing_panel_points.csv", EXAMPLES / "cell.yaml"
    grid, cam = EXAMPLES / "grid_200mm.csv", EXAMPLES / "cam_drill"
    abb = EXAMPLES / "cell_irb6700.yaml"
    program = [points, "--cell", cell, "--grid", grid]
    krl, ngc, rewrite = tmp_path / "krl", tmp_path / "gcode", tmp_path / "rewrite"
    plan, rapid = tmp_path / "plan", tmp_path / "rapid"
    actual = {
        "krl wing_panel_points.csv": job(krl, "krl", *program, "-o", krl),
        "gcode wing_panel_points.csv": job(ngc, "gcode", *program, "-o", ngc / "wing_panel.ngc"),
        "rewrite cam_drill.src cam_drill.dat": job(
            rewrite / "krl",
            *("rewrite", f"{cam}.src", f"{cam}.dat", "--cell", cell, "-o", rewrite / "krl"),
            *("--report", rewrite / "krl/cam_drill_krl_report.csv", "--allow-partial"),
        ),
        "rewrite cam_drill.ngc": job(
            rewrite / "ngc",
            *("rewrite", f"{cam}.ngc", "--cell", cell, "-o", rewrite / "ngc/cam_drill.ngc"),
            *("--report", rewrite / "ngc/cam_drill_ngc_report.csv", "--allow-partial"),
        ),
        "rapid wing_panel_points.csv": job(
            rapid, "rapid", points, "--cell", abb, "-o", rapid / "WING.mod"
        ),
        "rewrite cam_drill.mod": job(
            rewrite / "mod",
            *(
                "rewrite",
                f"{cam}.mod",
                "--cell",
                abb,
                "--header",
                "-o",
                rewrite / "mod/cam_drill.mod",
            ),
            *("--report", rewrite / "mod/cam_drill_rapid_report.csv", "--allow-partial"),
        ),
        "plan experiment": job(
            plan,
            *("plan", "experiment", "--centre", "D", 1700, 0, 1500, "--steps", "20:380:120"),
            *("--repeats", 3, "-o", plan),
        ),
    }
    check("demo", actual)


def test_demo_model_program_is_pinned(tmp_path):
    """The demo's model-based job: the identification plan (a KRL measurement program), the
    simulated session, the calibrated model and residual grid it identifies, and the drilling
    program corrected by both (each step's files pinned, so a change is found where it starts).
    Numerically derived (least squares, SVD, the structure's evidence): pinned by structure and
    numbers within pins.NUMBER_TOLERANCE, not bytes, so any CPU and BLAS kernel pass."""
    model = tmp_path / "model"
    tool = ["--tool", 0, 0, 250, 0, 0, 0]
    robot = ["--robot", "kr210-realistic", *tool]
    noise = ["--noise-tracker", 0.02, "--noise-repeat", 0.03]
    calibrated, residual = model / "calibrated.yaml", model / "residual_27.csv"
    steps = [
        ("plan", "identify", *robot, "--count", 60, "--tilt", 25, "--name", "IDENT", "-o", model),
        ("simulate", *robot, "--poses", model / "ident.csv", "--repeats", 3, *noise, "--seed", 2)
        + ("-o", model / "ident_measured.csv"),
        ("identify", model / "ident_measured.csv", *robot, "-o", calibrated),
        ("simulate", *robot, "--region", 1200, 2200, -500, 500, 1100, 2100, "--step", 500)
        + ("--abc", 0, 90, 0, "--repeats", 3, *noise, "--seed", 3, "-o", residual),
        ("krl", EXAMPLES / "wing_panel_points.csv", "--cell", EXAMPLES / "cell.yaml")
        + ("--model", calibrated, "--grid", residual, "-o", model / "krl"),
    ]
    model.mkdir()
    codes = [accugrid(*argv) for argv in steps]
    actual = {"plan identify .. krl --model": {"exit": codes, **numbers(model)}}
    check("demo model", actual)


@pytest.mark.skipif(bool(os.environ.get("ACCUGRID_REPIN")), reason="re-pinning")
def test_demo_model_is_the_same_under_another_blas_kernel_and_one_thread():
    """The model path's pin holds where OpenBLAS computes differently (another CPU's kernel, one
    thread): a choice that hangs on rounding (a candidate only rounding keeps alive) fails here
    on any machine, not only on a CI machine with another CPU."""
    env = {**os.environ, "OPENBLAS_CORETYPE": "Sandybridge", "OPENBLAS_NUM_THREADS": "1"}
    test = f"{Path(__file__)}::test_demo_model_program_is_pinned"
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", test],
        env=env,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stdout[-2000:]


def test_bench_outputs_are_pinned(tmp_path, monkeypatch):
    """The speed bench's inputs (bench/bench_commands.py: bench_programs.points_csv for krl,
    gcode and rapid, bench_rewrite.krl_pair, .gcode and .rapid_module for rewrite;
    bench/bench_rewrite.py also .krl_inline), made by the bench's own generators at 2,000
    positions, and the krl, gcode, rapid and rewrite outputs of them with the bench's arguments
    (and a report of each rewrite). The inputs are pinned too: a change there is not a change of
    the programs."""
    monkeypatch.syspath_prepend(str(ROOT))
    from bench.bench_programs import points_csv
    from bench.bench_rewrite import gcode, krl_inline, krl_pair, rapid_module

    n, cell = BENCH_POSITIONS, EXAMPLES / "cell.yaml"
    abb = EXAMPLES / "cell_irb6700.yaml"
    inputs = tmp_path / "inputs"
    (inputs / f"rewrite{n}").mkdir(parents=True)
    holes = inputs / f"holes{n}.csv"
    holes.write_text(points_csv(n))
    pair = krl_pair(inputs / f"rewrite{n}", n)
    (ngc,) = gcode(inputs / f"rewrite{n}", n)
    (inline,) = krl_inline(inputs / f"rewrite{n}", n)
    (module,) = rapid_module(inputs / f"rewrite{n}", n)
    krl, gc, ra = tmp_path / "krl", tmp_path / "gcode", tmp_path / "rapid"
    pair_out, ngc_out, inline_out = (tmp_path / k for k in ("pair", "ngc", "inline"))
    mod_out = tmp_path / "mod"
    big = ["--cell", cell, "--max-mb", 512]
    actual = {
        "inputs": digests(inputs),
        f"krl holes{n}.csv": job(krl, "krl", holes, "--cell", cell, "-o", krl / f"krl{n}"),
        f"gcode holes{n}.csv": job(gc, "gcode", holes, "--cell", cell, "-o", gc / f"holes{n}.ngc"),
        f"rapid holes{n}.csv": job(ra, "rapid", holes, "--cell", abb, "-o", ra / f"HOLES{n}.mod"),
        "rewrite big.src big.dat": job(
            pair_out,
            *("rewrite", *pair, *big, "-o", pair_out / f"rewritten{n}"),
            *("--report", pair_out / "report.csv"),
        ),
        "rewrite big.ngc": job(
            ngc_out,
            *("rewrite", ngc, *big, "-o", ngc_out / f"rewritten{n}.ngc"),
            *("--report", ngc_out / "report.csv"),
        ),
        f"rewrite {inline.name}": job(
            inline_out,
            *("rewrite", inline, *big, "-o", inline_out / inline.name),
            *("--report", inline_out / "report.csv"),
        ),
        f"rewrite {module.name}": job(
            mod_out,
            *("rewrite", module, "--cell", abb, "--max-mb", 512, "-o", mod_out / module.name),
            *("--report", mod_out / "report.csv"),
        ),
    }
    check("bench", actual)


def test_realworld_rewrites_are_pinned(realworld, tmp_path):
    """Every KRL and G-code program in ../shared/realworld rewritten with the options and cell of
    tests/test_rewrite_realworld.py (rewrite_helpers.REALWORLD_REWRITES): the exit code and the
    files written (program and report) as given, and where that is refused (exit 2) with
    --allow-partial as well."""
    programs = {p.relative_to(realworld).as_posix() for p in realworld.glob("[kg]*/*")}
    named = {name for names, _ in REALWORLD_REWRITES.values() for name in names}
    assert programs == named, f"realworld programs without a pinned rewrite: {programs - named}"
    (tmp_path / "cell").mkdir()
    cell = write_cell(tmp_path / "cell", base_data=REALWORLD_BASE_DATA)
    actual = {}
    for case, (names, options) in REALWORLD_REWRITES.items():
        inputs = [realworld / name for name in names]
        for run, extra in (("as given", []), ("--allow-partial", ["--allow-partial"])):
            folder = tmp_path / case / run.strip("-")
            out = folder / "out"
            target = out if len(inputs) == 2 else out / inputs[0].name  # a pair: -o is a folder
            argv = ["rewrite", *inputs, "--cell", cell, "-o", target, *options, *extra]
            result = job(folder, *argv, "--report", folder / "report.csv")
            actual[f"{case} {run}"] = result
            if result["exit"] != 2:
                break
    check("realworld", actual)


def test_realworld_rapid_rewrites_are_pinned(realworld, tmp_path):
    """Every RAPID program in ../shared/realworld/rapid rewritten in the cell of
    rewrite_helpers.REALWORLD_RAPID (tests/test_rapid.py checks what changes): the exit code
    and the files written (program and report) as given, where that is refused (exit 2) with
    --allow-partial, and with --allow-partial --ignore-external-axes."""
    programs = {p.name for p in (realworld / "rapid").iterdir()}
    missing = programs ^ set(REALWORLD_RAPID)
    assert not missing, f"realworld RAPID programs without a pinned rewrite: {missing}"
    runs = (
        ("as given", []),
        ("--allow-partial", ["--allow-partial"]),
        ("--ignore-external-axes", ["--allow-partial", "--ignore-external-axes"]),
    )
    actual = {}
    for name, (tool, wobj) in sorted(REALWORLD_RAPID.items()):
        (tmp_path / name).mkdir()
        cell = write_rapid_cell(tmp_path / name, tool, wobj)
        for run, extra in runs:
            if run == "--allow-partial" and actual[f"{name} as given"]["exit"] != 2:
                continue
            folder = tmp_path / name / run.strip("-")
            argv = ["rewrite", realworld / "rapid" / name, "--cell", cell, *extra]
            result = job(folder, *argv, "-o", folder / name, "--report", folder / "report.csv")
            actual[f"{name} {run}"] = result
    check("realworld rapid", actual)
