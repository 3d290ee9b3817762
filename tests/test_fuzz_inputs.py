"""Fuzz suite (issue 12): every reader and the whole commands on mutated real files.

Sources: the project's examples (points, measurements, tracker CSVs, cell files), the built-in
robot YAMLs, a fitted frame YAML, and the real-world programs of ../shared/realworld. Mutations:
byte flips, line deletions and duplications, token swaps, huge numbers, NaN, non-ASCII digits,
invalid UTF-8, hostile characters, a BOM, CRLF or CR line ends, truncation.

Every outcome must be a success or the project's InputError located in the mutated file, with a
one-line printable bounded message; a command must exit 0 or 2, leave no output after an error,
and never change an input. The example count is bounded (40 per test) so the suite runs in
seconds; a longer campaign: ``ACCUGRID_FUZZ_EXAMPLES=2000 pytest tests/test_fuzz_inputs.py``.
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

import pytest
from conftest import EXAMPLES, ROOT
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rewrite_helpers import write_cell

from accugrid.app.cli import main
from accugrid.app.jobs.robot_frame import load_frame
from accugrid.codegen.cell import load_cell
from accugrid.codegen.points import read_points
from accugrid.codegen.program_text import read_program
from accugrid.compensation.measurements import build_grid, read_measurements
from accugrid.infra.csvtable import read_table
from accugrid.infra.errors import MESSAGE_MAX, InputError
from accugrid.kinematics.robot import load_robot

FUZZ = settings(
    max_examples=int(os.environ.get("ACCUGRID_FUZZ_EXAMPLES", "40")),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)

NUMBER = re.compile(rb"-?[0-9]+(?:\.[0-9]+)?")
TOKEN_SPLIT = re.compile(rb"([,\s:{}\[\]]+)")
WILD_NUMBERS = [
    b"1e309",
    b"9" * 400,
    b"-1.7e308",
    b"1e-320",
    b"NaN",
    b"nan",
    b"-inf",
    b"1_000",
    "\u0661\u0662".encode(),
    "\uff11\uff12".encode(),
    b"0",
    b"",
]
HOSTILE = [
    b"\xff",
    b"\xc3",
    b"\x00",
    b"\r",
    b"\x0b",
    b"\x1b[2J",
    "\u202e".encode(),
    "\u2028".encode(),
    b'"',
    b"&a ",
    b"*a",
    b"!!python/object:os.system ",
    b"!!int ",
    b"\t",
    b"#",
    b"{",
    b"[",
]


def _flip(draw, data: bytes) -> bytes:
    if not data:
        return data
    i = draw(st.integers(0, len(data) - 1))
    return data[:i] + bytes([data[i] ^ draw(st.integers(1, 255))]) + data[i + 1 :]


def _lines(draw, data: bytes, duplicate: bool) -> bytes:
    lines = data.splitlines(keepends=True)
    if not lines:
        return data
    i = draw(st.integers(0, len(lines) - 1))
    return b"".join(lines[: i + 1] + lines[i:] if duplicate else lines[:i] + lines[i + 1 :])


def _swap_tokens(draw, data: bytes) -> bytes:
    parts = TOKEN_SPLIT.split(data)
    words = [k for k in range(0, len(parts), 2) if parts[k]]
    if len(words) < 2:
        return data
    a, b = draw(st.sampled_from(words)), draw(st.sampled_from(words))
    parts[a], parts[b] = parts[b], parts[a]
    return b"".join(parts)


def _wild_number(draw, data: bytes) -> bytes:
    spans = [m.span() for m in NUMBER.finditer(data)]
    if not spans:
        return data
    lo, hi = draw(st.sampled_from(spans))
    return data[:lo] + draw(st.sampled_from(WILD_NUMBERS)) + data[hi:]


def _insert(draw, data: bytes) -> bytes:
    i = draw(st.integers(0, len(data)))
    return data[:i] + draw(st.sampled_from(HOSTILE)) + data[i:]


MUTATIONS = {
    "flip": _flip,
    "delete_line": lambda draw, d: _lines(draw, d, False),
    "duplicate_line": lambda draw, d: _lines(draw, d, True),
    "swap_tokens": _swap_tokens,
    "wild_number": _wild_number,
    "insert": _insert,
    "bom": lambda draw, d: b"\xef\xbb\xbf" + d,
    "crlf": lambda draw, d: d.replace(b"\n", b"\r\n"),
    "cr": lambda draw, d: d.replace(b"\n", b"\r"),
    "truncate": lambda draw, d: d[: draw(st.integers(0, len(d)))],
}


@st.composite
def mutated(draw, sources: list[Path]) -> tuple[Path, bytes]:
    """(source file, its bytes after 1..4 mutations)."""
    source = draw(st.sampled_from(sources))
    data = source.read_bytes()
    for _ in range(draw(st.integers(1, 4))):
        data = MUTATIONS[draw(st.sampled_from(sorted(MUTATIONS)))](draw, data)
    return source, data


def check_error(err: InputError, path: Path) -> None:
    """The project's located error: names the mutated file, one printable bounded line."""
    assert err.path == str(path), str(err)
    text = str(err)
    assert text.isprintable() and len(text) <= 2 * MESSAGE_MAX + 20, text


def read_mutated(tmp_path: Path, case: tuple[Path, bytes], read) -> None:
    source, data = case
    path = tmp_path / source.name
    path.write_bytes(data)
    try:
        read(path)
    except InputError as err:
        check_error(err, path)
    assert path.read_bytes() == data


POINT_FILES = [EXAMPLES / "wing_panel_points.csv", EXAMPLES / "wing_panel_robot.csv"]
TRACKER_FILES = sorted((EXAMPLES / "tracker").glob("*.csv"))
CELL_FILES = [EXAMPLES / "cell.yaml", EXAMPLES / "cell_heatsink.yaml"]
ROBOT_FILES = sorted((ROOT / "kinematics" / "robots").glob("*.yaml"))


@FUZZ
@given(mutated(POINT_FILES))
def test_points_reader(tmp_path, case):
    read_mutated(tmp_path, case, read_points)


@FUZZ
@given(mutated([EXAMPLES / "grid_200mm.csv", EXAMPLES / "tracker" / "meas_tracker.csv"]))
def test_measurement_reader_and_grid(tmp_path, case):
    read_mutated(tmp_path, case, lambda p: build_grid(read_measurements(p)))


@FUZZ
@given(mutated(TRACKER_FILES))
def test_tracker_tables(tmp_path, case):
    def read(path):
        table = read_table(path)
        table.require(["x", "y", "z"])
        table.floats(["x", "y", "z"])

    read_mutated(tmp_path, case, read)


@FUZZ
@given(mutated(CELL_FILES))
def test_cell_reader(tmp_path, case):
    read_mutated(tmp_path, case, load_cell)


@FUZZ
@given(mutated(ROBOT_FILES))
def test_robot_reader(tmp_path, case):
    read_mutated(tmp_path, case, load_robot)


@pytest.fixture(scope="module")
def frame_file(tmp_path_factory) -> Path:
    """A frame YAML written by fit-frame from the example tracker files."""
    out = tmp_path_factory.mktemp("frame") / "robot_frame.yaml"
    tracker = EXAMPLES / "tracker"
    argv = ["fit-frame", "--base-plane", tracker / "base_plane.csv", "--a1-circle"]
    argv += [tracker / "a1_circle.csv", "--flange-holes", tracker / "flange_holes.csv"]
    assert main([str(a) for a in argv] + ["-o", str(out)]) == 0
    return out


@FUZZ
@given(data=st.data())
def test_frame_reader(tmp_path, frame_file, data):
    read_mutated(tmp_path, data.draw(mutated([frame_file])), load_frame)


@FUZZ
@given(data=st.data())
def test_program_reader(tmp_path, realworld, data):
    """The guarded program read (the KRL/G-code parsers have their own tests)."""
    programs = sorted(p for p in realworld.rglob("*") if p.suffix.lower() != ".md" and p.is_file())
    read_mutated(tmp_path, data.draw(mutated(programs)), lambda p: read_program(p, 2**20))


# ---------------------------------------------------------------- whole commands


def run_command(tmp_path: Path, argv: list, inputs: list[Path], outputs: list[Path], capsys):
    """Run the CLI in-process: exit 0 or 2, no output after an error, inputs unchanged."""
    before = {p: p.read_bytes() for p in inputs}
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err
    assert code in (0, 2), err
    if code == 2:
        (line,) = err.splitlines()
        assert line.isprintable() and "error: " in line
        assert not any(p.exists() for p in outputs), err
    assert {p: p.read_bytes() for p in inputs} == before


@FUZZ
@given(
    which=st.sampled_from(["points", "cell", "grid"]),
    dialect=st.sampled_from(["krl", "gcode"]),
    data=st.data(),
)
def test_krl_and_gcode_commands(tmp_path, capsys, which, dialect, data):
    files = {
        "points": EXAMPLES / "wing_panel_points.csv",
        "cell": EXAMPLES / "cell.yaml",
        "grid": EXAMPLES / "grid_200mm.csv",
    }
    work = tmp_path / f"w{len(list(tmp_path.iterdir()))}"
    work.mkdir()
    paths = {k: work / v.name for k, v in files.items()}
    for key, source in files.items():
        shutil.copy(source, paths[key])
    _, mutated_bytes = data.draw(mutated([files[which]]))
    paths[which].write_bytes(mutated_bytes)
    out = work / ("krl" if dialect == "krl" else "job.ngc")
    argv = [dialect, paths["points"], "--cell", paths["cell"], "-o", out]
    run_command(work, argv, list(paths.values()), [out], capsys)


@FUZZ
@given(which=st.sampled_from(["points", "grid"]), data=st.data())
def test_correct_command(tmp_path, capsys, which, data):
    files = {"points": EXAMPLES / "wing_panel_robot.csv", "grid": EXAMPLES / "grid_200mm.csv"}
    work = tmp_path / f"w{len(list(tmp_path.iterdir()))}"
    work.mkdir()
    paths = {k: work / v.name for k, v in files.items()}
    for key, source in files.items():
        shutil.copy(source, paths[key])
    paths[which].write_bytes(data.draw(mutated([files[which]]))[1])
    out = work / "corrected.csv"
    argv = ["correct", paths["points"], "--grid", paths["grid"], "-o", out]
    run_command(work, argv, list(paths.values()), [out], capsys)


@FUZZ
@given(data=st.data())
def test_rewrite_command_on_a_mutated_cell(tmp_path, capsys, realworld, data):
    """The cell and grid of a rewrite mutated; the real-world program itself stays intact (its
    parsers are fuzzed where they are owned)."""
    work = tmp_path / f"w{len(list(tmp_path.iterdir()))}"
    work.mkdir()
    cell = write_cell(work, field="constant", step=500.0)
    which = data.draw(st.sampled_from([cell, work / "grid.csv"]))
    which.write_bytes(data.draw(mutated([which]))[1])
    program = realworld / "gcode" / "norn93_1_heatsink_drill.gcode"
    out, report = work / "out.gcode", work / "report.csv"
    argv = ["rewrite", program, "--cell", cell, "-o", out, "--report", report]
    run_command(work, argv, [cell, work / "grid.csv", program], [out, report], capsys)
