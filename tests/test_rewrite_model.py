"""accugrid rewrite with a calibrated model (--model, cell key correction.model)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np

from accugrid.app.cli import main
from accugrid.codegen.krl.parse import parse_krl
from accugrid.kinematics.frames import abc_to_matrix
from accugrid.kinematics.robot import load_robot

ROOT = Path(__file__).resolve().parents[1]
POINTS = ROOT / "examples" / "wing_panel_points.csv"
REALISTIC = resources.files("accugrid.kinematics").joinpath("robots", "kr210-realistic.yaml")


def _cell(tmp_path: Path) -> Path:
    """The example cell on the nominal kr210, with 5 decimals and no grid."""
    lines = []
    for line in (ROOT / "examples" / "cell.yaml").read_text().splitlines():
        if line.startswith("robot:"):
            line = "robot: kr210"
        elif line.startswith("grid:"):
            continue
        lines.append(line)
    text = "\n".join(lines) + "\n"
    text = text.replace("decimals: 3", "decimals: 5")
    path = tmp_path / "cell.yaml"
    path.write_text(text)
    return path


def _with_model(tmp_path: Path, model_name: str) -> Path:
    """Cell file whose correction: section names ``model_name`` (relative to the cell)."""
    cell = _cell(tmp_path)
    text = cell.read_text().replace("\ncorrection:\n", f"\ncorrection:\n  model: {model_name}\n")
    assert f"model: {model_name}" in text
    cell.write_text(text)
    return cell


def _calibrated(path: Path, text: str | None = None) -> Path:
    """kr210-realistic as a calibrated robot file whose identified TCP is the cell's tool."""
    text = REALISTIC.read_text() if text is None else text
    path.write_text(text + "tool: {x: 0, y: 0, z: 250, a: 0, b: 0, c: 0}\n")
    return path


def _krl_positions(path: Path) -> dict[str, np.ndarray]:
    """X, Y, Z, A, B, C (6,) of every E6POS declared in a .dat, by name."""
    return {
        p.name: np.array([p.x, p.y, p.z, p.a, p.b, p.c])
        for p in parse_krl(path.read_text(), path)
        if p.type == "E6POS"
    }


def test_rewrite_with_a_model_makes_the_calibrated_arm_reach_the_original_targets(tmp_path):
    cal = _calibrated(tmp_path / "cal.yaml")
    grid = tmp_path / "residual.csv"
    # the same arm measured without noise: the residual after the (exact) model is zero
    simulate = ["simulate", "--robot", "kr210-realistic", "--region", "1200", "2200", "-500"]
    simulate += ["500", "1100", "2100", "--step", "500", "--abc", "0", "90", "0", "--tool"]
    assert main([*simulate, "0", "0", "250", "0", "0", "0", "-o", str(grid)]) == 0
    cell_path = _with_model(tmp_path, "cal.yaml")
    src, dat = ROOT / "examples" / "cam_drill.src", ROOT / "examples" / "cam_drill.dat"
    out = tmp_path / "rw"
    argv = ["rewrite", str(src), str(dat), "--cell", str(cell_path), "--grid", str(grid)]
    assert main([*argv, "--decimals", "6", "--allow-partial", "-o", str(out)]) == 0
    before, after = _krl_positions(dat), _krl_positions(out / "cam_drill.dat")
    from accugrid.codegen.cell import load_cell

    cell = load_cell(cell_path)
    moved = [k for k in before if np.linalg.norm(after[k][:3] - before[k][:3]) > 0.5]
    assert moved == ["XH1_APP", "XH1"]  # the .dat's two hole positions
    rot, org = cell.robot_T_base[:3, :3], cell.robot_T_base[:3, 3]
    target = np.array([before[k][:3] for k in moved]) @ rot.T + org
    command = np.array([after[k][:3] for k in moved]) @ rot.T + org
    poses = np.tile(np.eye(4), (len(moved), 1, 1))
    poses[:, :3, :3] = rot @ abc_to_matrix(np.array([after[k][3:] for k in moved]))
    poses[:, :3, 3] = command
    sol = load_robot("kr210").with_tool(cell.flange_T_tool).ik(poses)
    assert sol.ok.all()
    reached = load_robot(cal).true_robot().fk(sol.q)[:, :3, 3]
    assert np.linalg.norm(reached - target, axis=1).max() < 1e-3


def test_rewrite_refuses_a_model_of_another_robot(tmp_path, capsys):
    text = REALISTIC.read_text().replace("a_mm: 350.0", "a_mm: 360.0", 1)
    _calibrated(tmp_path / "other.yaml", text)
    cell_path = _with_model(tmp_path, "other.yaml")
    src, dat = ROOT / "examples" / "cam_drill.src", ROOT / "examples" / "cam_drill.dat"
    out = tmp_path / "rw"
    grid = ROOT / "examples" / "grid_200mm.csv"
    argv = ["rewrite", str(src), str(dat), "--cell", str(cell_path), "--grid", str(grid)]
    assert main([*argv, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "other.yaml" in err and "\n" not in err
    assert not out.exists()
