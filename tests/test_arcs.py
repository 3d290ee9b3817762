"""Arcs and circles, each on its own minimal program: G2/G3 arcs and helices in the three planes
(I/J/K from the start or absolute, R format, P turns), chained arcs, an orbital hole, arcs after
G91 moves, an arc whose correction varies too much; KRL ``CIRC``/``SCIRC`` auxiliary and end
points (points, each corrected at its own position).

Expected values are recomputed here from the grid's own interpolation of each point (``GridModel``
read from the grid file the cell names, or built here), the arc's centre worked out by hand from
its words, and, for G-code, LinuxCNC's ``rs274``: its ARC_FEED gives each arc's end and centre
as it reads the rewritten program; never from the rewrite under test.
"""

from __future__ import annotations

import csv
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rewrite_helpers import rewrite_gcode, write_cell
from scipy.spatial.transform import Rotation

from accugrid.app.cli import main
from accugrid.codegen.plugin_types import Options
from accugrid.compensation import GridModel


def report(path: Path) -> list[dict[str, str]]:
    return list(csv.DictReader(open(path, newline="")))


def krl_numbers(text: str) -> list[list[float]]:
    """X, Y, Z of every ``{X .., Y .., Z ..}`` aggregate of a line, in order."""
    out = []
    for part in text.split("{")[1:]:
        words = dict(p.strip().split(None, 1) for p in part.split("}")[0].split(","))
        out.append([float(words[k]) for k in "XYZ"])
    return out


def test_krl_circ_aux_and_end_points_are_each_corrected_at_their_own_position(tmp_path):
    """``CIRC aux, end`` and ``SCIRC aux, end`` (inline and by name, with ``CA``): both points are
    positions the circle passes through, each corrected by the grid at its own place (base 0:
    the robot frame), not shifted together."""
    cell = write_cell(tmp_path, field="smooth")
    grid = GridModel.from_measurements(tmp_path / "grid.csv")
    src, dat = tmp_path / "c.src", tmp_path / "c.dat"
    src.write_text(
        "DEF c( )\n"
        "BAS (#BASE,0)\n"
        "LIN {X 600.0,Y 0.0,Z 800.0,A 0.0,B 90.0,C 0.0}\n"
        "CIRC {X 700.0,Y 100.0,Z 800.0,A 0.0,B 90.0,C 0.0},{X 600.0,Y 200.0,Z 800.0,A 0.0,"
        "B 90.0,C 0.0}\n"
        "CIRC {X 500.0,Y 100.0,Z 800.0},{X 600.0,Y 0.0,Z 800.0}, CA 360.0\n"
        "SCIRC {X 900.0,Y 100.0,Z 1250.0,A 0.0,B 90.0,C 0.0}, {X 600.0,Y 400.0,Z 1250.0,"
        "A 0.0,B 90.0,C 0.0} C_SPL\n"
        "CIRC XAUX, XEND\n"
        "END\n"
    )
    dat.write_text(
        "DEFDAT c\n"
        "DECL E6POS XAUX={X 650.0,Y 300.0,Z 700.0,A 0.0,B 90.0,C 0.0,S 6,T 27,E1 0.0}\n"
        "DECL E6POS XEND={X 300.0,Y 650.0,Z 700.0,A 0.0,B 90.0,C 0.0,S 6,T 27,E1 0.0}\n"
        "ENDDAT\n"
    )
    out = tmp_path / "out"
    argv = ["rewrite", src, dat, "--cell", cell, "-o", out, "--decimals", "4"]
    assert main([str(a) for a in [*argv, "--report", tmp_path / "r.csv"]]) == 0
    new_src = (out / "c.src").read_text().splitlines()
    new_dat = (out / "c.dat").read_text().splitlines()
    pairs = [  # (line of the original, line of the rewrite)
        (line, new_src[k])
        for k, line in enumerate(src.read_text().splitlines())
        if "CIRC {" in line
    ]
    pairs += [
        (line, new_dat[k]) for k, line in enumerate(dat.read_text().splitlines()) if "=" in line
    ]
    points = np.array([p for old, _ in pairs for p in krl_numbers(old)])
    assert len(points) == 8
    written = np.array([p for _, new in pairs for p in krl_numbers(new)])
    want = grid.correct(points)  # base 0 is the robot frame: P + e(P) at each point
    np.testing.assert_allclose(written, want, atol=0.5e-4 + 1e-9)
    # the aux and end points of each motion get different corrections: each its own
    assert np.abs((want - points)[0::2] - (want - points)[1::2]).max() > 0.01
    rows = [
        r
        for r in report(tmp_path / "r.csv")
        if "CIRC" in r["name"] or r["name"] in ("XAUX", "XEND")
    ]
    assert len(rows) == 8 and all(r["status"] == "corrected" for r in rows)


# ---------------------------------------------------------------- G-code arcs

T_PROGRAM = np.eye(4)  # robot_T_program: Z down, X reversed, away from the robot's origin
T_PROGRAM[:3, :3] = Rotation.from_euler("ZYX", [0.0, 180.0, 0.0], degrees=True).as_matrix()
T_PROGRAM[:3, 3] = [500.0, -200.0, 100.0]
HALF = 0.5e-3 + 1e-9  # half the last written decimal (3 decimals), mm
PLANE_AXES = {"G17": (0, 1, 2), "G18": (2, 0, 1), "G19": (1, 2, 0)}  # rs274's ARC_FEED order
ARC_RE = re.compile(r"ARC_FEED\(([^)]*)\)")
PLANE_RE = re.compile(r"SELECT_PLANE\(CANON_PLANE_(XY|XZ|YZ)\)")
MOVE_RE = re.compile(r"(STRAIGHT_TRAVERSE|STRAIGHT_FEED|ARC_FEED)\(([^)]*)\)")
CANON_PLANES = {"XY": "G17", "XZ": "G18", "YZ": "G19"}


def linear_grid(gradient: float) -> GridModel:
    """A grid over +-600 mm (100 mm step) of e(P) = (0.25, -0.125, 0.375) mm plus a linear
    field of ``gradient`` mm/mm."""
    axes = [np.arange(-600.0, 601.0, 100.0)] * 3
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    x, y, z = pts.T
    e = np.array([0.25, -0.125, 0.375]) + gradient * np.stack([x + z, 2 * z - y, -y], axis=1)
    return GridModel.from_measurements((pts, pts - e))


GENTLE, STEEP = linear_grid(1e-5), linear_grid(2e-4)


def corrected(model: GridModel, program_xyz) -> np.ndarray:
    """Where program-frame points (N, 3) must be commanded: p + R^T e(T p), e from the grid."""
    p = np.atleast_2d(np.asarray(program_xyz, float))
    robot = p @ T_PROGRAM[:3, :3].T + T_PROGRAM[:3, 3]
    return p + (model.correct(robot) - robot) @ T_PROGRAM[:3, :3]


def gcode_rewrite(text: str, model: GridModel):
    """The rewritten text and its report rows (3 decimals; positions left uncorrected are kept
    and reported)."""
    opts = Options(model=model, decimals=3, allow_partial=True)
    result = rewrite_gcode("p.ngc", text, opts, T_PROGRAM)
    return result.texts["p.ngc"], list(result.rows)


def interpret(rs274, path: Path) -> subprocess.CompletedProcess:
    """``rs274 -g path`` (the fixture's rs274 runs in a home of its own: see conftest)."""
    return subprocess.run(
        [rs274, "-g", str(path)], capture_output=True, text=True, timeout=60, check=False
    )


def run_rs274(rs274, folder: Path, text: str, complete: bool = True) -> str:
    """rs274's canonical commands for ``text``; ``complete``: it must run to the program's end
    without an error."""
    path = folder / "arc.ngc"
    path.write_text(text)
    run = interpret(rs274, path)
    if not complete:
        return run.stdout
    assert run.returncode == 0 and "PROGRAM_END()" in run.stdout, run.stdout[-800:] + run.stderr
    assert "USE_LENGTH_UNITS(CANON_UNITS_MM)" in run.stdout
    return run.stdout


def arcs_of(out: str) -> list[dict]:
    """Each ARC_FEED of rs274's output: its plane, start (the previous move's end), end and
    centre (3 mm each; the centre's helix coordinate NaN), turns; and the command names."""
    plane, pos, arcs = "G17", np.full(3, np.nan), []
    for line in out.splitlines():
        found = PLANE_RE.search(line)
        if found:
            plane = CANON_PLANES[found.group(1)]
        move = MOVE_RE.search(line)
        if not move:
            continue
        values = [float(v) for v in move.group(2).split(",")]
        if move.group(1) != "ARC_FEED":
            pos = np.array(values[:3])
            continue
        a, b, h = PLANE_AXES[plane]
        end, centre = np.empty(3), np.full(3, np.nan)
        end[[a, b, h]] = values[0], values[1], values[5]
        centre[[a, b]] = values[2], values[3]
        arcs.append({"plane": plane, "start": pos, "end": end, "centre": centre})
        arcs[-1]["turns"] = int(values[4])
        pos = end
    return arcs


def commands(out: str) -> list[str]:
    """The canonical commands rs274 printed, by name, in order."""
    return [line.split("N.....")[-1].split("(")[0].strip() for line in out.splitlines()]


def radii(arc: dict) -> tuple[float, float]:
    a, b, _ = PLANE_AXES[arc["plane"]]
    c = arc["centre"][[a, b]]
    return float(np.hypot(*(arc["start"][[a, b]] - c))), float(np.hypot(*(arc["end"][[a, b]] - c)))


def check_rigid(rs274, tmp_path, text: str, atol: float = HALF) -> list[dict]:
    """Rewrite ``text``: every move corrected; rs274 runs the same commands; each arc's start,
    centre and end after rewriting are those before plus the correction at its centre (the
    helix axis halfway from start to end) within ``atol`` (half the written resolution for an
    arc of its own; the resolution for arcs that share one shift), its radii those before
    exactly. The arcs after."""
    model = GENTLE
    before = run_rs274(rs274, tmp_path, text)
    new, rows = gcode_rewrite(text, model)
    assert all(r.status == "corrected" for r in rows), [(r.line, r.reason) for r in rows]
    after = run_rs274(rs274, tmp_path, new)
    assert commands(after) == commands(before)
    old_arcs, new_arcs = arcs_of(before), arcs_of(after)
    assert len(old_arcs) == len(new_arcs) > 0
    for old, arc in zip(old_arcs, new_arcs, strict=True):
        h = PLANE_AXES[old["plane"]][2]
        centre = old["centre"].copy()
        centre[h] = (old["start"][h] + old["end"][h]) / 2
        shift = corrected(model, centre)[0] - centre
        for key in ("start", "end"):
            np.testing.assert_allclose(arc[key], old[key] + shift, atol=atol)
        keep = ~np.isnan(old["centre"])
        np.testing.assert_allclose(arc["centre"][keep], (old["centre"] + shift)[keep], atol=atol)
        assert radii(arc) == pytest.approx(radii(old), abs=1e-9)  # rs274 prints 4 decimals
        assert arc["turns"] == old["turns"]
        assert np.abs(shift).max() > 0.1  # the field moves it measurably
    return new_arcs


@pytest.mark.parametrize(
    "arc",
    [
        "G17 G2 X320 Y110 I10 J0",  # a half circle, I J from the start
        "G17 G3 X310 Y120 I0 J10 Z-20 P2",  # a helix of 1.25 turns down to Z-20
        "G17 G90.1 G2 X320 Y110 I310 J110",  # absolute centre
        "G17 G2 X310 Y120 R10",  # R format, a quarter circle
        "G17 G3 X310 Y120 R-10",  # R format, three quarters
        "G18 G2 X310 Z-30 I0 K-10 Y115 P3",  # XZ plane, helix along Y
        "G18 G90.1 G3 X320 Z-20 I310 K-20",
        "G19 G3 Y130 Z-20 J10 K0 X305",  # YZ plane, helix along X
        "G19 G2 Y100 Z-20 R10",
    ],
)
def test_arc_moves_rigidly_by_the_correction_at_its_centre(rs274, tmp_path, arc):
    """One arc (or helix) after the moves that set its start at (300, 110, -20): start, centre
    and end shifted by one vector, the correction at its centre, radius kept exactly."""
    text = f"G21 G90 F100\nG0 X300 Y110 Z5\nG1 Z-20\n{arc}\nG0 Z10\nM2\n"
    check_rigid(rs274, tmp_path, text)


def test_an_orbital_hole_moves_as_one(rs274, tmp_path):
    """Helical (orbital) drilling of a 20 mm hole at (300, 100): a plunge to the top, three
    helix turns of 2 mm down, a full circle at the bottom with no end words, back to the centre:
    every arc chained to the last, one shift for the whole hole (the correction at its centre),
    the centre words as written."""
    text = (
        "G21 G90 G17 F200\nG0 X310 Y100 Z5\nG1 Z0\nG2 X310 Y100 Z-2 I-10 J0\n"
        "G2 X310 Y100 Z-4 I-10 J0\nG2 X310 Y100 Z-6 I-10 J0\nG2 I-10 J0\nG1 X300 Y100\n"
        "G0 Z5\nM2\n"
    )
    arcs = check_rigid(rs274, tmp_path, text)
    assert len(arcs) == 4
    shifts = np.array([a["centre"][:2] - [300.0, 100.0] for a in arcs])
    assert np.ptp(shifts, axis=0).max() == 0.0  # one shift for all
    new, _ = gcode_rewrite(text, GENTLE)
    assert new.count("I-10 J0") == 4


ENDS = [[280.0, 105.0, -20.0], [300.0, 105.0, -20.0], [310.0, 115.0, -20.0], [300.0, 125.0, -20.0]]


def test_chained_arcs_and_incremental_moves(rs274, tmp_path):
    """An S of two arcs (the second starts where the first ends) reached by G91 moves, then a
    G91 arc and a G91 arc with an absolute (G90.1) centre: all land rigidly shifted, the
    increments rewritten from the shifted positions."""
    text = (
        "G21 G90 G17 F100\nG0 X250 Y100 Z5\nG91 G0 X10 Y5\nG1 Z-25\n"
        "G90 G2 X280 Y105 I10 J0\nG3 X300 Y105 I10 J0\n"
        "G91 G2 X10 Y10 I10 J0\nG90.1 G3 X-10 Y10 I300 J115\nG91.1 G90 G0 Z5\nM2\n"
    )
    arcs = check_rigid(rs274, tmp_path, text, atol=1e-3 + 1e-9)
    # chained end to start and at one depth: one shift, each arc within 0.001 mm of its own
    shifts = [arc["end"] - end for arc, end in zip(arcs, ENDS, strict=True)]
    np.testing.assert_allclose(shifts, [shifts[0]] * 4, atol=1e-9)


def test_an_arc_whose_correction_varies_too_much_is_reported(rs274, tmp_path):
    """Where the correction varies across an arc by more than the written resolution, it is not
    corrected, nor are the moves that set its start: the report says by how much, and rs274
    cuts the same arc as before. The move after it is corrected (it writes X, Y and Z: one that
    wrote Z alone would stay at the arc's uncorrected end, farther than the tolerance)."""
    text = "G21 G90 G17 F100\nG0 X300 Y110 Z5\nG1 Z-20\nG2 X340 Y110 I20 J0\nG0 X340 Y110 Z10\nM2\n"
    new, rows = gcode_rewrite(text, STEEP)
    assert [r.status for r in rows] == ["skipped", "skipped", "skipped", "corrected"]
    assert "correction varies by" in rows[2].reason and " mm across the arc" in rows[2].reason
    assert "sets the start of the arc at line 4" in rows[0].reason
    assert new.splitlines()[:4] == text.splitlines()[:4]
    assert arcs_of(run_rs274(rs274, tmp_path, new)) and all(
        np.array_equal(a[k], b[k], equal_nan=True)
        for a, b in zip(
            arcs_of(run_rs274(rs274, tmp_path, new)),
            arcs_of(run_rs274(rs274, tmp_path, text)),
            strict=True,
        )
        for k in ("start", "end", "centre")
    )
    # independently: the correction at its farthest points differs from the centre's by more
    # than 0.001 mm (what 3 decimals can write)
    ends = corrected(STEEP, [[300.0, 110.0, -20.0], [340.0, 110.0, -20.0], [320.0, 110.0, -20.0]])
    spread = ends - [[300.0, 110.0, -20.0], [340.0, 110.0, -20.0], [320.0, 110.0, -20.0]]
    assert np.abs(spread[:2] - spread[2]).max() > 0.001


def test_the_side_an_arc_sweeps_decides(tmp_path):
    """Two half circles between the same points about the same centre: the correction is
    constant where robot y >= 0 (program y >= 200) and varies below. G3 sweeps the constant
    side and is corrected; G2 sweeps the other side and is reported (its ends and centre alone
    would not tell them apart)."""
    axes = [np.arange(-600.0, 601.0, 100.0)] * 3
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    e = np.tile([0.25, -0.125, 0.375], (len(pts), 1))
    e[:, 2] += 2e-4 * np.minimum(pts[:, 1], 0.0)
    half = GridModel.from_measurements((pts, pts - e))
    ends = corrected(half, [[320.0, 200.0, -20.0], [280.0, 200.0, -20.0], [300.0, 200.0, -20.0]])
    assert np.ptp(ends[:, 2]) == pytest.approx(0.0, abs=1e-12)  # ends and centre agree
    for arc, status in (("G3", "corrected"), ("G2", "skipped")):
        text = f"G21 G90 G17 F100\nG0 X320 Y200 Z5\nG1 Z-20\n{arc} X280 Y200 I-20 J0\nM2\n"
        rows = gcode_rewrite(text, half)[1]
        assert rows[2].status == status, rows[2].reason
    bottom = corrected(half, [[300.0, 180.0, -20.0]])[0, 2] - (-20.0)  # the lowest point
    spread = abs(bottom - (ends[2, 2] + 20.0))
    assert f"the Z correction varies by {spread:.4f} mm across the arc" in rows[2].reason
    assert spread > 0.002


# ---------------------------------------------------------------- G18/G19 canned cycles


def feeds(out: str) -> tuple[np.ndarray, np.ndarray]:
    """The hole bottoms (STRAIGHT_FEED ends) of rs274's cycle expansion and the point each feed
    starts from (its R plane)."""
    moves = [
        (m.group(1), [float(v) for v in m.group(2).split(",")[:3]]) for m in MOVE_RE.finditer(out)
    ]
    at = [i for i, (kind, _) in enumerate(moves) if kind == "STRAIGHT_FEED"]
    return np.array([moves[i][1] for i in at]), np.array([moves[i - 1][1] for i in at])


@pytest.mark.parametrize(
    ("plane", "axis", "lines", "atol"),
    [
        ("G18", 1, ["G81 X320 Z-10 Y-5 R2", "X330 Z-20", "G91 X5 Z5 Y-4 R-3", "X5 Z-5"], HALF),
        ("G19", 0, ["G82 P0.2 Y110 Z-10 X-5 R2", "Y120 Z-20 X-8", "G91 Y5 Z5 R-3"], HALF),
        # one increment for the 3 holes of L3: their corrections agree within 0.001 mm
        ("G18", 1, ["G99 G81 X310 Z-15 Y-5 R2", "G98 X340 R4", "G91 G99 X5 Y-2 R-1 L3"], 1e-3),
    ],
)
def test_side_plane_cycles_drill_their_corrected_holes(rs274, tmp_path, plane, axis, lines, atol):
    """Canned cycles in G18 (the cycle's axis Y: holes at X, Z) and G19 (axis X: holes at Y, Z),
    absolute and G91, continuation lines with and without a depth: the holes and R planes rs274
    drills for the rewritten program are the independent corrections of those it drills for
    the original (each hole on all three axes, the R plane along the cycle's axis), within half
    the written resolution (the resolution for the holes of one repeated G91 block)."""
    text = (
        "\n".join(
            [f"G21 G90 {plane} G98 F100", "G0 X300 Y100 Z10", *lines, "G80", "G90 G0 X300", "M2"]
        )
        + "\n"
    )
    before = run_rs274(rs274, tmp_path, text)
    bottoms, r_points = feeds(before)
    new, rows = gcode_rewrite(text, GENTLE)
    assert all(r.status == "corrected" for r in rows), [(r.line, r.reason) for r in rows]
    after = run_rs274(rs274, tmp_path, new)
    new_bottoms, new_r = feeds(after)
    assert len(new_bottoms) == len(bottoms)
    np.testing.assert_allclose(new_bottoms, corrected(GENTLE, bottoms), atol=atol + 1e-9)
    want_r = corrected(GENTLE, r_points)[:, axis]
    np.testing.assert_allclose(new_r[:, axis], want_r, atol=atol + 1e-9)
    assert np.abs(new_bottoms - bottoms).max() > 0.1


# ---------------------------------------------------------------- LinuxCNC's radius tolerance


def accepted(rs274, folder: Path, text: str) -> bool:
    path = folder / "tol.ngc"
    path.write_text(text)
    run = interpret(rs274, path)
    return run.returncode == 0 and "PROGRAM_END()" in run.stdout


@pytest.mark.parametrize(
    ("units", "end", "i", "ok"),
    [
        ("G21", "2.028", "1", True),  # 0.028 mm: within 2 * 0.01 * sqrt(2) mm
        ("G21", "2.029", "1", False),  # beyond it, and 2.8 % of the radius
        ("G21", "2000.99", "1000", True),  # 0.99 mm, but 0.099 % of the radius
        ("G21", "2001.01", "1000", False),  # 1.01 mm and 0.1009 %
        ("G20", "2.0028", "1", True),  # 0.0028 in: within 2 * 0.001 * sqrt(2) in
        ("G20", "2.0029", "1", False),
    ],
)
def test_linuxcnc_radius_tolerance(rs274, tmp_path, units, end, i, ok):
    """What rs274 (LinuxCNC's interp_arc.cc, arc_data_ijk) accepts of an I/J/K arc whose end
    radius differs from its start radius: refused only when the difference is more than
    2 * 0.01 * sqrt(2) mm (2 * 0.001 * sqrt(2) in) and more than 0.1 % of the larger radius.
    An arc of a small orbital hole (radius 1 mm) tolerates 0.028 mm: moving its end by a
    correction of some 0.3 mm without its start and centre would break it; the rigid shift
    keeps both radii exactly."""
    text = f"{units} G90 G17 F100\nG0 X0 Y0 Z0\nG2 X{end} Y0 I{i} J0\nM2\n"
    assert accepted(rs274, tmp_path, text) is ok


def test_a_small_arc_near_the_tolerance_keeps_its_radii(rs274, tmp_path):
    """A 1 mm arc whose end radius is already 0.028 mm off (as a CAM post may round it): moved
    rigidly, both radii stay as written and rs274 accepts it; its end moved alone by the same
    correction (start and centre kept) is refused."""
    text = "G21 G90 G17 F100\nG0 X299 Y100 Z-5\nG2 X301.028 Y100 I1 J0\nG0 Z5\nM2\n"
    assert accepted(rs274, tmp_path, text)
    arc = check_rigid(rs274, tmp_path, text)[0]
    assert radii(arc) == pytest.approx((1.0, 1.028), abs=1e-9)
    shift = corrected(GENTLE, [[300.0, 100.0, -5.0]])[0] - [300.0, 100.0, -5.0]
    moved = text.replace("X301.028 Y100", f"X{301.028 + shift[0]:.3f} Y{100 + shift[1]:.3f}")
    assert not accepted(rs274, tmp_path, moved)


# ---------------------------------------------------------------- any arc


@st.composite
def arc_programs(draw):
    """A program with one random arc or helix after the moves that set its start (300, 100,
    -10): plane, direction, I/J/K from the start, absolute (G90.1) or R format, G90 or G91
    end words, P turns, a radius of 1 to 40 mm."""
    plane = draw(st.sampled_from(["G17", "G18", "G19"]))
    a, b, h = PLANE_AXES[plane]
    radius = draw(st.sampled_from([1.0, 2.5, 7.0, 15.0, 40.0]))
    to_centre = draw(st.floats(0, 2 * np.pi))
    to_end = draw(st.floats(0, 2 * np.pi))
    form = draw(st.sampled_from(["ijk", "absolute", "r"]))
    start = np.array([300.0, 100.0, -10.0])
    centre, end = start.copy(), start.copy()
    centre[[a, b]] += radius * np.array([np.cos(to_centre), np.sin(to_centre)])
    end[[a, b]] = centre[[a, b]] + radius * np.array([np.cos(to_end), np.sin(to_end)])
    end[h] += draw(st.sampled_from([0.0, -2.0, -5.0]))
    end = np.round(end, 3)
    incremental = draw(st.booleans())
    values = end - start if incremental else end
    words = [f"{'XYZ'[k]}{values[k]:.3f}" for k in (a, b, h)]
    if form == "r":
        chord = np.hypot(*(end - start)[[a, b]])
        if chord < 0.5 or chord > 1.99 * radius:
            return None
        words.append(f"R{draw(st.sampled_from([1, -1])) * radius:.3f}")
    else:
        offset = centre if form == "absolute" else centre - start
        words += [f"{'IJK'[k]}{offset[k]:.3f}" for k in (a, b)]
        words.append(f"P{draw(st.sampled_from([1, 2]))}")
    arc = draw(st.sampled_from(["G2", "G3"]))
    mode = ("G91 " if incremental else "") + ("G90.1 " if form == "absolute" else "")
    return (
        f"G21 G90 {plane} F100\nG0 X300 Y100 Z5\nG1 Z-10\n{mode}{arc} {' '.join(words)}\n"
        "G90 G91.1 G0 Z20\nM2\n"
    )


@settings(max_examples=25, deadline=None)
@given(arc_programs())
def test_any_arc_moves_rigidly_or_stays(rs274, tmp_path_factory, text):
    """Whatever the arc: rs274 runs the rewritten program with the same commands; a corrected
    arc's start, centre and end moved by one shift written exactly, within the written 0.001 mm
    of the correction at its start, centre and end, its radii as before; an arc not corrected
    (its correction varies too much) is cut exactly as programmed."""
    if text is None:
        return
    folder = tmp_path_factory.mktemp("arc")
    if not accepted(rs274, folder, text):
        return  # rs274 refuses it as written (e.g. an R arc it cannot reach)
    before_out = run_rs274(rs274, folder, text)
    before = arcs_of(before_out)
    new, rows = gcode_rewrite(text, GENTLE)
    after_out = run_rs274(rs274, folder, new)
    assert commands(after_out) == commands(before_out)
    (old,), (arc,) = before, arcs_of(after_out)
    row = rows[2]
    keep = ~np.isnan(old["centre"])
    if row.status != "corrected":
        assert "correction varies by" in row.reason, row.reason
        for key in ("start", "end"):
            np.testing.assert_array_equal(arc[key], old[key])
        np.testing.assert_array_equal(arc["centre"][keep], old["centre"][keep])
        return
    shift = arc["end"] - old["end"]
    np.testing.assert_allclose(arc["start"] - old["start"], shift, atol=1e-9)
    np.testing.assert_allclose((arc["centre"] - old["centre"])[keep], shift[keep], atol=1e-9)
    np.testing.assert_allclose(shift, np.round(shift, 3), atol=1e-9)  # written exactly
    h = PLANE_AXES[old["plane"]][2]
    centre = old["centre"].copy()
    centre[h] = (old["start"][h] + old["end"][h]) / 2
    points = np.array([old["start"], old["end"], centre])
    np.testing.assert_allclose(corrected(GENTLE, points) - points, [shift] * 3, atol=1e-3 + 1e-9)
    assert radii(arc) == pytest.approx(radii(old), abs=1e-9)


def test_realworld_slot_arcs_move_rigidly(realworld, rs274, tmp_path):
    """LinuxCNC's vertical-slot.ngc (two passes of a slot: 8 arcs, each pass one chain at one
    depth) rewritten by the command line in a cell whose tool is the program's: all its arcs
    are corrected, and in rs274's reading each arc's start, centre and end moved by one shift,
    the same for every arc of the slot, with its radii exactly as before."""
    program = realworld / "gcode" / "pygcode_vertical-slot.ngc"
    cell = write_cell(tmp_path, field="smooth")
    # the program drills with T5 M06 G43: the cell's tool is tool 5
    cell.write_text(cell.read_text().replace("tool: {number: 1,", "tool: {number: 5,"))
    out, report_csv = tmp_path / "slot.ngc", tmp_path / "r.csv"
    argv = ["rewrite", program, "--cell", cell, "-o", out, "--report", report_csv]
    assert main([str(a) for a in [*argv, "--allow-partial"]]) == 0
    rows = [r for r in report(report_csv) if r["name"] in ("G2", "G3")]
    assert len(rows) == 8 and all(r["status"] == "corrected" for r in rows)

    # rs274 stops at a tool change (it has no tool table): read both without those lines
    def no_tool_change(text: str) -> str:
        return "".join(line for line in text.splitlines(True) if "M06" not in line)

    before = arcs_of(run_rs274(rs274, tmp_path, no_tool_change(program.read_text()), False))
    after = arcs_of(run_rs274(rs274, tmp_path, no_tool_change(out.read_text()), False))
    assert len(before) == len(after) == 8
    shifts = []
    for old, arc in zip(before, after, strict=True):
        shift = arc["end"] - old["end"]
        np.testing.assert_allclose(arc["start"] - old["start"], shift, atol=1e-9)
        np.testing.assert_allclose(arc["centre"][:2] - old["centre"][:2], shift[:2], atol=1e-9)
        assert radii(arc) == pytest.approx(radii(old), abs=1e-9)
        shifts.append(shift)
    np.testing.assert_allclose(shifts, [shifts[0]] * 8, atol=1e-9)
    assert np.abs(shifts[0]).max() > 0.1
