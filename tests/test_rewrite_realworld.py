"""`accugrid rewrite` on the real programs in ../shared/realworld (RoboDK, a KUKA controller, a
person, G-code generators), with a synthetic grid that covers their positions.

Checked without trusting the rewrite: a generic tokenizer shows the output differs from the input
only in numbers on the lines the report says were corrected; re-parsing the output gives the
reported new positions; the report has a row for every position the parser finds.
"""

from __future__ import annotations

import csv
import subprocess

import numpy as np
import pytest
from rewrite_helpers import REALWORLD_BASE_DATA, REALWORLD_REWRITES, changed_lines, write_cell

from accugrid.app.cli import main
from accugrid.codegen.gcode.parse import parse_gcode
from accugrid.codegen.krl.parse import scan_krl

# how many positions must be corrected at least, per case of REALWORLD_REWRITES
AT_LEAST = {
    "robodk": 0,  # its LINs move a tool set as a literal frame that is not the cell's
    "xpoints_alone": 100,
    "xpoints_no_base": 0,
    "st1_st2_pair": 1,
    # BAS(#INITMOV,0) in T1/T2 only (an IF): the base depends on the mode; and 7 of the 13
    # positions it uses are also left operands of ':' (frames): never corrected
    "job1_side1": 0,
    "job1_side1_strict_rules": 0,
    "sample_program": 0,  # tool and base frames, frames passed to a routine: no drilling position
    "cnc_struc": 790,
    "heatsink": 40,
    # its G91 cycles repeated L3/L4 start at a level never set: not corrected, and neither are
    # the 5 holes that set their start (one increment cannot undo a corrected start); its
    # absolute cycles in G18 and G19 are
    "example3_inch": 15,
    "lagun_parameters": 0,
    "my100_inch": 91,
    "drill_practice": 4,
    "vertical_slot": 0,  # T5 M06 G43: every move is tool 5's tip, not the cell's tool 1
}
# (inputs, extra options, how many positions must be corrected at least)
CASES = {case: (*REALWORLD_REWRITES[case], AT_LEAST[case]) for case in REALWORLD_REWRITES}


KRL = (".src", ".dat")


@pytest.mark.parametrize("case", sorted(CASES))
def test_realworld_rewrite(realworld, tmp_path, case):
    names, options, at_least = CASES[case]
    cell = write_cell(tmp_path, base_data=REALWORLD_BASE_DATA)
    inputs = [realworld / n for n in names]
    out = tmp_path / "out"
    target = out if len(inputs) == 2 else out / inputs[0].name  # a pair: -o is a folder
    args = ["rewrite", "--allow-partial", *map(str, inputs), "--cell", str(cell), "-o", str(target)]
    report = tmp_path / "report.csv"
    assert main([*args, "--report", str(report), *options]) == 0
    rows = list(csv.DictReader(report.open()))
    corrected = [r for r in rows if r["status"] == "corrected"]
    assert len(corrected) >= at_least
    for path in inputs:
        before = path.read_bytes().decode("latin-1")
        after = (out / path.name).read_bytes().decode("latin-1")
        mine = [r for r in rows if r["file"] == path.name]
        lines = changed_lines(before, after, added_words=path.suffix.lower() not in KRL)
        corrected_lines = {int(r["line"]) for r in mine if r["status"] == "corrected"}
        if path.suffix.lower() in KRL:
            assert lines <= corrected_lines
        if path.suffix.lower() in (".src", ".dat"):
            scan_before = scan_krl(before, path.name)
            scan_after = scan_krl(after, path.name)
            keys = {(int(r["line"]), r["name"]) for r in mine}
            for p in scan_before.positions:  # every position the parser finds is reported
                assert (p.line, p.name) in keys
            by_key = {(int(r["line"]), r["name"]): r for r in mine}
            for p_old, p_new in zip(scan_before.positions, scan_after.positions, strict=True):
                row = by_key[(p_old.line, p_old.name)]
                new_xyz = np.array([p_new.x, p_new.y, p_new.z], dtype=float)
                if row["status"] == "corrected":
                    want = [float(row[k]) for k in ("x_new", "y_new", "z_new")]
                    assert np.allclose(new_xyz, want, atol=1e-4)
                    assert {k: v for k, v in p_new.values.items() if k not in "XYZ"} == {
                        k: v for k, v in p_old.values.items() if k not in "XYZ"
                    }
                else:
                    assert p_new.values == p_old.values
        else:
            moves_before, moves_after = parse_gcode(before), parse_gcode(after)
            assert len(mine) == len(moves_before)
            # an incremental (G91) move not corrected may change its increments: it must land
            # where the input put it, not be dragged by a corrected move before it
            # nor a cycle's line that needs the Z and R words of its own hole (added)
            kept = {m.line for m in moves_before if m.incremental or m.is_cycle}
            assert lines <= corrected_lines | kept
            for row, m, old in zip(mine, moves_after, moves_before, strict=True):
                assert int(row["line"]) == m.line
                if row["status"] == "corrected":
                    want = [float(row[k]) for k in ("x_new", "y_new", "z_new")]
                    assert np.allclose(m.target, want, atol=1e-4)
                else:  # the axes it writes, to half a unit of the last decimal (0.01 mm, 0.001 in)
                    half = 0.5 * m.scale * (1e-3 if m.scale != 1.0 else 1e-2) + 1e-9
                    axes = ["XYZ".index(k) for k in m.words if k in "XYZ"]
                    np.testing.assert_allclose(
                        np.array(m.target)[axes], np.array(old.target)[axes], atol=half
                    )
    skipped = [r for r in rows if r["status"] != "corrected"]
    assert all(r["reason"] for r in skipped)


def test_realworld_reasons(realworld, tmp_path):
    """The rules for what is not placed, on the real files."""
    cell = write_cell(tmp_path)
    side = realworld / "krl" / "chinamilling_St1_Job1_Side1.src"
    report = tmp_path / "r.csv"
    args = [str(side), str(side.with_suffix(".dat")), "--cell", str(cell)]
    argv = ["rewrite", "--allow-partial", *args, "-o", str(tmp_path / "o"), "--report", str(report)]
    assert main(argv) == 0
    text = report.read_text()
    assert "frame arithmetic" in text and "MoveSettings" in text and "$POS_ACT" in text
    robodk = realworld / "krl" / "robodk_Program.src"
    argv = ["rewrite", str(robodk), "--cell", str(cell), "-o", str(tmp_path / "r.src")]
    argv += ["--report", str(report), "--force"]
    # its first two LINs move the tool $TOOL = {FRAME: X -30.000, ...} (line 49), not the cell's;
    # its last two follow a call that may change $BASE: not placed, they would land off by the
    # robot's error, so the job fails unless partial output is allowed
    assert main(argv) == 2
    assert not (tmp_path / "r.src").exists()
    assert main([*argv, "--allow-partial"]) == 0
    rows = list(csv.DictReader(report.open()))
    lins = [r for r in rows if r["name"] == "LIN"]
    assert [r["status"] for r in lins] == ["skipped"] * 4
    for row in lins[:2]:
        assert row["reason"].startswith("tool unknown: $TOOL set to a literal frame (line 49)")
    assert "Subprog" in rows[-2]["reason"] or any("Subprog" in r["reason"] for r in rows)


@pytest.mark.parametrize("case", sorted(k for k, v in CASES.items() if v[0][0].startswith("gcode")))
def test_realworld_gcode_through_rs274(realworld, tmp_path, rs274, case):
    """LinuxCNC's interpreter runs every rewritten G-code program as it runs the original: the
    same sequence of canonical commands (only their numbers differ) and the same ending (a few
    of these programs stop at a tool the interpreter's table lacks, or a missing subroutine)."""
    names, options, _ = CASES[case]
    cell = write_cell(tmp_path, base_data=REALWORLD_BASE_DATA)
    program = realworld / names[0]
    out = tmp_path / program.name
    argv = ["rewrite", "--allow-partial", str(program), "--cell", str(cell), "-o", str(out)]
    assert main([*argv, *options]) == 0
    runs = []
    for path in (program, out):
        run = subprocess.run(
            [rs274, "-g", str(path)], capture_output=True, text=True, timeout=60, check=False
        )
        commands = [line.split("N.....")[-1].split("(")[0] for line in run.stdout.splitlines()]
        error = run.stderr.replace(str(path), "PROGRAM").splitlines()[:2]
        runs.append((run.returncode, error, commands))
    assert runs[0] == runs[1]
    assert len(runs[0][2]) > 5
