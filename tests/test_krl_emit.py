"""KRL output: round trip through the KRL parser to the printed precision, structure a KR C4
accepts, harmless user text, splitting into sub-programs, and the `accugrid krl` command."""

from __future__ import annotations

import re
import shutil

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from program_helpers import CELL, POINTS, ROOT, cell, cell_with, grid, panel_points, robot

from accugrid.app.cli import main
from accugrid.codegen.krl import emit
from accugrid.codegen.krl.configuration import configuration_words
from accugrid.codegen.krl.emit import module_split, render_krl, render_measurement
from accugrid.codegen.krl.parse import parse_krl
from accugrid.codegen.plugin import MeasureSettings
from accugrid.codegen.program import build_program
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix

ROWS = np.array([[x, y] for y in (150.0, 175.0, 450.0) for x in np.arange(0.0, 576.0, 25.0)])
NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*$")
NASTY = [
    "A\nEND\nDEF X( )",
    "B; $OUT[1]=TRUE",
    "C(x) %{PE} &ACCESS",
    "D" * 200,
    'E"\r\n{X 1}',
]


def program_for(xy, ids=None, c=None, corrected=True):
    return build_program(
        panel_points(np.asarray(xy), ids), c or cell(), robot(), grid() if corrected else None
    )


def decls(files):
    """name -> parsed E6POS of every .dat of a job."""
    out = {}
    for fname, text in files.items():
        if fname.endswith(".dat"):
            for p in parse_krl(text, fname):
                assert p.kind == "decl" and p.type == "E6POS"
                out[p.name] = p
    return out


def statements(text):
    """Code lines with comments and the &ACCESS/&REL header removed, stripped, blanks dropped."""
    code = (ln.split(";", 1)[0].strip() for ln in text.split("\r\n"))
    return [ln for ln in code if ln and not ln.startswith("&")]


def check_round_trip(program, files):
    parsed = decls(files)
    same_ret = program.cell.drilling.retract_mm == program.cell.drilling.approach_mm
    stages = ("APP", "CLR", "BOT") if same_ret else ("APP", "CLR", "BOT", "RET")
    assert len(parsed) == len(program) * len(stages)
    half = 0.5 * 10.0 ** -program.cell.dialects["krl"].decimals + 1e-9
    status, turn = np.moveaxis(configuration_words(program.configuration), -1, 0)
    for i in range(len(program)):
        for k, stage in enumerate(stages):
            p = parsed[f"XH{i + 1}_{stage}"]
            np.testing.assert_allclose([p.x, p.y, p.z], program.positions[i, k], atol=half, rtol=0)
            rot = abc_to_matrix(np.array([p.a, p.b, p.c]))
            # 0.0005 deg per printed angle bounds the rotation error
            np.testing.assert_allclose(rot, program.rotations[i], atol=3e-5)
            assert (p.s, p.t) == (status[i, k], turn[i, k])
            assert [p.values[f"E{n}"] for n in range(1, 7)] == [0.0] * 6


@settings(max_examples=25)
@given(
    st.lists(
        st.tuples(st.floats(-100, 650), st.floats(100, 550)), min_size=1, max_size=15, unique=True
    )
)
def test_round_trip_recovers_every_corrected_pose(xy):
    program = program_for(xy)
    files = render_krl(program, ["header"])
    check_round_trip(program, files)


def test_example_structure_a_kr_c4_accepts():
    program = program_for(ROWS)
    files = render_krl(program, ["accugrid test header"])
    assert sorted(files) == ["WING_PANEL.dat", "WING_PANEL.src"]
    src, dat = files["WING_PANEL.src"], files["WING_PANEL.dat"]
    # only & lines above DEF/DEFDAT, as in every controller-written file (issue 11 item 8)
    assert src.startswith(
        "&ACCESS RVP\r\n&REL 1\r\nDEF WING_PANEL( )\r\n; accugrid test header\r\n"
    )
    assert dat.startswith(
        "&ACCESS RVP\r\n&REL 1\r\nDEFDAT WING_PANEL\r\n; accugrid test header\r\n"
    )
    for text in (src, dat):
        assert "\n" not in text.replace("\r\n", "")
    s = statements(src)
    assert s[0] == "DEF WING_PANEL( )" and s[-1] == "END"
    assert "BAS(#INITMOV,0)" in s and "$BASE = BASE_DATA[1]" in s and "$TOOL = TOOL_DATA[1]" in s
    assert "$OUT[1] = TRUE" in s and s[-2] == "$OUT[1] = FALSE"
    d = statements(dat)
    assert d[0] == "DEFDAT WING_PANEL" and d[-1] == "ENDDAT"
    # every motion goes to a declared position, every declared position is used
    targets = [ln.split()[1] for ln in s if ln.startswith(("PTP ", "LIN "))]
    declared = set(decls(files))
    assert set(targets) == declared
    assert all(NAME_RE.match(n) and len(n) <= 24 for n in declared)
    # per hole: PTP travel (approximated), LIN approach, LIN feed, dwell, LIN retract (approximated)
    assert [ln.split()[0] for ln in s].count("PTP") == len(program)
    assert s.count("WAIT SEC 0.500") == len(program)
    assert f"$VEL.CP = {5 / 1000:.4f}" in s  # 5 mm/s feed in m/s
    assert all(ln.endswith("C_PTP") for ln in s if ln.startswith("PTP"))
    check_round_trip(program, files)


def test_labels_cannot_inject_statements():
    program = program_for(ROWS[: len(NASTY)], NASTY)
    plain = program_for(ROWS[: len(NASTY)], [f"H{i}" for i in range(len(NASTY))])
    files = render_krl(program, ["header"])
    ref = render_krl(plain, ["header"])
    for name in files:
        # the controller sees exactly the statements of a program with plain ids
        assert statements(files[name]) == statements(ref[name])
        lines = files[name].split("\r\n")
        assert len(lines) == len(ref[name].split("\r\n"))
        for ln in lines:
            assert len(ln) < 400
            if ln.startswith("; hole"):
                assert not re.search(r"[;(%&\"{}]", ln[1:])


@pytest.mark.parametrize("block", [1, 5, 11])
def test_files_do_not_depend_on_the_block_of_numbers(monkeypatch, block):
    """Numbers are made a block of holes at a time and sliced per module: modules that straddle
    blocks (8 holes per module here), and blocks smaller than a module, give the same files."""
    c = cell_with(krl={"lines_per_file": 80})
    program = program_for(ROWS, c=c)
    whole = dict(render_krl(program, ["h1", "h2"]))
    monkeypatch.setattr(emit, "BLOCK", block)
    assert dict(render_krl(program, ["h1", "h2"])) == whole
    assert dict(render_krl(program, ["h1", "h2"], LOOPING)) == whole  # the records, sliced too


def test_split_into_sub_programs():
    c = cell_with(krl={"lines_per_file": 80})
    program = program_for(ROWS, c=c)
    files = render_krl(program, ["h1", "h2"])
    parts = sorted(f[:-4] for f in files if f.endswith(".src") and f != "WING_PANEL.src")
    assert len(parts) > 1 and parts[0] == "WING_PANEL_001"
    assert all(n.count("\n") <= 80 for n in files.values())
    assert all(len(p) <= 24 and NAME_RE.match(p) for p in parts)
    main_s = statements(files["WING_PANEL.src"])
    assert [ln for ln in main_s if re.fullmatch(r"WING_PANEL_\d+\( \)", ln)] == [
        f"{p}( )" for p in parts
    ]
    assert "BAS(#INITMOV,0)" in main_s and not any(ln.startswith(("PTP", "LIN")) for ln in main_s)
    for p in parts:
        s, d = statements(files[f"{p}.src"]), statements(files[f"{p}.dat"])
        assert s[0] == f"DEF {p}( )" and d[0] == f"DEFDAT {p}"
        # each module declares exactly the positions its motions use
        used = {ln.split()[1] for ln in s if ln.startswith(("PTP ", "LIN "))}
        assert used == set(decls({f"{p}.dat": files[f"{p}.dat"]}))
    # holes stay in order across the modules
    order = [
        int(re.match(r"XH(\d+)_", ln.split()[1]).group(1))
        for p in parts
        for ln in statements(files[f"{p}.src"])
        if ln.startswith("PTP")
    ]
    assert order == list(range(1, len(program) + 1))
    check_round_trip(program, files)


def test_identical_output_for_identical_input():
    a = render_krl(program_for(ROWS), ["h"])
    b = render_krl(program_for(ROWS), ["h"])
    assert a == b


def test_user_templates_and_strict_undefined(tmp_path):
    program = program_for(ROWS[:2])
    copy = tmp_path / "tpl"
    shutil.copytree(ROOT / "templates", copy)
    src = copy / "krl" / "program.src.j2"
    src.write_text(src.read_text().replace("END\n", "; my shop\nEND\n"))
    files = render_krl(program, ["h"], copy)
    assert "; my shop\r\nEND\r\n" in files["WING_PANEL.src"]
    src.write_text("DEF {{ nmae }}( )\n")
    with pytest.raises(InputError, match="undefined"):
        render_krl(program, ["h"], copy)
    src.write_text("DEF {% if %}\n")
    with pytest.raises(InputError, match="syntax") as info:
        render_krl(program, ["h"], copy / "krl")
    assert info.value.line == 1


# The built-in KRL templates as they were before the per-hole lines moved into Python: a user's
# copy that loops over `holes` and `positions` in Jinja must keep working, with the same bytes.
LOOPING = ROOT / "tests" / "looping_templates" / "krl"


@pytest.mark.parametrize(
    "change, rows, ids",
    [
        ({}, ROWS, None),
        ({"krl": {"lines_per_file": 80}}, ROWS, None),
        (
            {
                "krl": {
                    "travel_motion": "lin",
                    "clamp_output": 2,
                    "external_axes": (100.0, 0, 0, 0, 0, -5.5),
                }
            },
            ROWS[:4],
            None,
        ),
        ({"drilling": {"retract_mm": 7.5}}, ROWS[: len(NASTY)], NASTY),
    ],
)
def test_user_template_looping_per_hole_gives_the_same_bytes(tmp_path, change, rows, ids):
    program = program_for(rows, ids, c=cell_with(**change))
    copy = tmp_path / "krl"
    shutil.copytree(ROOT / "templates" / "krl", copy)
    for name in ("program.src.j2", "program.dat.j2"):
        shutil.copyfile(LOOPING / name, copy / name)
    looped = render_krl(program, ["h1", "h2"], copy)
    assert looped == render_krl(program, ["h1", "h2"])
    assert "hole_lines" not in (copy / "program.src.j2").read_text()
    assert "position_lines" not in (copy / "program.dat.j2").read_text()


def run_cli(*args):
    return main(["krl", str(POINTS), "--cell", str(CELL), *map(str, args)])


def test_command_writes_reproducible_files_and_refuses_overwrite(tmp_path, capsys):
    out = tmp_path / "krl"
    assert run_cli("-o", out) == 0
    first = {p.name: p.read_bytes() for p in out.iterdir()}
    assert sorted(first) == ["WING_PANEL.dat", "WING_PANEL.src"]
    text = first["WING_PANEL.src"].decode()
    assert "; grid grid_200mm.csv sha256 " in text and "; largest correction " in text
    assert run_cli("-o", out) == 2
    assert "use --force" in capsys.readouterr().err
    assert run_cli("-o", out, "--force") == 0
    assert {p.name: p.read_bytes() for p in out.iterdir()} == first


def test_command_no_correction_and_grid_override(tmp_path, capsys):
    assert run_cli("-o", tmp_path / "n", "--no-correction") == 0
    nominal = (tmp_path / "n" / "WING_PANEL.dat").read_text()
    assert "largest correction 0.000 mm" in (tmp_path / "n" / "WING_PANEL.src").read_text()
    assert run_cli("-o", tmp_path / "c") == 0
    assert (tmp_path / "c" / "WING_PANEL.dat").read_text() != nominal
    assert run_cli("-o", tmp_path / "x", "--grid", tmp_path / "missing.csv") == 2
    assert "missing.csv" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()
    assert (
        run_cli("-o", tmp_path / "y", "--grid", CELL.parent / "grid_200mm.csv", "--no-correction")
        == 2
    )


def test_command_bad_points_write_nothing(tmp_path, capsys):
    bad = tmp_path / "p.csv"
    bad.write_text("id,x,y,z,i,j,k\nA,1,2,3,0,0,-1\nA,4,5,6,0,0,-1\n")
    out = tmp_path / "o"
    assert main(["krl", str(bad), "--cell", str(CELL), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:3:1: duplicate id 'A'" in err and "Traceback" not in err
    assert not out.exists()


def test_lin_travel_clamp_and_external_axes():
    c = cell_with(
        krl={
            "travel_motion": "lin",
            "clamp_output": 2,
            "external_axes": (100.0, 0, 0, 0, 0, -5.5),
        }
    )
    program = program_for(ROWS[:3], c=c)
    files = render_krl(program, ["h"])
    s = statements(files["WING_PANEL.src"])
    assert not any(ln.startswith("PTP") for ln in s)
    i = s.index("LIN XH1_APP C_DIS")
    assert s[i - 1] == "$VEL.CP = 0.5000"  # 500 mm/s travel
    assert s[i + 2 : i + 4] == ["LIN XH1_CLR", "$OUT_C[2] = TRUE"]
    assert s.count("$OUT[2] = FALSE") == 3
    for p in decls(files).values():
        assert p.values["E1"] == 100.0 and p.values["E6"] == -5.5


def test_command_allow_config_change(tmp_path, capsys):
    text = CELL.read_text().replace("  # status: 2 ", "  status: 0   ")
    assert "  status: 0" in text
    cell_file = tmp_path / "cell.yaml"
    cell_file.write_text(text)
    (tmp_path / "grid_200mm.csv").write_bytes((CELL.parent / "grid_200mm.csv").read_bytes())
    args = ["krl", str(POINTS), "--cell", str(cell_file), "-o", str(tmp_path / "o")]
    assert main(args) == 2  # the grid holds in Status 6 only
    assert "72 another Status than the grid's" in capsys.readouterr().err
    args.append("--no-correction")
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "hole 'WP-R1-001'" in err and "with Status 0" in err
    assert main([*args, "--allow-config-change"]) == 0
    assert "warning: 72 hole(s) take another Status than 0" in capsys.readouterr().err


def test_a_million_hole_job_numbers_its_modules_past_999():
    """The example cell (5,000 lines per file) splits 1e6 holes into more than 999 modules:
    numbered with four digits, valid KRL names, all called from the main program."""
    header = ["h"] * 6
    names = module_split(cell(), 1_000_000, header)[0]
    assert len(names) > 999 and names[0] == "WING_PANEL_0001"
    assert names[-1] == f"WING_PANEL_{len(names):04d}"
    assert all(len(n) <= 24 and NAME_RE.match(n) for n in names)
    assert module_split(cell(), 100_000, header)[0][:2] == ["WING_PANEL_001", "WING_PANEL_002"]


@pytest.mark.parametrize(
    ("name", "holes", "lines", "message"),
    [
        ("ABCDEFGHIJKLMNOPQRST", 1_000_000, 5000, "longer than 24 characters"),
        ("WING_PANEL", 10**8, 5000, "the main program calling them would have"),
    ],
)
def test_modules_that_cannot_be_named_or_called_are_refused(name, holes, lines, message):
    c = cell_with(krl={"name": name, "lines_per_file": lines})
    with pytest.raises(InputError, match=message):
        module_split(c, holes, ["h"])[0]


def test_a_job_the_modules_cannot_hold_is_refused_before_the_correction(tmp_path, capsys):
    """200 holes far outside the grid in a cell of 50 lines per file: the module layout is
    refused (before the correction and IK, which would refuse the holes)."""
    text = CELL.read_text().replace("lines_per_file: 5000", "lines_per_file: 50")
    (tmp_path / "cell.yaml").write_text(text)
    (tmp_path / "grid_200mm.csv").write_bytes((CELL.parent / "grid_200mm.csv").read_bytes())
    rows = "".join(f"H{i},{i},9000,0,0,0,-1\n" for i in range(200))
    (tmp_path / "p.csv").write_text("id,x,y,z,i,j,k\n" + rows)
    out = tmp_path / "o"
    argv = ["krl", str(tmp_path / "p.csv"), "--cell", str(tmp_path / "cell.yaml"), "-o", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "the main program calling them would have" in err and "outside" not in err
    assert not out.exists()


@pytest.mark.parametrize(
    "settings_",
    [
        MeasureSettings(
            tool=1, base=0, ptp_percent=30, speed_m_s=0.2, wait_sec=1.5, wait_input=None
        ),
        MeasureSettings(1, 2, 50, 0.25, 0.0, 7, ptp_only=True),
    ],
)
def test_measurement_lines_are_what_the_looping_templates_made(tmp_path, settings_):
    """The measurement program's per-row lines come formatted from Python; a user template that
    loops over `moves` and `points` (the former built-in ones) gives the same bytes."""
    rng = np.random.default_rng(3)
    points = np.round(rng.uniform([1500, -200, 1300], [1900, 200, 1700], (40, 3)), 2)
    points[20:] = points[:20]  # repeated poses share one E6POS
    ids = [f"P{i}" for i in range(20)] + ["x;(y)%"] * 20
    status, turn = np.full(40, 6), rng.integers(0, 64, 40)
    looping = LOOPING
    args = (points, [0.0, 90.0, 0.0], ids, status, turn, "measure_it", ["h1"], settings_)
    assert "moves" in (looping / "measure.src.j2").read_text()
    assert render_measurement(*args, looping) == render_measurement(*args)
