"""Shared inputs for the drilling-program tests: the example cell, its robot, a synthetic grid
with a known smooth error field, and point sets on the example panel."""

from __future__ import annotations

import csv
import dataclasses
import io
from functools import lru_cache
from pathlib import Path

import numpy as np

from accugrid.codegen.cell import load_cell
from accugrid.codegen.cell_record import Cell
from accugrid.codegen.points import parse_points
from accugrid.compensation import GridModel
from accugrid.infra.textsafe import fixed
from accugrid.kinematics.robot import load_robot

ROOT = Path(__file__).resolve().parents[1]
CELL = ROOT / "examples" / "cell.yaml"
POINTS = ROOT / "examples" / "wing_panel_points.csv"


def error_field(p: np.ndarray) -> np.ndarray:
    """A smooth, clearly non-constant error field e(P) (N, 3) mm for P (N, 3) mm (robot frame)."""
    u = (p - [1700.0, 0.0, 1600.0]) / 500.0
    return np.stack(
        [
            1.0 + 0.8 * u[:, 0] + 0.3 * u[:, 1] ** 2,
            -0.5 + 0.6 * u[:, 2],
            2.0 - 0.7 * u[:, 1] * u[:, 2],
        ],
        axis=1,
    )


@lru_cache(maxsize=1)
def grid() -> GridModel:
    """Synthetic grid over the demo region (step 200 mm), measured at A 0 B 90 C 0 in KUKA
    Status 6 (recorded, as simulate's column s)."""
    axes = [np.arange(1200, 2201, 200.0), np.arange(-600, 601, 200.0), np.arange(1100, 2101, 200.0)]
    commanded = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    measured = commanded - error_field(commanded)
    abc = np.tile([0.0, 90.0, 0.0], (len(commanded), 1))
    g = GridModel.from_measurements((commanded, measured, abc))
    return GridModel(g.origin, g.step, g.errors, g.orientation_abc, status=6)


@lru_cache(maxsize=1)
def cell() -> Cell:
    return load_cell(CELL)


def cell_with(c: Cell | None = None, **sections: dict) -> Cell:
    """The example cell (or ``c``) with fields of its section records changed, e.g.
    ``cell_with(drilling={"peck_mm": 2.0}, gcode={"canned_cycles": False})``."""
    c = cell() if c is None else c
    record = {**c.dialects, **{k: getattr(c, k) for k in sections if k not in c.dialects}}
    changed = {k: dataclasses.replace(record[k], **v) for k, v in sections.items()}
    dialects = {k: changed.pop(k, v) for k, v in c.dialects.items()}
    return dataclasses.replace(c, dialects=dialects, **changed)


@lru_cache(maxsize=1)
def robot():
    return load_robot(cell().robot_name).with_tool(cell().flange_T_tool)


def panel_csv(xy: np.ndarray, ids: list[str] | None = None, tilt: float = 4000.0) -> str:
    """Points CSV text for holes at base (x, y) (N, 2) on the example's curved skin (radius
    ``tilt`` mm about base Y), i,j,k into the skin."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["id", "x", "y", "z", "i", "j", "k", "diameter", "depth"])
    for n, (x, y) in enumerate(xy):
        z = np.sqrt(tilt**2 - (x - 287.5) ** 2) - tilt
        i, k = -(x - 287.5) / tilt, -(z + tilt) / tilt
        name = ids[n] if ids is not None else f"H{n + 1}"
        row = [fixed(x), fixed(y), fixed(z, 4), fixed(i, 6), "0", fixed(k, 6), "4.83", "7"]
        writer.writerow([name, *row])
    return out.getvalue()


def panel_points(xy: np.ndarray, ids: list[str] | None = None):
    return parse_points(panel_csv(xy, ids), "panel.csv")


def near_singular_wrist():
    """One hole 'SING-1' whose APP pose has A5 = 1 deg (A = 0, -90, 110, 0, 1, 0 deg) in the
    example cell, as parsed points (x, y, z, a, b, c), and that pose base_T_tcp (4, 4)."""
    from accugrid.kinematics.frames import xyzabc_from_pose

    c = cell()
    pose = robot().fk(np.radians([[0.0, -90.0, 110.0, 0.0, 1.0, 0.0]]))[0]
    base_T_tcp = np.linalg.inv(c.robot_T_base) @ pose
    # the hole point is the pose + approach along the tool axis (the APP stage is the pose)
    x = xyzabc_from_pose(base_T_tcp)
    hole = x[:3] + c.drilling.approach_mm * base_T_tcp[:3, 2]
    text = "id,x,y,z,a,b,c\nSING-1," + ",".join(f"{v:.6f}" for v in [*hole, *x[3:]]) + "\n"
    return parse_points(text, "s.csv"), base_T_tcp
