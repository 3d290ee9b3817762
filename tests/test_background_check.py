"""The program's IK check on a background thread (``build_program(background=True)``, issue 14):
the same program as a check done at once, its errors where the job can still stop, and the
KRL ``.src`` files made while it runs."""

from __future__ import annotations

import threading
from unittest import mock

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from program_helpers import (
    CELL,
    POINTS,
    cell,
    cell_with,
    grid,
    near_singular_wrist,
    panel_points,
    robot,
)

from accugrid.app.cli import main
from accugrid.codegen import program
from accugrid.codegen.points import parse_points
from accugrid.codegen.program import build_program
from accugrid.infra import atomic
from accugrid.infra.errors import InputError

ROWS = [(x, y) for x in (-200.0, 0.0, 250.0) for y in (100.0, 300.0, 500.0)]


def status_zero_cell(tmp_path):
    """The example cell requiring Status 0, which the panel's holes cannot keep."""
    text = CELL.read_text().replace("  # status: 2 ", "  status: 0   ")
    assert "  status: 0" in text
    tmp_path.mkdir(exist_ok=True)
    (tmp_path / "grid_200mm.csv").write_bytes((CELL.parent / "grid_200mm.csv").read_bytes())
    path = tmp_path / "cell.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    "case",
    ["grid", "no correction", "allow change", "singular wrist"],
)
def test_a_program_checked_in_the_background_is_the_one_checked_at_once(case):
    c, g = cell(), grid()
    pts = panel_points(ROWS)
    if case == "no correction":
        g = None
    elif case == "allow change":  # Status 0: not the grid's (6), so uncorrected
        c, g = cell_with(configuration={"status": 0, "allow_change": True}), None
    elif case == "singular wrist":
        pts, g = near_singular_wrist()[0], None
    at_once = build_program(pts, c, robot(), g)
    later = build_program(pts, c, robot(), g, background=True)
    assert later.configuration is None or later.checking is None
    assert later.wait() is later and later.checking is None
    assert later.warnings == at_once.warnings
    if case in ("allow change", "singular wrist"):
        assert later.warnings  # the IK's own warnings come after the correction's
    for got, want in zip(_fields(later.configuration), _fields(at_once.configuration), strict=True):
        np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(later.positions, at_once.positions)


@settings(max_examples=30, deadline=None)
@given(
    st.sampled_from(["fixed Status", "allow change"]),
    st.integers(1, 40),
    st.lists(st.tuples(st.integers(0, len(ROWS)), st.integers(0, len(ROWS))), max_size=6),
)
def test_the_configuration_from_the_ik_blocks_is_what_the_finished_check_keeps(case, block, ranges):
    """Holes lo..hi-1 asked for while the check runs (IK blocks of ``block`` poses, some holes
    changing Status with allow_change): the configuration the finished check keeps."""
    c = (
        cell()
        if case == "fixed Status"
        else cell_with(configuration={"status": 0, "allow_change": True})
    )
    pts = panel_points(ROWS)
    g = grid() if case == "fixed Status" else None  # the grid holds in Status 6 only
    final = _fields(build_program(pts, c, robot(), g).configuration)
    with mock.patch.object(program, "IK_BLOCK", block):
        prog = build_program(pts, c, robot(), g, background=True)
        for lo, hi in [(min(a, b), max(a, b)) for a, b in ranges] + [(0, len(ROWS))]:
            for got, want in zip(_fields(prog.configuration_of(lo, hi)), final, strict=True):
                np.testing.assert_array_equal(got, want[lo:hi])
        prog.wait()


def _fields(configuration) -> tuple[np.ndarray, ...]:
    """Every field of a configuration: shoulder, elbow, wrist, quarter."""
    c = configuration
    return c.shoulder, c.elbow, c.wrist, c.quarter


def test_an_unreachable_hole_checked_in_the_background_is_raised_by_wait():
    text = "id,x,y,z,a,b,c\nNEAR,0,150,0,-90,0,180\nFAR-AWAY,0,150,-3000,-90,0,180\n"
    prog = build_program(parse_points(text, "p.csv"), cell(), robot(), None, background=True)
    for _ in range(2):  # a second wait raises again, it never hands out an unchecked program
        with pytest.raises(InputError, match="hole 'FAR-AWAY'.*not reachable") as info:
            prog.wait()
        assert (info.value.path, info.value.line) == ("p.csv", 3)
    assert prog.configuration is None


SPIN = (("A", -90), ("B", 30), ("C", 150), ("D", -90))  # hole id, KUKA A deg (B 0, C 180)


@pytest.mark.parametrize("failure", ["unreachable in the Status", "branch jump"])
@pytest.mark.parametrize("command", ["krl", "gcode"])
def test_a_job_whose_ik_check_fails_replaces_nothing(tmp_path, capsys, command, failure):
    """The check fails after the files were rendered (a hole that cannot keep the Status: the
    .dat asks for it; a branch jump: only the job's final wait sees it): exit 2, one line, the
    previous output untouched and no temporaries left."""
    out = tmp_path / ("krl" if command == "krl" else "p.ngc")
    assert main([command, str(POINTS), "--cell", str(CELL), "-o", str(out)]) == 0
    before = {p: p.read_bytes() for p in sorted(tmp_path.rglob("*")) if p.is_file()}
    capsys.readouterr()
    points, cell_file, message = POINTS, CELL, "hole 'D': A6 turns 241 deg"
    if failure == "branch jump":  # A spins the drill 120 deg per hole: A6 runs out of its range
        points = tmp_path / "input" / "jump.csv"
        points.parent.mkdir()
        spin = "".join(f"{h},{25 * k},300,0,{a},0,180\n" for k, (h, a) in enumerate(SPIN))
        points.write_text("id,x,y,z,a,b,c\n" + spin)
    else:
        cell_file, message = status_zero_cell(tmp_path / "input"), "hole 'WP-R1-001'"
    argv = [command, str(points), "--cell", str(cell_file), "-o", str(out), "--force"]
    code = main([*argv, "--no-correction"])  # the IK check's own failures
    stdout, err = capsys.readouterr()
    assert code == 2 and stdout == "" and err.count("\n") == 1
    assert message in err
    after = {p: p.read_bytes() for p in sorted(tmp_path.rglob("*")) if p.is_file()}
    assert {p: b for p, b in after.items() if "input" not in p.parts} == before


def test_krl_src_files_are_written_while_the_ik_check_runs(tmp_path, monkeypatch, capsys):
    """The IK check is held until a module's .src is written: the job only finishes if the .src
    files need no Status or Turn; all of them are written before the first .dat."""
    written: list[str] = []
    src_written = threading.Event()
    real_write, real_check = atomic._write_temp, program._configuration
    saw_src = []

    def write(tmp, data):
        real_write(tmp, data)
        written.append(tmp.rsplit("/", 1)[-1])
        if written[-1].endswith(".src"):
            src_written.set()

    def held_check(*args):
        saw_src.append(src_written.wait(timeout=60))
        return real_check(*args)

    monkeypatch.setattr(atomic, "_write_temp", write)
    monkeypatch.setattr(program, "_configuration", held_check)
    out = tmp_path / "krl"
    cell_file = tmp_path / "cell.yaml"
    cell_file.write_text(CELL.read_text().replace("lines_per_file: 5000 ", "lines_per_file: 300  "))
    (tmp_path / "grid_200mm.csv").write_bytes((CELL.parent / "grid_200mm.csv").read_bytes())
    assert main(["krl", str(POINTS), "--cell", str(cell_file), "-o", str(out)]) == 0
    assert saw_src == [True]
    modules = [n for n in written if n.startswith("WING_PANEL_")]
    assert len(modules) >= 4
    first_dat = next(i for i, n in enumerate(modules) if n.endswith(".dat"))
    assert all(n.endswith(".src") for n in modules[:first_dat])
    assert all(n.endswith(".dat") for n in modules[first_dat:])
    assert sorted(written[-2:]) == ["WING_PANEL.dat", "WING_PANEL.src"]
    assert "warning" not in capsys.readouterr().err
