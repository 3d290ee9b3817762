"""The rewrite engine and `accugrid rewrite`: exact corrections, byte preservation, safety."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rewrite_helpers import (
    E_CONST,
    const_model,
    error_field,
    rewrite_gcode,
    rewrite_krl,
    write_cell,
    write_grid,
)
from scipy.spatial.transform import Rotation

from accugrid.app.cli import main
from accugrid.codegen.gcode.parse import parse_gcode
from accugrid.codegen.krl.parse import parse_krl
from accugrid.codegen.plugin_types import Options
from accugrid.compensation import GridModel

BASE2 = (100.0, 50.0, 0.0, 90.0, 0.0, 0.0)  # robot_T_base of BASE_DATA[2]
R2 = Rotation.from_euler("ZYX", BASE2[3:], degrees=True).as_matrix()
CONST_MODEL = const_model()  # e = E_CONST everywhere

SRC = (
    "&ACCESS RVP\r\n"
    "DEF job ( )\r\n"
    "; Bohrung f\xfcr Tr\xe4ger \x96 cp1252 bytes\r\n"
    "BAS (#BASE,2)\r\n"
    "PTP HOME\r\n"
    "LIN  { X 100.000,Y  -20.500 ,Z 300.000,A 0.000,B 90.000,C 0.000}  C_DIS ; first\r\n"
    "LIN P1\r\n"
    "LIN {X 9000.000,Y 0.000,Z 300.000,A 0.000,B 90.000,C 0.000}\r\n"
    "PTP P1\r\n"
    "END\r\n"
)
DAT = (
    "&ACCESS RVP\r\n"
    "DEFDAT job\r\n"
    "DECL E6POS P1={X 250.0000,Y 10.0000,Z 200.0000,A 0.0,B 90.0,C 0.0,S 'B010',T 'B10',"
    "E1 0.0}\r\n"
    "DECL E6AXIS HOME={A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0}\r\n"
    "ENDDAT\r\n"
)


@pytest.fixture
def job(tmp_path):
    cell = write_cell(tmp_path, field="constant", base_data={2: BASE2})
    src, dat = tmp_path / "job.src", tmp_path / "job.dat"
    src.write_bytes(SRC.encode("latin-1"))
    dat.write_bytes(DAT.encode("latin-1"))
    return tmp_path, cell, src, dat


def expected(xyz):
    """Base-frame position after adding the constant robot-frame error: p + R^T e."""
    return np.asarray(xyz) + R2.T @ E_CONST


def run(*args):
    """``accugrid rewrite --allow-partial``: these programs have home and clearance poses outside
    the grid (the job rule itself: tests/test_policy.py)."""
    return main(["rewrite", "--allow-partial", *map(str, args)])


def test_krl_pair_corrected_exactly_once_and_bytes_kept(job):
    folder, cell, src, dat = job
    out = folder / "out"
    assert run(src, dat, "--cell", cell, "-o", out, "--report", folder / "r.csv") == 0
    new_src = (out / "job.src").read_bytes().decode("latin-1")
    new_dat = (out / "job.dat").read_bytes().decode("latin-1")
    # the inline LIN, 3 decimals as in the input
    x, y, z = expected([100.0, -20.5, 300.0])
    line = f"LIN  {{ X {x:.3f},Y  {y:.3f} ,Z {z:.3f},A 0.000,B 90.000,C 0.000}}  C_DIS ; first\r\n"
    assert line in new_src
    # everything else of the .src unchanged (the outside LIN included)
    assert new_src.replace(line, "") == SRC.replace(SRC.splitlines(True)[5], "")
    # P1 used by two motions: corrected once, 4 decimals as in the input
    x, y, z = expected([250.0, 10.0, 200.0])
    assert f"P1={{X {x:.4f},Y {y:.4f},Z {z:.4f},A 0.0,B 90.0,C 0.0,S 'B010'" in new_dat
    assert new_dat.count("\r\n") == DAT.count("\r\n")
    report = (folder / "r.csv").read_text().splitlines()
    status = [r.split(",")[3] for r in report[1:]]
    assert sorted(status) == ["corrected", "corrected", "outside", "skipped"]
    assert any("joint-space" in r for r in report)


def test_strict_and_safety_leave_nothing_behind(job, capsys):
    folder, cell, src, dat = job
    out = folder / "strict"
    assert main(["rewrite", str(src), str(dat), "--cell", str(cell), "-o", str(out)]) == 2
    assert "outside the grid" in capsys.readouterr().err  # refused by default
    assert not out.exists()
    assert run(src, "--cell", cell, "-o", src, "--force") == 2  # never the input
    assert src.read_bytes() == SRC.encode("latin-1")
    target = folder / "one.src"
    assert run(src, dat, "--cell", cell, "-o", target) == 0
    assert run(src, dat, "--cell", cell, "-o", target) == 2  # exists, no --force
    assert run(src, dat, "--cell", cell, "-o", target, "--force") == 0
    assert (folder / "one.dat").exists()


def test_header_only_when_asked(job):
    folder, cell, src, dat = job
    assert run(src, dat, "--cell", cell, "-o", folder / "h", "--header") == 0
    text = (folder / "h" / "job.src").read_bytes().decode("latin-1")
    # below the DEF line: controller-written files have only & lines above it (issue 11 item 8)
    assert text.startswith("&ACCESS RVP\r\nDEF job ( )\r\n; accugrid ")
    dat_text = (folder / "h" / "job.dat").read_bytes().decode("latin-1")
    assert dat_text.startswith("&ACCESS RVP\r\nDEFDAT job\r\n; accugrid ")
    assert "sha256" in text and "; largest correction" in text
    assert run(src, dat, "--cell", cell, "-o", folder / "n") == 0
    assert "accugrid" not in (folder / "n" / "job.src").read_text("latin-1")


def test_lone_dat_needs_a_base(job):
    folder, cell, _, dat = job
    assert run(dat, "--cell", cell, "-o", folder / "a.dat", "--report", folder / "a.csv") == 0
    assert (folder / "a.dat").read_bytes() == dat.read_bytes()
    assert "not used by a motion" in (folder / "a.csv").read_text()
    assert run(dat, "--cell", cell, "-o", folder / "b.dat", "--base", "2") == 0
    x, y, z = expected([250.0, 10.0, 200.0])
    assert f"X {x:.4f},Y {y:.4f},Z {z:.4f}" in (folder / "b.dat").read_text("latin-1")


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"DEF a()\r\nLIN {X 1,Y 2,Z 3\r\n", "a.src:2:5: unbalanced"),  # truncated
        (b"DEF a()\r\nLIN {X 1,Y 2,Z 3}\r\n\x00\x9f\x88binary", "a.src:3: binary"),
    ],
)
def test_malformed_input_is_one_line_error_and_no_output(job, capsys, content, message):
    folder, cell, _, _ = job
    bad = folder / "a.src"
    bad.write_bytes(content)
    assert run(bad, "--cell", cell, "-o", folder / "x.src", "--report", folder / "x.csv") == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not (folder / "x.src").exists() and not (folder / "x.csv").exists()


def test_size_cap(job, capsys):
    folder, cell, _, _ = job
    big = folder / "big.ngc"
    big.write_bytes(b"G0 X1 Y2 Z3\n" * 20000)  # 240 kB
    assert run(big, "--cell", cell, "-o", folder / "big_out.ngc", "--max-mb", "0.1") == 2
    assert "over the limit" in capsys.readouterr().err
    assert not (folder / "big_out.ngc").exists()


def test_gcode_program_frame_decimals_and_outside(tmp_path):
    frame = (500.0, -200.0, 100.0, 0.0, 180.0, 0.0)  # program Z points down in the robot frame
    cell = write_cell(tmp_path, field="constant", program_frame=frame)
    prog = tmp_path / "p.ngc"
    prog.write_bytes(b"G21 G90 G17\r\nG0 X10. Y20.0 Z30.00\r\nG1 Z-5 (plunge)\r\nG0 Z9000\r\n")
    assert run(prog, "--cell", cell, "-o", tmp_path / "o.ngc", "--decimals", "3") == 0
    rot = Rotation.from_euler("ZYX", frame[3:], degrees=True).as_matrix()
    d = rot.T @ E_CONST
    out = (tmp_path / "o.ngc").read_bytes().decode()
    x, y, z = np.array([10.0, 20.0, 30.0]) + d
    assert f"G0 X{x:.3f} Y{y:.3f} Z{z:.3f}\r\n" in out
    assert f"G1 Z{-5 + d[2]:.3f} (plunge)\r\n" in out
    assert out.endswith("G0 Z9000\r\n")  # outside the grid: left as is


def _model():
    axes = [np.arange(-600.0, 601.0, 200.0)] * 3
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    return GridModel.from_measurements((pts, pts - error_field(pts, "smooth")))


MODEL = _model()


def _options(**kw):
    return Options(model=MODEL, **kw)


coord = st.integers(-500_000, 500_000).map(lambda v: v / 1000)


@settings(max_examples=25)
@given(st.lists(st.tuples(coord, coord, coord, st.integers(0, 7)), min_size=2, max_size=12))
def test_incremental_program_lands_where_its_absolute_twin_does(points):
    """G91 twin: each line writes only the axes flagged in the mask; both programs, rewritten,
    command the same positions (within the written rounding) and those are P + e(P)."""
    first = points[0][:3]
    absolute = ["G21 G90 G0 " + " ".join(f"{k}{v:.3f}" for k, v in zip("XYZ", first, strict=True))]
    incremental = [absolute[0], "G91"]
    prev = np.array(first)
    for *p, mask in points[1:]:
        axes = [i for i in range(3) if mask >> i & 1] or [0]
        absolute.append("G1 " + " ".join(f"{'XYZ'[i]}{p[i]:.3f}" for i in axes))
        incremental.append("G1 " + " ".join(f"{'XYZ'[i]}{p[i] - prev[i]:.3f}" for i in axes))
        for i in axes:
            prev[i] = p[i]
    a_text, i_text = "\n".join(absolute) + "\n", "\n".join(incremental) + "\n"
    a_moves, i_moves = parse_gcode(a_text), parse_gcode(i_text)
    np.testing.assert_allclose([m.target for m in a_moves], [m.target for m in i_moves], atol=1e-9)
    opts = _options()
    a_out = rewrite_gcode("a.ngc", a_text, opts)
    i_out = rewrite_gcode("i.ngc", i_text, opts)
    a_new = np.array([m.target for m in parse_gcode(a_out.texts["a.ngc"])])
    i_new = np.array([m.target for m in parse_gcode(i_out.texts["i.ngc"])])
    np.testing.assert_allclose(i_new, a_new, atol=1.5e-3)
    for row, new in zip(a_out.rows, a_new, strict=True):
        assert row.status == "corrected"
        assert np.allclose(new, row.new, atol=1e-9)  # the report tells what is commanded
    # a line that writes all three axes lands on P + e(P) within rounding
    full = [i for i, m in enumerate(a_moves) if len(m.words) == 3]
    targets = np.array([a_moves[i].target for i in full])
    want = MODEL.correct(targets)
    np.testing.assert_allclose(a_new[full], want, atol=6e-4)


def test_arc_and_its_start_move_by_one_shift():
    """The arc, the plunge that sets its start Z and the move that sets its start X, Y move by
    one vector on the axes they set (I, J from the start stay as written)."""
    text = "G90 G0 X0 Y0 Z10\nG1 Z-1\nG2 X20 Y0 I10 J0\nG1 X40\n"
    result = rewrite_gcode("arc.ngc", text, _options())
    assert [r.status for r in result.rows] == ["corrected"] * 4
    new = parse_gcode(result.texts["arc.ngc"])
    shift = np.array(new[2].target) - [20.0, 0.0, -1.0]
    np.testing.assert_allclose(np.array(new[2].start) - [0.0, 0.0, -1.0], shift, atol=1e-12)
    assert "I10 J0" in result.texts["arc.ngc"].splitlines()[2]
    assert np.abs(shift).max() > 0.05


def test_krl_reparse_gives_the_report(job):
    folder, cell, src, dat = job
    out = folder / "rp"
    assert run(src, dat, "--cell", cell, "-o", out) == 0
    before = parse_krl(SRC, "job.src")
    after = parse_krl((out / "job.src").read_text("latin-1"), "job.src")
    assert [p.values.keys() for p in before] == [p.values.keys() for p in after]
    moved = [
        np.allclose([a.x, a.y, a.z], expected([b.x, b.y, b.z]), atol=6e-4)
        for b, a in zip(before, after, strict=True)
    ]
    assert moved == [True, False]


EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.mark.parametrize("dialect", ["krl", "gcode"])
def test_round_trip_with_the_generator(tmp_path, dialect):
    """A program generated without correction, rewritten, equals the program generated with
    correction (header lines aside). The grid has a constant error, so the generator's one
    correction per hole and the rewrite's one correction per position must agree exactly."""
    grid = write_grid(
        tmp_path / "const.csv",
        lower=(1000, -800, 900),
        upper=(2400, 800, 2300),
        step=200.0,
        field="constant",
    )
    cell, points = EXAMPLES / "cell.yaml", EXAMPLES / "wing_panel_points.csv"
    nominal, corrected, rewritten = (tmp_path / n for n in ("nominal", "corrected", "rewritten"))
    if dialect == "krl":
        assert (
            main(["krl", str(points), "--cell", str(cell), "--no-correction", "-o", str(nominal)])
            == 0
        )
        assert (
            main(
                ["krl", str(points), "--cell", str(cell), "--grid", str(grid), "-o", str(corrected)]
            )
            == 0
        )
        files = sorted(p.name for p in nominal.iterdir())
        src = [nominal / f for f in files if f.endswith(".src")]
        dat = [nominal / f for f in files if f.endswith(".dat")]
        assert len(src) == len(dat) == 1
        assert (
            main(
                [
                    "rewrite",
                    str(src[0]),
                    str(dat[0]),
                    "--cell",
                    str(cell),
                    "--grid",
                    str(grid),
                    "-o",
                    str(rewritten),
                ]
            )
            == 0
        )
        pairs = [(corrected / f, rewritten / f) for f in files]
    else:
        # G-code files by suffix (codegen.dialects)
        nominal, corrected, rewritten = (
            p.with_suffix(".ngc") for p in (nominal, corrected, rewritten)
        )
        assert (
            main(["gcode", str(points), "--cell", str(cell), "--no-correction", "-o", str(nominal)])
            == 0
        )
        assert (
            main(
                [
                    "gcode",
                    str(points),
                    "--cell",
                    str(cell),
                    "--grid",
                    str(grid),
                    "-o",
                    str(corrected),
                ]
            )
            == 0
        )
        assert (
            main(
                [
                    "rewrite",
                    str(nominal),
                    "--cell",
                    str(cell),
                    "--grid",
                    str(grid),
                    "-o",
                    str(rewritten),
                ]
            )
            == 0
        )
        pairs = [(corrected, rewritten)]

    def body(path):
        header = ("; grid", "; largest", "(grid", "(largest")
        return [ln for ln in path.read_bytes().splitlines() if not ln.decode().startswith(header)]

    for want, got in pairs:
        assert body(got) == body(want)
    nominal_bytes = [
        (nominal / w.name if nominal.is_dir() else nominal).read_bytes() for w, _ in pairs
    ]
    assert [g.read_bytes() for _, g in pairs] != nominal_bytes  # something was corrected


NUM_TOKEN = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")
spaces = st.text(" \t", max_size=3)
krl_value = st.integers(-400_000, 400_000).map(lambda v: f"{v / 1000:.3f}")


@settings(max_examples=30)
@given(
    st.lists(
        st.tuples(
            st.sampled_from(["LIN", "lin", "PTP", "SLin"]),
            spaces,
            spaces,
            st.lists(krl_value, min_size=3, max_size=3),
            st.sampled_from(["", " ; done {X 1}", ";", " C_DIS ;FOLD x"]),
            st.booleans(),
        ),
        min_size=1,
        max_size=6,
    )
)
def test_krl_rewrite_changes_only_the_position_numbers(lines):
    """Random case, whitespace and comments around inline aggregates: the output has the same
    text between numbers, and each X, Y, Z is the input plus the constant error (base = robot)."""
    body = ["DEF r ( )", "BAS (#BASE,0)"]
    for kw, w1, w2, (x, y, z), tail, typed in lines:
        prefix = f"POS:{w1}" if typed else ""
        agg = f"{{{w2}{prefix}X {x},{w1}y{w2} {y} ,Z {z}{w1},A 0.0,B 90.0,C 0.0}}"
        body.append(f"{w1}{kw}{w2} {agg}{tail}")
    text = "\r\n".join(body + ["END"]) + "\r\n"
    opts = Options(model=CONST_MODEL)
    out = rewrite_krl({"r.src": text}, opts).texts["r.src"]
    assert NUM_TOKEN.split(out) == NUM_TOKEN.split(text)
    before, after = parse_krl(text, "r.src"), parse_krl(out, "r.src")
    for b, a in zip(before, after, strict=True):
        want = np.array([b.x, b.y, b.z]) + E_CONST
        assert np.allclose([a.x, a.y, a.z], want, atol=5e-4)
        assert (a.a, a.b, a.c) == (b.a, b.b, b.c)
