"""A configuration change between holes names the axis that turns and its two angles."""

from __future__ import annotations

import re
import shutil

from conftest import EXAMPLES

from accugrid.codegen.cli import main


def test_a_forced_status_that_flips_a_wrist_axis_names_it(tmp_path, capsys):
    for name in ("cell.yaml", "grid_200mm.csv", "wing_panel_points.csv"):
        shutil.copy(EXAMPLES / name, tmp_path / name)
    cell = tmp_path / "cell.yaml"
    cell.write_text(cell.read_text().replace("  # status: 2 ", "  status: 2   "))
    argv = ["krl", tmp_path / "wing_panel_points.csv", "--cell", cell, "-o", tmp_path / "krl"]
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    found = re.search(r"A(\d) turns (\d+) deg from the previous pose \((\S+) to (\S+) deg;", err)
    assert found, err
    axis, turned, before, after = int(found[1]), int(found[2]), float(found[3]), float(found[4])
    assert axis in (4, 6)  # the wrist, not the arm: the Status fixes the arm
    assert abs(abs(after - before) - turned) <= 1 and turned > 180
    assert not (tmp_path / "krl").exists()
