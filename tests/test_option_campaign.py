"""A seeded campaign of hostile option values and faulty inputs over the real commands.

Every case runs the command in a forked child (the parent keeps the imports, so a case costs
milliseconds) with a time limit, and checks: exit 0 or 2, never 1, never a traceback, never a
hang; on exit 2 the output folder is exactly as it was (targets untouched, no temporary left).
``ACCUGRID_FUZZ_EXAMPLES=N`` runs N option cases instead of the CI's 300.
"""

from __future__ import annotations

import os
import random
import shutil
import signal
import sys
import time
from pathlib import Path

import pytest
from conftest import EXAMPLES

from accugrid.app.cli import main

EXAMPLES_N = int(os.environ.get("ACCUGRID_FUZZ_EXAMPLES", "300"))
TIME_LIMIT_S = 120  # a guard against a hang, not a timing assertion

HOSTILE = [
    "nan", "NaN", "inf", "-inf", "1e9999", "-0", "0", "-1", "5e-8", "1e-320", "1e308",
    "-1e308", "1000000000", "99999999999999999999", "1e6", "360", "abc", "", "0x10", " 7",
]  # fmt: skip

# (command line before the option, the option, its number of values); OUT is the output
BASE = {
    "simulate": ["simulate", "--region", "1200", "1400", "-100", "100", "1200", "1400",
                 "--step", "100", "-o", "OUT/s.csv", "--force"],
    "correct": ["correct", "IN/wing_panel_robot.csv", "--grid", "IN/grid_200mm.csv",
                "-o", "OUT/c.csv", "--force"],
    "plan identify": ["plan", "identify", "--count", "20", "--candidates", "100", "-o", "OUT",
                      "--force"],
    "plan cube": ["plan", "cube", "--centre", "1700", "0", "1500", "--step", "100", "-o", "OUT",
                  "--force"],
    "rewrite": ["rewrite", "IN/cam_drill.ngc", "--cell", "IN/cell.yaml", "-o", "OUT/r.ngc",
                "--report", "OUT/r.csv", "--force", "--allow-partial"],
}  # fmt: skip
OPTIONS = [
    ("simulate", "--abc", 3), ("simulate", "--tool", 6), ("simulate", "--step", 1),
    ("simulate", "--region", 6), ("simulate", "--noise-tracker", 1),
    ("simulate", "--noise-repeat", 1), ("simulate", "--seed", 1), ("simulate", "--repeats", 1),
    ("simulate", "--status", 1),
    ("correct", "--abc", 3), ("correct", "--tool", 6), ("correct", "--power", 1),
    ("correct", "--iterations", 1), ("correct", "--max-correction", 1),
    ("correct", "--orientation-tol", 1), ("correct", "--orientation-limit", 1),
    ("correct", "--repeat-tol", 1),
    ("plan identify", "--count", 1), ("plan identify", "--candidates", 1),
    ("plan identify", "--tilt", 1), ("plan identify", "--abc", 3), ("plan identify", "--tool", 6),
    ("plan identify", "--region", 6), ("plan identify", "--seed", 1),
    ("plan identify", "--repeats", 1), ("plan identify", "--speed", 1),
    ("plan identify", "--wait-sec", 1), ("plan identify", "--ptp-percent", 1),
    ("plan identify", "--tool-number", 1), ("plan identify", "--base-number", 1),
    ("plan cube", "--centre", 3), ("plan cube", "--step", 1), ("plan cube", "--repeats", 1),
    ("rewrite", "--decimals", 1), ("rewrite", "--tolerance", 1), ("rewrite", "--max-mb", 1),
    ("rewrite", "--base", 1), ("rewrite", "--orientation-tol", 1),
]  # fmt: skip


def run_case(argv: list[str]) -> tuple[int | str, str]:
    """``main(argv)`` in a forked child: (exit code or "timeout", stderr)."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: never returns to pytest
        code = 1
        try:
            os.close(read)
            os.dup2(write, 2)
            os.dup2(os.open(os.devnull, os.O_WRONLY), 1)
            sys.stderr = open(2, "w", closefd=False)  # noqa: SIM115 - pytest's capture is not fd 2
            sys.stdout = open(1, "w", closefd=False)  # noqa: SIM115
            code = main(argv)
        except SystemExit as stop:
            code = stop.code if isinstance(stop.code, int) else 1
        except BaseException:  # noqa: BLE001 - reported as a traceback on stderr
            import traceback

            traceback.print_exc()
        finally:
            sys.stderr.flush()
            os._exit(code)
    os.close(write)
    err = bytearray()
    start = time.monotonic()
    os.set_blocking(read, False)
    while True:
        err += _drain(read)  # a full pipe would block the child
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        if time.monotonic() - start > TIME_LIMIT_S:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            os.close(read)
            return "timeout", err.decode(errors="replace")
        time.sleep(0.005)
    err += _drain(read)
    os.close(read)
    return os.waitstatus_to_exitcode(status), err.decode(errors="replace")


def _drain(fd: int) -> bytes:
    """What the non-blocking ``fd`` holds now (EOF: what is left)."""
    out = bytearray()
    try:
        while chunk := os.read(fd, 65536):
            out += chunk
    except BlockingIOError:
        pass
    return bytes(out)


def snapshot(folder: Path) -> dict[str, bytes]:
    return {
        os.fsdecode(p.relative_to(folder)): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


def check(argv: list[str], out: Path) -> tuple[int | str, str]:
    """Run one case; exit 0 or 2, no traceback, and on exit 2 ``out`` unchanged."""
    before = snapshot(out)
    code, err = run_case(argv)
    shown = " ".join(argv)
    assert code in (0, 2), (shown, code, err[-2000:])
    assert "Traceback" not in err and "internal error" not in err, (shown, err[-2000:])
    if code == 2:
        assert snapshot(out) == before, shown
        assert err.strip(), shown  # said why
    return code, err


@pytest.fixture
def inputs(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("cell.yaml", "grid_200mm.csv", "wing_panel_robot.csv", "cam_drill.ngc"):
        shutil.copy(EXAMPLES / name, folder / name)
    return folder


@pytest.fixture
def warm(tmp_path, inputs):
    """Run every base command once here, so the forked cases find their modules imported."""
    for command, words in BASE.items():
        out = tmp_path / f"warm-{command.replace(' ', '-')}"
        out.mkdir()
        argv = [a.replace("OUT", str(out)).replace("IN", str(inputs)) for a in words]
        assert main(argv) == 0, command


def test_hostile_number_options_exit_0_or_2_and_leave_targets(tmp_path, inputs, warm):
    rng = random.Random(22)
    codes = []
    for case in range(EXAMPLES_N):
        command, option, count = rng.choice(OPTIONS)
        values = [rng.choice(HOSTILE)] + [rng.choice(["0", "10", "-5", "90", "1"])] * (count - 1)
        rng.shuffle(values)
        out = tmp_path / f"out{case}"
        out.mkdir()
        (out / "s.csv").write_text("old\n")  # an existing target the --force run may replace
        argv = [a.replace("OUT", str(out)).replace("IN", str(inputs)) for a in BASE[command]] + [
            option,
            *values,
        ]
        codes.append(check(argv, out)[0])
        shutil.rmtree(out)
    assert codes.count(2) > len(codes) / 3 and 0 in codes  # both refusals and runs were seen


@pytest.mark.parametrize(
    ("option", "value", "said"),
    [
        ("--tool", "nan", "argument --tool: 'nan' is not a finite number (mm or deg)"),
        ("--noise-tracker", "nan", "argument --noise-tracker: 'nan' is not a finite number (mm)"),
        ("--abc", "inf", "argument --abc: 'inf' is not a finite number (deg)"),
        ("--step", "-0", "argument --step: '-0' must be > 0 mm"),
        ("--repeats", "1e3", "argument --repeats: '1e3' is not a whole number"),
    ],
)
def test_the_refusal_names_the_option_value_and_unit(tmp_path, option, value, said):
    argv = [a.replace("OUT", str(tmp_path)) for a in BASE["simulate"]]
    values = [value] * {"--tool": 6, "--abc": 3}.get(option, 1)
    code, err = check([*argv, option, *values], tmp_path)
    assert code == 2 and said in err


def test_bounded_sizes_are_named(tmp_path):
    argv = [a.replace("OUT", str(tmp_path)) for a in BASE["plan identify"]]
    code, err = check([*argv, "--candidates", "1000000000"], tmp_path)
    assert code == 2 and "'1000000000' must be <= 100000 candidate poses" in err
    code, err = check([*argv, "--count", "100000"], tmp_path)
    assert code == 2 and "'100000' must be <= 1000 poses" in err


def test_small_positive_numbers_and_negative_zero_are_accepted(tmp_path, inputs):
    argv = [a.replace("OUT", str(tmp_path)) for a in BASE["simulate"]]
    assert check([*argv, "--noise-tracker", "5e-8", "--noise-repeat", "-0"], tmp_path)[0] == 0
    argv = [a.replace("OUT", str(tmp_path)).replace("IN", str(inputs)) for a in BASE["rewrite"]]
    assert check([*argv, "--tolerance", "5e-8"], tmp_path)[0] == 0


@pytest.fixture
def urdf_robot(tmp_path):
    """A URDF robot file (kr210 exported as URDF)."""
    from accugrid.kinematics.robot import load_robot
    from accugrid.kinematics.urdf_export import urdf_text

    (tmp_path / "kr210.urdf").write_text(urdf_text(load_robot("kr210")))
    path = tmp_path / "urdf_robot.yaml"
    path.write_text("name: kr210-urdf\nurdf: kr210.urdf\ntip: tcp\n")
    return path


def test_a_urdf_robot_as_model_is_a_located_refusal(tmp_path, inputs, urdf_robot):
    out = tmp_path / "out"
    out.mkdir()
    model = ["--model", str(urdf_robot)]
    cell = ["--cell", str(inputs / "cell.yaml")]
    points = str(EXAMPLES / "wing_panel_points.csv")
    for argv in (
        ["krl", points, *cell, *model, "-o", str(out / "krl")],
        ["rewrite", str(inputs / "cam_drill.ngc"), *cell, *model, "-o", str(out / "r.ngc")],
    ):
        code, err = check(argv, out)
        assert code == 2 and f"{urdf_robot}: model kr210-urdf is a URDF robot" in err


def test_input_names_with_a_non_utf8_byte_work(tmp_path, inputs):
    odd = os.fsdecode(b"\xff")
    out = tmp_path / "out"
    out.mkdir()
    robot = ["--robot", "kr210", "--tool", "0", "0", "250", "0", "0", "0"]
    plan = tmp_path / "plan"
    assert (
        check(["plan", "identify", *robot, "--count", "30", "-o", str(plan)], plan.parent)[0] == 0
    )
    meas = tmp_path / f"m{odd}.csv"
    poses = str(next(plan.glob("*.csv")))
    assert check(["simulate", *robot, "--poses", poses, "-o", str(meas)], tmp_path)[0] == 0
    cal = out / f"c{odd}.yaml"
    assert check(["identify", str(meas), *robot, "-o", str(cal)], out)[0] == 0
    assert "m\\udcff.csv" in cal.read_text(encoding="utf-8")
    ngc = inputs / f"p{odd}.ngc"
    shutil.copy(inputs / "cam_drill.ngc", ngc)
    argv = ["rewrite", str(ngc), "--cell", str(inputs / "cell.yaml"), "-o", str(out / "r.ngc")]
    assert check([*argv, "--allow-partial", "--report", str(out / f"r{odd}.csv")], out)[0] == 0


def test_identify_refuses_more_rows_than_its_bound(tmp_path, monkeypatch):
    from accugrid.app.jobs import identify as calibration

    robot = ["--robot", "kr210", "--tool", "0", "0", "250", "0", "0", "0"]
    plan, meas = tmp_path / "plan", tmp_path / "meas.csv"
    assert check(["plan", "identify", *robot, "--count", "30", "-o", str(plan)], tmp_path)[0] == 0
    poses = str(next(plan.glob("*.csv")))
    assert check(["simulate", *robot, "--poses", poses, "-o", str(meas)], tmp_path)[0] == 0
    monkeypatch.setattr(calibration, "MAX_ROWS", 29)  # the bound, made small for the test
    code, err = check(["identify", str(meas), *robot, "-o", str(tmp_path / "c.yaml")], tmp_path)
    assert code == 2 and f"{meas}: 30 measurement rows; identify takes at most 29" in err


def test_misspelt_cell_keys_are_refused_before_anything_is_written(tmp_path, inputs):
    """Seeded: one letter of a key of the example cell changed, dropped or doubled."""
    rng = random.Random(7)
    lines = (inputs / "cell.yaml").read_text().splitlines(keepends=True)
    keyed = [i for i, line in enumerate(lines) if ":" in line and not line.lstrip().startswith("#")]
    out = tmp_path / "out"
    out.mkdir()
    seen = []
    for case in range(max(20, EXAMPLES_N // 5)):
        at = rng.choice(keyed)
        indent = len(lines[at]) - len(lines[at].lstrip())
        key = lines[at][indent:].split(":", 1)[0]
        k = rng.randrange(len(key))
        edits = [key[:k] + key[k + 1 :], key[:k] + key[k] + key[k:], key[:k] + "q" + key[k + 1 :]]
        changed = rng.choice([e for e in edits if e] or ["q"])
        text = lines[:at] + [lines[at].replace(key, changed, 1)] + lines[at + 1 :]
        cell = inputs / f"cell{case}.yaml"
        cell.write_text("".join(text))
        argv = ["krl", str(EXAMPLES / "wing_panel_points.csv"), "--cell", str(cell)]
        code, err = check([*argv, "-o", str(out / "krl")], out)
        if code == 2 and "unknown key" in err:
            assert f"cell{case}.yaml:{at + 1}:" in err  # located at the key's line
            seen.append(case)
        shutil.rmtree(out / "krl", ignore_errors=True)
    assert seen  # the campaign hit misspelt keys


def test_a_large_size_limit_allocates_nothing_for_it(tmp_path, inputs):
    """--max-mb 1e6 (a TiB): the reader asks for the file's size, not the limit (MemoryError)."""
    argv = [a.replace("OUT", str(tmp_path)).replace("IN", str(inputs)) for a in BASE["rewrite"]]
    assert check([*argv, "--max-mb", "1e6"], tmp_path)[0] == 0


def test_identify_refuses_a_non_finite_tool_naming_the_option_and_unit(tmp_path, capsys):
    # identify --tool 0 0 nan 0 0 0 ended in an internal error
    meas = tmp_path / "m.csv"
    meas.write_text("x,y,z,x_meas,y_meas,z_meas\n1700,0,1500,1700,0,1500\n")
    argv = ["identify", str(meas), "--robot", "kr210", "--tool", "0", "0", "nan", "0", "0", "0"]
    with pytest.raises(SystemExit) as stop:
        main([*argv, "-o", str(tmp_path / "cal.yaml")])
    assert stop.value.code == 2
    assert "argument --tool: 'nan' is not a finite number (mm or deg)" in capsys.readouterr().err
    assert not (tmp_path / "cal.yaml").exists()


def test_a_robot_without_the_closed_form_inverse_gets_its_program_by_the_numerical_one(
    tmp_path, inputs, capsys
):
    # A DH structure without a closed-form inverse (a4 = 10 mm: no spherical wrist) is served by
    # the numerical IK: the same positions, in the configuration (S, T) the closed form of the
    # unbent arm gives them.
    from importlib import resources

    nominal = resources.files("accugrid.kinematics").joinpath("robots", "kr210.yaml").read_text()
    bent = nominal.replace("{a_mm: 0.0, alpha_deg: -90.0", "{a_mm: 10.0, alpha_deg: -90.0", 1)
    assert bent != nominal
    (inputs / "bent.yaml").write_text(bent.replace("name: kr210", "name: bent", 1))
    (inputs / "straight.yaml").write_text(nominal.replace("name: kr210", "name: straight", 1))
    points = inputs / "wing_panel_robot.csv"
    positions = {}
    for name in ("bent", "straight"):
        cell = inputs / f"cell_{name}.yaml"
        text = (inputs / "cell.yaml").read_text()
        cell.write_text(text.replace("robot: kr210-paper", f"robot: {name}.yaml", 1))
        out = tmp_path / name
        argv = ["krl", str(points), "--cell", str(cell), "--no-correction", "-o", str(out)]
        assert main(argv) == 0
        dat = (out / "WING_PANEL.dat").read_text()
        positions[name] = [line for line in dat.splitlines() if line.startswith("DECL E6POS")]
    assert len(positions["bent"]) >= 72
    assert positions["bent"] == positions["straight"]
