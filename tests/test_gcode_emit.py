"""G-code output: round trip through the G-code parser to the printed precision, canned cycles
only where the drill axis is the program's -Z, harmless user text, and `accugrid gcode`."""

from __future__ import annotations

import re
import shutil

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from program_helpers import CELL, POINTS, ROOT, cell, cell_with, grid, panel_points, robot

from accugrid.app.cli import main
from accugrid.codegen.gcode import emit
from accugrid.codegen.gcode.emit import render_gcode
from accugrid.codegen.gcode.parse import parse_gcode
from accugrid.codegen.points import parse_points
from accugrid.codegen.program import build_program
from accugrid.kinematics.frames import abc_to_matrix, pose_from_xyzabc

# rows as in the example: row 2 staggered by 12.5 mm, so its hole at x 287.5 is on the crown
ROWS = np.array(
    [
        [x + (12.5 if y == 175.0 else 0.0), y]
        for y in (150.0, 175.0, 450.0)
        for x in range(0, 576, 25)
    ]
)
NASTY = ["A\nM2\nG0 X0", "B; M5", "C(x) %", "D" * 200, "E)(G1 Z-100)"]


def program_for(xy, ids=None, c=None):
    return build_program(panel_points(np.asarray(xy), ids), c or cell(), robot(), grid())


def visited(moves):
    """Every point the tool is sent to, in order, with the A B C in effect: (M, 6)."""
    out = []
    for m in moves:
        abc = [m.rotary[k] for k in "ABC"]
        if m.is_cycle:
            x, y, _ = m.target
            out += [[x, y, m.r_mm, *abc], [*m.target, *abc], [*m.end, *abc]]
        else:
            out.append([*m.target, *abc])
    return np.array(out)


def expected_points(program, frame):
    """Per hole the four corrected positions in the program frame, and the rotations."""
    pos, _ = program.in_frame(frame)
    rot = np.linalg.inv(frame[:3, :3]) @ program.cell.robot_T_base[:3, :3] @ program.rotations
    return pos, rot


def check_round_trip(program, text, frame=None):
    frame = program.cell.dialects["gcode"].robot_T_program if frame is None else frame
    pts = visited(parse_gcode(text, "p.ngc"))
    pos, rot = expected_points(program, frame)
    half = 0.5 * 10.0 ** -program.cell.dialects["gcode"].decimals + 1e-9
    at = 0
    for i in range(len(program)):
        for k in range(4):
            # the next visited point that is this stage (the program may pass a stage twice)
            while at < len(pts) and np.abs(pts[at, :3] - pos[i, k]).max() > half:
                # anything in between must be a position of the same hole
                assert np.abs(pts[at, :3] - pos[i]).max(axis=1).min() <= half, (i, k, pts[at])
                at += 1
            assert at < len(pts), f"hole {i} stage {k} not found"
            np.testing.assert_allclose(abc_to_matrix(pts[at, 3:]), rot[i], atol=3e-5)
            at += 1
    assert at == len(pts)


@settings(max_examples=25)
@given(
    st.lists(
        st.tuples(st.floats(-100, 650), st.floats(100, 550)), min_size=1, max_size=15, unique=True
    )
)
def test_round_trip_recovers_every_corrected_pose(xy):
    program = program_for(xy)
    check_round_trip(program, render_gcode(program, ["header"]))


def test_example_structure_and_canned_cycles():
    program = program_for(ROWS)
    text = render_gcode(program, ["accugrid test header"])
    lines = text.split("\n")
    assert lines[0] == "(accugrid test header)"
    assert any("A B C: KUKA A, B, C of the tool in the program frame, deg" in ln for ln in lines)
    code = [ln for ln in lines if ln and not ln.startswith("(")]
    assert code[0] == "G17 G21 G90 G94" and code[1].startswith("M3 S")
    assert code[-2:] == ["M5", "M2"]
    # the crown hole at base x 287.5 (row 2) has its axis exactly along -Z: a G82 (dwell) cycle
    cycles = [ln for ln in code if re.match(r"G98 G8[123] ", ln)]
    assert len(cycles) == 1 and cycles[0].startswith("G98 G82 ") and " P0.500 " in cycles[0]
    # the other holes are tilted: explicit G1 moves along the drill axis
    assert sum(ln.startswith("G1 ") for ln in code) == 3 * (len(program) - 1)
    check_round_trip(program, text)


def test_canned_cycle_options():
    xy = [[287.5, 175.0]]
    c = cell_with(drilling={"peck_mm": 2.0})
    text = render_gcode(program_for(xy, c=c), ["h"])
    assert re.search(r"^G98 G83 .* Q2\.000 ", text, re.M)
    c = cell_with(drilling={"dwell_s": 0.0})
    assert re.search(r"^G98 G81 ", render_gcode(program_for(xy, c=c), ["h"]), re.M)
    c = cell_with(gcode={"canned_cycles": False})
    text = render_gcode(program_for(xy, c=c), ["h"])
    assert "G8" not in text.replace("G80", "") and "G4 P0.500" in text
    c = cell_with(drilling={"retract_mm": 50.0})
    program = program_for(xy, c=c)
    text = render_gcode(program, ["h"])
    assert re.search(r"^G80\nG0 Z", text, re.M)
    check_round_trip(program, text)


def test_program_frame_differs_from_base():
    frame = pose_from_xyzabc(np.array([1700.0, 100.0, 1200.0, 180.0, -90.0, 0.0]))
    c = cell_with(gcode={"robot_T_program": frame})
    program = program_for(ROWS[:6], c=c)
    check_round_trip(program, render_gcode(program, ["h"]), frame)


def test_labels_cannot_inject_blocks():
    program = program_for(ROWS[: len(NASTY)], NASTY)
    plain = program_for(ROWS[: len(NASTY)], [f"H{i}" for i in range(len(NASTY))])
    text, ref = render_gcode(program, ["h"]), render_gcode(plain, ["h"])

    def code(t):
        return [ln for ln in t.split("\n") if not ln.startswith("(")]

    assert code(text) == code(ref)
    for ln in text.split("\n"):
        if ln.startswith("("):
            assert ln.endswith(")") and ln.count("(") == 1 and ln.count(")") == 1
            assert ";" not in ln and "%" not in ln


def test_identical_output_for_identical_input():
    assert render_gcode(program_for(ROWS), ["h"]) == render_gcode(program_for(ROWS), ["h"])


def test_abc_points_keep_their_orientation():
    text = "id,x,y,z,a,b,c\nK1,100,300,0,-90,0,175\nK2,125,300,0,-80,5,178\n"
    program = build_program(parse_points(text, "k.csv"), cell(), robot(), grid())
    check_round_trip(program, render_gcode(program, ["h"]))


# The built-in template as it was before the per-hole lines moved into Python: a user's copy that
# loops over `holes` in Jinja must keep working, with the same bytes.
LOOPING = ROOT / "tests" / "looping_templates" / "gcode" / "program.ngc.j2"


@pytest.mark.parametrize(
    "change, ids",
    [
        ({}, None),
        ({"drilling": {"peck_mm": 2.0, "retract_mm": 50.0}}, None),
        (
            {"drilling": {"dwell_s": 0.0, "retract_mm": 50.0}},
            [f"{n}{i}" for i in range(15) for n in NASTY],
        ),
        ({"gcode": {"canned_cycles": False}}, None),
        (
            {
                "gcode": {"canned_cycles": False},
                "drilling": {"dwell_s": 0.0, "retract_mm": 50.0},
            },
            None,
        ),
    ],
)
def test_user_template_looping_per_hole_gives_the_same_bytes(tmp_path, change, ids):
    program = program_for(ROWS, ids[: len(ROWS)] if ids else None, cell_with(**change))
    shutil.copyfile(LOOPING, tmp_path / "program.ngc.j2")
    assert "hole_lines" not in LOOPING.read_text()
    looped = render_gcode(program, ["h1", "h2"], tmp_path)
    assert looped == render_gcode(program, ["h1", "h2"])


def test_hole_lines_in_blocks_are_the_hole_lines_whole(tmp_path, monkeypatch):
    """Blocks of 7 holes, the lines printed twice, or measured by a user template: the same text
    as one block (the block-by-block writer only streams what it can)."""
    program = program_for(ROWS)
    whole = render_gcode(program, ["h"])
    builtin = (ROOT / "templates" / "gcode" / "program.ngc.j2").read_text()
    monkeypatch.setattr(emit, "BLOCK", 7)
    assert b"".join(emit.gcode_text(program, ["h"])).decode() == whole
    twice = builtin.replace("{{ hole_lines -}}", "{{ hole_lines -}}\n{{ hole_lines -}}")
    (tmp_path / "program.ngc.j2").write_text(twice)
    head, _, tail = whole.partition("M5\n")
    lines = head.split("G17 G21 G90 G94\n")[1].split("\n", 1)[1]
    assert render_gcode(program, ["h"], tmp_path) == head + lines + "M5\n" + tail
    (tmp_path / "program.ngc.j2").write_text(builtin.replace("hole_lines -", "hole_lines|length -"))
    assert f"{len(lines)}M5" in render_gcode(program, ["h"], tmp_path)


def run_cli(*args):
    return main(["gcode", str(POINTS), "--cell", str(CELL), *map(str, args)])


def test_command(tmp_path, capsys):
    out = tmp_path / "wp.ngc"
    assert run_cli("-o", out) == 0
    first = out.read_bytes()
    assert b"(grid grid_200mm.csv sha256 " in first
    assert run_cli("-o", out) == 2 and "use --force" in capsys.readouterr().err
    assert run_cli("-o", out, "--force") == 0 and out.read_bytes() == first
    assert run_cli("-o", POINTS, "--force") == 2
    assert "input" in capsys.readouterr().err
    nominal = tmp_path / "n.ngc"
    assert run_cli("-o", nominal, "--no-correction") == 0
    assert b"largest correction 0.000 mm" in nominal.read_bytes()


@pytest.mark.parametrize("option", ["--templates", "--grid"])
def test_command_bad_paths(tmp_path, capsys, option):
    out = tmp_path / "x.ngc"
    assert run_cli("-o", out, option, tmp_path / "nope") == 2
    assert "nope" in capsys.readouterr().err and not out.exists()


def test_command_header_names_the_inputs(tmp_path):
    import hashlib

    from accugrid.codegen import __version__
    from accugrid.codegen.points import read_points
    from accugrid.compensation import GridModel
    from accugrid.kinematics.frames import transform_points

    out = tmp_path / "h.ngc"
    assert run_cli("-o", out) == 0
    head = [ln[1:-1] for ln in out.read_text().split("\n")[:8]]
    grid_file = CELL.parent / "grid_200mm.csv"

    def sha(p):
        return hashlib.sha256(p.read_bytes()).hexdigest()

    model = GridModel.from_measurements(grid_file)
    pts = read_points(POINTS)
    e = model.predict(transform_points(cell().robot_T_base, pts.xyz))
    worst = int(np.argmax(np.linalg.norm(e, axis=1)))
    bound = re.fullmatch(
        r"largest u95 (\d+\.\d{3}) mm over 72 positions: the 95 percent bound "
        r"of the error",
        head.pop(6),
    )
    assert bound and 0.0 < float(bound.group(1)) < 0.3  # a grid of 0.02 + 0.03 mm noise
    assert head == [
        f"accugrid {__version__} gcode",
        f"points wing_panel_points.csv sha256 {sha(POINTS)}",
        f"cell cell.yaml sha256 {sha(CELL)}",
        f"grid grid_200mm.csv sha256 {sha(grid_file)}",
        "grid step 200.000 x 200.000 x 200.000 mm",
        f"largest correction {np.linalg.norm(e[worst]):.3f} mm at hole {pts.ids[worst]}",
        f"holes {len(pts)}",
    ]
