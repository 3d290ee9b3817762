"""Constructs of real CAM and controller programs that used to put holes in the wrong place, each
on its own minimal program: KSS 8 spline blocks with their own base, incremental (G91) canned
cycles, modal canned cycles that change depth, a dwell and a move on one line, a full circle.

Expected values come from the frame maths (a constant error field e = E_CONST: a corrected
position in a frame with rotation R is p + R^T e) and, for G-code, from LinuxCNC's ``rs274``
where it is installed; never from the code under test.
"""

from __future__ import annotations

import csv

import numpy as np
import pytest
from rewrite_helpers import E_CONST, write_cell
from scipy.spatial.transform import Rotation

from accugrid.codegen.cli import main
from accugrid.codegen.krl.parse import scan_krl

BASE2 = (100.0, 50.0, 0.0, 90.0, 0.0, 0.0)  # robot_T_base of BASE_DATA[2]
R2 = Rotation.from_euler("ZYX", BASE2[3:], degrees=True).as_matrix()


def rewrite(*args) -> int:
    return main(["rewrite", *map(str, args)])


def report(path) -> list[dict[str, str]]:
    return list(csv.DictReader(open(path, newline="")))


def numbers(line: str) -> list[float]:
    """X, Y, Z of a KRL aggregate line."""
    inner = line[line.index("{") + 1 : line.index("}")]
    parts = dict(p.strip().split(None, 1) for p in inner.split(","))
    return [float(parts[k]) for k in "XYZ"]


# ---------------------------------------------------------------- KSS 8 spline blocks

SPLINE_DAT = (
    "DEFDAT s\n"
    'DECL FDAT FS1={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE,POINT2[] " "}\n'
    "DECL E6POS XP1={X 220.000,Y 15.000,Z 40.000,A 0.0,B 90.0,C 0.0,S 6,T 27,E1 0.0}\n"
    "ENDDAT\n"
)


@pytest.mark.parametrize(
    "opening",
    [
        "SPLINE WITH $BASE = BASE_DATA[2]",
        "SPLINE WITH $BASE = SBASE(FS1.BASE_NO), $IPO_MODE = SIPO_MODE(FS1.IPO_FRAME)",
        "PTP_SPLINE WITH $BASE = BASE_DATA[2], $VEL_AXIS[1] = SVEL_JOINT(100.0)",
    ],
)
def test_spline_block_segments_move_in_the_blocks_base(tmp_path, opening):
    """The segments of a spline block are corrected in the block's base (BASE_DATA[2], rotated
    90 deg about Z), not in the base before it (0, the robot frame); after ENDSPLINE base 0
    holds again."""
    cell = write_cell(tmp_path, field="constant", base_data={2: BASE2})
    segment = "SPTP" if opening.startswith("PTP") else "SLIN"
    src = tmp_path / "s.src"
    lines = [
        "DEF s( )",
        "BAS (#BASE,0)",
        opening,
        f"  {segment} {{X 200.000,Y 0.000,Z 50.000,A 0.0,B 90.0,C 0.0}}",
        f"  {segment} XP1",
        "ENDSPLINE",
        "LIN {X 300.000,Y 0.000,Z 500.000,A 0.0,B 90.0,C 0.0}",
        "END",
    ]
    src.write_text("\n".join(lines) + "\n")
    (tmp_path / "s.dat").write_text(SPLINE_DAT)
    out = tmp_path / "out"
    assert (
        rewrite(src, tmp_path / "s.dat", "--cell", cell, "-o", out, "--report", tmp_path / "r.csv")
        == 0
    )
    new = (out / "s.src").read_text().splitlines()
    in_base2 = R2.T @ E_CONST  # the constant robot-frame error seen in base 2
    np.testing.assert_allclose(numbers(new[3]), [200.0, 0.0, 50.0] + in_base2, atol=6e-4)
    np.testing.assert_allclose(numbers(new[6]), [300.0, 0.0, 500.0] + E_CONST, atol=6e-4)
    xp1 = next(li for li in (out / "s.dat").read_text().splitlines() if "XP1=" in li)
    np.testing.assert_allclose(numbers(xp1), [220.0, 15.0, 40.0] + in_base2, atol=6e-4)
    assert all(row["status"] == "corrected" for row in report(tmp_path / "r.csv"))


def test_spline_block_whose_base_is_not_known_is_reported(tmp_path):
    cell = write_cell(tmp_path, field="constant")
    src = tmp_path / "u.src"
    text = (
        "DEF u( )\nBAS (#BASE,0)\nSPLINE WITH $BASE = lbase\n"
        "  SLIN {X 200.000,Y 0.000,Z 50.000,A 0.0,B 90.0,C 0.0}\n"
        "  SPL {X 210.000,Y 5.000,Z 50.000,A 0.0,B 90.0,C 0.0}\nENDSPLINE\n"
        "LIN {X 300.000,Y 0.000,Z 500.000,A 0.0,B 90.0,C 0.0}\nEND\n"
    )
    src.write_text(text)
    out = tmp_path / "u_out.src"
    assert rewrite(src, "--cell", cell, "-o", out, "--report", tmp_path / "r.csv") == 0
    rows = report(tmp_path / "r.csv")
    assert [(r["line"], r["status"]) for r in rows] == [
        ("4", "skipped"),
        ("5", "skipped"),
        ("7", "corrected"),
    ]
    for row in rows[:2]:
        assert "SPLINE block at line 3" in row["reason"] and "lbase" in row["reason"]
    assert out.read_text().splitlines()[:6] == text.splitlines()[:6]


def test_spline_block_base_is_the_same_in_every_reading_lane():
    """The whole-text lanes (rigid and regex lines between statements) and the line-by-line
    reader (lone CR line endings) give every segment the block's base."""
    lines = [
        "DEF s( )",
        "BAS (#BASE,0)",
        "SPLINE WITH $BASE = BASE_DATA[2]",
        "SLIN XP1",  # the rigid layout
        "SLIN  {X 1.0, Y 2.0, Z 3.0}",  # the regex lane
        "SCIRC {X 1.0,Y 2.0,Z 3.0}, {X 2.0,Y 3.0,Z 3.0}",  # the statement reader
        "ENDSPLINE",
        "SLIN XP1",
        "END",
    ]
    for sep in ("\n", "\r\n", "\r"):
        scan = scan_krl(sep.join(lines) + sep, "s.src")
        bases = [(p.line, p.base.number) for p in scan.positions]
        bases += [(u.line, u.base.number) for u in scan.uses]
        assert sorted(bases) == [(4, 2), (5, 2), (6, 2), (6, 2), (8, 0)], sep
