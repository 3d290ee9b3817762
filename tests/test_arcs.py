"""Arcs and circles, each on its own minimal program: KRL ``CIRC``/``SCIRC`` auxiliary and end
points (points, each corrected at its own position).

Expected values are recomputed here from the grid's own interpolation of each point (``GridModel``
read from the grid file the cell names), never from the rewrite under test.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
from rewrite_helpers import write_cell

from accugrid.app.cli import main
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
