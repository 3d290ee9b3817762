"""The correction policy (compensation.policy) as every command applies it: the same verdict
and words in correct, krl, gcode and rewrite; no partial job without --allow-partial; Status,
tool and the model's region are part of the correction. Landings are checked independently:
the nominal controller's IK with the commanded tool, then the true arm's forward kinematics."""

from __future__ import annotations

import csv
import dataclasses
import os
import re
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import EXAMPLES
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from accugrid.app.cli import main
from accugrid.codegen.krl.parse import parse_krl
from accugrid.codegen.points import parse_points
from accugrid.codegen.program import build_program
from accugrid.compensation.grid import GridModel
from accugrid.compensation.policy import F_REGION, OUTSIDE_MODEL, Policy
from accugrid.compensation.settings import CorrectionSettings
from accugrid.kinematics.frames import abc_to_matrix, pose_from_xyzabc
from accugrid.kinematics.robot import load_robot
from accugrid.kinematics.validity import Validity

ROBOTS = resources.files("accugrid.kinematics").joinpath("robots")
DRILL = (0.0, 0.0, 250.0, 0.0, 0.0, 0.0)  # the cell's tool as taught
SMR = (15.0, -8.0, 310.0, 0.0, 0.0, 0.0)  # the SMR the model was identified with
NOMINAL = load_robot("kr210")
TOOL = ["--tool", *map(str, DRILL)]
PLAN_HEADER = "id,x,y,z,a,b,c,s,a1,a2,a3,a4,a5,a6\n"


def _cell(folder: Path, grid: str | None = None, model: str | None = None, status=None) -> Path:
    """A cell on kr210 whose base is the robot frame (BASE_DATA[1] = identity), the drill as
    tool, optionally a grid, a correction.model and a configuration.status."""
    lines = [
        "robot: kr210",
        "tool: {number: 1, x: 0, y: 0, z: 250, a: 0, b: 0, c: 0}",
        "base: {number: 1, x: 0, y: 0, z: 0, a: 0, b: 0, c: 0}",
        "program: {name: P, decimals: 6}",
    ]
    if grid is not None:
        lines.append(f"grid: {grid}")
    if model is not None:
        lines += ["correction:", f"  model: {model}"]
    if status is not None:
        lines += ["configuration:", f"  status: {status}"]
    path = folder / "cell.yaml"
    path.write_text("\n".join(lines) + "\n")
    return path


def _calibrated(path: Path, tcp=SMR) -> Path:
    """kr210-realistic as a calibrated file: its arm, the SMR as identified TCP and as the
    controller's tool of the measurements (identification.controller_tool)."""
    text = ROBOTS.joinpath("kr210-realistic.yaml").read_text()
    pose = ", ".join(f"{k}: {v}" for k, v in zip("xyzabc", tcp, strict=True))
    text += f"tool: {{{pose}}}\nidentification:\n  controller_tool: {{{pose}}}\n"
    path.write_text(text)
    return path


def _landed(arm_file: Path, commands, abc, status, tool=DRILL) -> np.ndarray:
    """Where the true arm puts ``tool``'s tip: the nominal controller with ``tool`` solves the
    commands (N, 3) mm at abc (N, 3) deg in KUKA ``status`` (int or (N,)), robot frame."""
    tcp = pose_from_xyzabc(np.array(tool))
    poses = np.tile(np.eye(4), (len(commands), 1, 1))
    poses[:, :3, :3], poses[:, :3, 3] = abc_to_matrix(np.asarray(abc, float)), commands
    sol = NOMINAL.with_tool(tcp).ik(poses, status=status)
    assert sol.ok.all()
    return load_robot(arm_file).true_robot().with_tool(tcp).fk(sol.q)[:, :3, 3]


def _grid(folder: Path, robot: str = "kr210-realistic", status: int = 6, name="grid.csv") -> Path:
    """A noise-free grid measurement of ``robot`` with the drill in ``status`` (column s)."""
    path = folder / name
    argv = ["simulate", "--robot", robot, "--region", "1300", "1900", "-400", "400", "1200"]
    argv += ["1800", "--step", "300", "--abc", "0", "90", "0", "--status", str(status)]
    argv += ["--noise-tracker", "0", "--noise-repeat", "0", "--tool", *map(str, DRILL)]
    assert main([*argv, "-o", str(path)]) == 0
    return path


def _rows(path: Path) -> list[dict]:
    return list(csv.DictReader(line for line in path.open() if not line.startswith("#")))


def test_krl_model_lands_the_drill_tip_not_the_smr(tmp_path, capsys):
    # finding: krl --model used the model's TCP (the SMR) instead of the cell's drill
    cal = _calibrated(tmp_path / "cal.yaml")
    points = tmp_path / "p.csv"
    points.write_text("id,x,y,z,a,b,c\nH1,1500,100,1400,0,90,0\nH2,1600,-100,1500,10,80,0\n")
    out = tmp_path / "krl"
    cell = _cell(tmp_path, model="cal.yaml", status=6)
    assert main(["krl", str(points), "--cell", str(cell), "-o", str(out)]) == 0, (
        capsys.readouterr().err
    )
    from accugrid.codegen.cell import load_cell

    c = load_cell(cell)
    robot = NOMINAL.with_tool(c.flange_T_tool)
    pts = parse_points(points.read_text(), "p.csv")
    program = build_program(pts, c, robot, model=load_robot(cal))
    command = pts.xyz + program.correction  # the hole point's command, robot frame
    target = pts.xyz
    landed = _landed(cal, command, pts.abc, 6)
    assert np.linalg.norm(landed - target, axis=1).max() < 1e-3
    # the old rule (the controller with the drill, the arm carrying the model's TCP, the SMR)
    # would command something else entirely
    from accugrid.compensation.model_correction import model_correct

    drill = pose_from_xyzabc(np.array(DRILL))
    old = model_correct(load_robot(cal), pts.xyz, pts.abc, 6, controller_tool=drill)
    assert np.linalg.norm(old.command - command, axis=1).min() > 10.0
    # the written .dat holds these numbers: the hole point is on the drill axis between the
    # APP and BOT positions, each moved by the same correction
    dat = next(out.glob("*.dat"))
    written = np.array([[p.x, p.y, p.z] for p in parse_krl(dat.read_text(), dat.name)])
    axis_point = written - command[0]
    along = np.cross(axis_point, abc_to_matrix(pts.abc[0])[:, 2])
    assert (np.linalg.norm(along, axis=1) < 1e-4).sum() >= 3  # H1's positions


def test_rewrite_model_corrects_each_krl_position_in_its_own_status(tmp_path, capsys):
    # finding: rewrite --model gave S 6 and S 2 of one point the same numbers (S 2 missed)
    cal = _calibrated(tmp_path / "cal.yaml")
    src = tmp_path / "job.src"
    pose = "X 1500.0,Y 100.0,Z 1400.0,A 0.0,B 90.0,C 0.0"
    src.write_text(
        f"DEF job( )\n$BASE=BASE_DATA[1]\nLIN {{{pose},S 6,T 27}}\n"
        f"LIN {{{pose},S 'B010',T 35}}\nEND\n"
    )
    cell = _cell(tmp_path, model="cal.yaml")
    out, report = tmp_path / "out.src", tmp_path / "r.csv"
    argv = ["rewrite", str(src), "--cell", str(cell), "-o", str(out), "--decimals", "6"]
    assert main([*argv, "--report", str(report)]) == 0, capsys.readouterr().err
    rows = _rows(report)
    assert [r["status"] for r in rows] == ["corrected", "corrected"]
    new = np.array([[float(r[k]) for k in ("x_new", "y_new", "z_new")] for r in rows])
    assert np.linalg.norm(new[0] - new[1]) > 0.1  # each in its own Status
    landed = _landed(cal, new, np.zeros((2, 3)) + [0.0, 90.0, 0.0], np.array([6, 2]))
    assert np.abs(landed - [1500.0, 100.0, 1400.0]).max() < 1e-3


def test_krl_status_words_are_read_per_aggregate():
    from accugrid.codegen.krl.rewrite import aggregate_status

    text = (
        "LIN {X 1,S 6,T 2} ; {S 3}\nDECL E6POS P={X 1,Y 2,S 'B010'}\nLIN {X 2}\nLIN {X 3, s 'H5'}\n"
    )
    agg = np.array([text.index("{"), text.index("={") + 1, text.index("{X 2"), text.index("{X 3")])
    assert aggregate_status(text, agg).tolist() == [6, 2, -1, 5]


_STATUS_WORD = re.compile(r"[{,]\s*S\s+(?:'B([01]+)'|'H([0-9A-F]+)'|(\d+))", re.IGNORECASE)


def test_krl_status_words_past_int64_read_as_the_largest_int64():
    from accugrid.codegen.krl.rewrite import aggregate_status

    top = 2**63 - 1
    text = "{S 9223372036854775806}{S 99999999999999999999}"
    text += "{S 'H7FFFFFFFFFFFFFFF'}{S 'HFFFFFFFFFFFFFFFFF'}"
    agg = np.array([i for i, c in enumerate(text) if c == "{"])
    assert aggregate_status(text, agg).tolist() == [top - 1, top, top, top]


# texts of S words and near misses: what may stand before the S, blanks, S, blanks, a word
_BLANKS = st.sampled_from(["", " ", "  ", "\t\n", "\x1c", "\xa0"])
_STATUS_TEXT = st.lists(
    st.tuples(
        st.sampled_from(["{", ",", "}", ";", "X 1", ""]),
        _BLANKS,
        st.sampled_from(["S", "s", "X"]),
        _BLANKS,
        st.sampled_from(
            ["7", "12", "'B101'", "'b01'", "'H1aF'", "'h9'", "'B12'", "'Hg'", "'", "}", ""]
        ),
    ).map("".join),
    max_size=6,
).map("".join)


@settings(max_examples=300, deadline=None)
@given(_STATUS_TEXT, st.data())
def test_krl_status_words_read_as_the_pattern_reads_them(text, data):
    # reference: the grammar as a regular expression, each match (non-overlapping, in text
    # order) given to the aggregate whose "{" is the last at or before it, if before its "}"
    from accugrid.codegen.krl.rewrite import aggregate_status

    opens = [i for i, c in enumerate(text) if c == "{"]
    agg = data.draw(st.lists(st.sampled_from(opens), unique=True) if opens else st.just([]))
    want = [-1] * len(agg)
    for m in _STATUS_WORD.finditer(text):
        b, h, d = m.groups()
        value = int(b, 2) if b else int(h, 16) if h else int(d)
        owner = max((a for a in agg if a <= m.start()), default=None)
        if owner is not None and "}" not in text[owner : m.start()]:
            want[agg.index(owner)] = value
    assert aggregate_status(text, np.array(agg, np.int64)).tolist() == want


def test_grid_only_rewrite_leaves_a_position_in_another_status_and_says_why(tmp_path, capsys):
    # finding: grid-only rewrite corrected an S 2 position with a Status-6 grid, unflagged
    grid = _grid(tmp_path)
    src = tmp_path / "job.src"
    text = (
        "DEF job( )\n$BASE=BASE_DATA[1]\nLIN {X 1500.0,Y 100.0,Z 1400.0,A 0.0,B 90.0,C 0.0,S 6}\n"
        "LIN {X 1500.0,Y 100.0,Z 1450.0,A 0.0,B 90.0,C 0.0,S 2}\nEND\n"
    )
    src.write_text(text)
    cell = _cell(tmp_path, grid=grid.name)
    out, report = tmp_path / "out.src", tmp_path / "r.csv"
    argv = ["rewrite", str(src), "--cell", str(cell), "-o", str(out), "--report", str(report)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "job.src:4: 1 position(s) cannot be corrected (1 another Status than the grid's)" in err
    assert "in KUKA Status 2: the grid holds only in Status 6" in err
    assert not out.exists() and not report.exists()
    assert main([*argv, "--allow-partial"]) == 0
    assert "1 position(s) left uncorrected (1 another Status than the grid's)" in (
        capsys.readouterr().err
    )
    lines = out.read_text().splitlines()
    assert lines[3] == text.splitlines()[3]  # byte-identical
    assert lines[2] != text.splitlines()[2]
    rows = _rows(report)
    assert rows[1]["status"] == "skipped" and "Status 2" in rows[1]["reason"]


def test_a_status_6_residual_grid_is_refused_for_status_2(tmp_path, capsys):
    # finding: correct --model --status 2 applied a Status-6 residual grid (0.7 mm off)
    grid = _grid(tmp_path, robot="kr210-paper")
    points = tmp_path / "p.csv"
    points.write_text("id,x,y,z,a,b,c\nH1,1500,100,1400,0,90,0\n")
    out = tmp_path / "o.csv"
    argv = ["correct", str(points), "--model", "kr210-paper", "--grid", str(grid), *TOOL]
    argv += ["-o", str(out)]
    assert main([*argv, "--status", "2"]) == 2
    err = capsys.readouterr().err
    assert "1 another Status than the grid's" in err
    assert "in KUKA Status 2: the residual grid holds only in Status 6" in err
    assert main([*argv, "--status", "6"]) == 0  # its own Status
    assert main([*argv, "--status", "2", "--allow-partial", "--force"]) == 0
    assert _rows(out)[0]["flag"].startswith("not corrected: in KUKA Status 2")


def test_a_grid_records_its_status_and_one_in_two_statuses_is_refused(tmp_path):
    grid = _grid(tmp_path, robot="kr210-paper", status=6)
    assert _rows(grid)[0]["s"] == "6"
    from accugrid.compensation import GridModel
    from accugrid.infra.errors import InputError

    assert GridModel.from_measurements(grid).status == 6
    lines = grid.read_text().splitlines()
    header = lines[1].split(",")
    s = header.index("s")
    row = lines[5].split(",")
    row[s] = "2"
    lines[5] = ",".join(row)
    mixed = tmp_path / "mixed.csv"
    mixed.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match="one KUKA Status: column s is 2 here, 6 in the first"):
        GridModel.from_measurements(mixed)


def test_a_tilted_hole_gets_the_same_verdict_and_words_in_every_command(tmp_path, capsys):
    # finding: a 29 deg hole was written by krl (warning), refused by correct, skipped by rewrite
    grid = _grid(tmp_path, robot="kr210-paper")
    cell = _cell(tmp_path, grid=grid.name, status=6)
    points = tmp_path / "p.csv"
    points.write_text("id,x,y,z,a,b,c\nT29,1500,100,1400,0,61,0\n")
    words = "orientation 29.0 deg from the grid's 0.000, 90.000, 0.000 deg, beyond the limit"
    src = tmp_path / "t.src"
    src.write_text("DEF t( )\n$BASE=BASE_DATA[1]\nLIN {X 1500,Y 100,Z 1400,A 0,B 61,C 0}\nEND\n")
    runs = {
        "correct": ["correct", str(points), "--grid", str(grid), "-o", str(tmp_path / "c.csv")],
        "krl": ["krl", str(points), "--cell", str(cell), "-o", str(tmp_path / "k")],
        "gcode": ["gcode", str(points), "--cell", str(cell), "-o", str(tmp_path / "g.ngc")],
        "rewrite": ["rewrite", str(src), "--cell", str(cell), "-o", str(tmp_path / "r.src")],
    }
    for name, argv in runs.items():
        assert main(argv) == 2, name
        err = capsys.readouterr().err
        assert "cannot be corrected (1 orientation beyond the limit)" in err, name
        assert words in err, name


def test_krl_allow_partial_marks_the_uncorrected_hole_in_the_header(tmp_path, capsys):
    grid = _grid(tmp_path, robot="kr210-paper")
    cell = _cell(tmp_path, grid=grid.name, status=6)
    points = tmp_path / "p.csv"
    points.write_text("id,x,y,z,a,b,c\nIN,1500,100,1400,0,90,0\nOUT,1500,100,1900,0,90,0\n")
    out = tmp_path / "k"
    argv = ["krl", str(points), "--cell", str(cell), "-o", str(out)]
    assert main(argv) == 2
    assert "hole 'OUT' (" in capsys.readouterr().err and not out.exists()
    assert main([*argv, "--allow-partial"]) == 0
    err = capsys.readouterr().err
    assert "1 hole(s) cannot be corrected (1 outside the grid): written uncorrected" in err
    src = next(out.glob("*.src")).read_text()
    assert "; not corrected: hole OUT: outside the grid box by 100.000 mm" in src


def test_a_half_corrected_real_program_fails_unless_allow_partial(realworld, tmp_path, capsys):
    # finding: a CAM program came back with some holes corrected and its plunges not, exit 0
    from tests.rewrite_helpers import write_cell

    program = realworld / "gcode" / "norn93_1_heatsink_drill.gcode"
    # a grid over the part's top 100 mm only: the holes' first positions in it, the rest not
    cell = write_cell(tmp_path, lower=(-500, -500, -100), upper=(500, 500, 0), step=100.0)
    out, report = tmp_path / "o.gcode", tmp_path / "r.csv"
    argv = ["rewrite", str(program), "--cell", str(cell), "-o", str(out), "--report", str(report)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "position(s) cannot be corrected (" in err
    assert f"{program}:" in err and not out.exists() and not report.exists()
    assert main([*argv, "--allow-partial"]) == 0
    err = capsys.readouterr().err
    assert "left uncorrected (" in err
    rows = _rows(report)
    left = [r for r in rows if r["status"] != "corrected"]
    assert left and all(r["reason"] for r in left)
    assert any(r["status"] == "corrected" for r in rows)


def test_a_rewrite_that_corrects_nothing_is_an_error(tmp_path, capsys):
    grid = _grid(tmp_path, robot="kr210-paper")
    cell = _cell(tmp_path, grid=grid.name)
    src = tmp_path / "j.src"
    src.write_text("DEF j( )\nPTP {A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0}\nEND\n")
    argv = ["rewrite", str(src), "--cell", str(cell), "-o", str(tmp_path / "o.src")]
    assert main(argv) == 2
    assert "no position corrected" in capsys.readouterr().err
    assert main([*argv, "--allow-partial"]) == 0
    assert (tmp_path / "o.src").read_bytes() == src.read_bytes()


def test_correct_model_flags_the_wrist_singularity_as_krl_does(tmp_path, capsys):
    # a point whose command has |A5| of about 1 deg (A = 0, -90, 110, 0, 1, 0 deg)
    tcp = pose_from_xyzabc(np.array(DRILL))
    from accugrid.kinematics.frames import xyzabc_from_pose

    x = xyzabc_from_pose(NOMINAL.with_tool(tcp).fk(np.radians([[0, -90, 110, 0, 1, 0]]))[0])
    points = tmp_path / "p.csv"
    points.write_text("id,x,y,z,a,b,c\nS," + ",".join(f"{v:.4f}" for v in x) + "\n")
    out = tmp_path / "o.csv"
    argv = ["correct", str(points), "--model", "kr210-paper", "--tool", *map(str, DRILL)]
    assert main([*argv, "-o", str(out)]) == 0
    flag = _rows(out)[0]["flag"]
    assert "deg, within 5 deg of the wrist singularity" in flag and flag.startswith("|A5| ")


def test_identify_records_where_the_model_holds_and_targets_outside_are_flagged(tmp_path, capsys):
    # finding: a model identified in a small region was applied anywhere, unflagged
    rng = np.random.default_rng(2)
    xyz = rng.uniform([1600, -100, 1400], [1800, 100, 1600], (40, 3))
    abc = np.array([0.0, 90.0, 0.0]) + rng.uniform(-8, 8, (40, 3))
    body = "".join(
        f"P{i},{','.join(f'{v:.3f}' for v in (*p, *a))},6,,,,,,\n"
        for i, (p, a) in enumerate(zip(xyz, abc, strict=True))
    )
    plan, meas, cal = tmp_path / "plan.csv", tmp_path / "meas.csv", tmp_path / "cal.yaml"
    plan.write_text(PLAN_HEADER + body)
    sim = ["simulate", "--robot", "kr210-paper", "--poses", str(plan), *TOOL, "-o", str(meas)]
    assert main(sim) == 0
    assert main(["identify", str(meas), "--robot", "kr210", *TOOL, "-o", str(cal)]) == 0
    record = yaml.safe_load(cal.read_text())["identification"]["validity"]
    assert set(record) == {
        "box_min_mm",
        "box_max_mm",
        "tool_axis",
        "tilt_deg",
        "joints_deg",
        "validated_max_mm",
    }
    np.testing.assert_allclose(record["box_min_mm"], xyz.min(axis=0), atol=1e-3)
    np.testing.assert_allclose(record["box_max_mm"], xyz.max(axis=0), atol=1e-3)
    targets = tmp_path / "t.csv"
    inside = xyz.mean(axis=0)
    far = [1300.0, 400.0, 1900.0]
    targets.write_text(
        "id,x,y,z,a,b,c\n"
        + f"IN,{inside[0]:.3f},{inside[1]:.3f},{inside[2]:.3f},0,90,0\n"
        + f"FAR,{far[0]},{far[1]},{far[2]},0,90,0\n"
    )
    out = tmp_path / "o.csv"
    argv = ["correct", str(targets), "--model", str(cal), *TOOL, "--status", "6", "-o", str(out)]
    assert main(argv) == 0
    flags = [r["flag"] for r in _rows(out)]
    gap = np.linalg.norm(
        np.maximum(np.array(record["box_min_mm"]) - far, 0)
        + np.maximum(np.array(far) - record["box_max_mm"], 0)
    )
    assert flags[0] == ""
    assert flags[1].startswith(
        f"outside the poses the model was identified from ({gap:.1f} mm from their region"
    )
    assert main([*argv, "--strict", "--force"]) == 2
    err = capsys.readouterr().err
    assert "1 outside the model's poses" in err and "hole 'FAR'" in err
    # a misspelt key of the record is a located error, never a silently dropped bound
    text = cal.read_text().replace("    tilt_deg:", "    tilt_dg:", 1)
    assert "tilt_dg" in text
    cal.write_text(text)
    assert main([*argv, "--force"]) == 2
    err = capsys.readouterr().err
    assert "cal.yaml:" in err
    assert "identification.validity.tilt_dg: unknown key; did you mean tilt_deg?" in err


def test_validity_measures_the_distance_tilt_and_joint_excess():
    v = Validity(
        np.array([0.0, 0.0, 0.0]),
        np.array([10.0, 10.0, 10.0]),
        np.array([0.0, 0.0, 1.0]),
        10.0,
        np.tile([-10.0, 10.0], (6, 1)),
    )
    points = np.array([[5.0, 5.0, 5.0], [13.0, 14.0, 5.0]])
    tilt = np.radians(25.0)
    rot = np.array(
        [np.eye(3), [[1, 0, 0], [0, np.cos(tilt), -np.sin(tilt)], [0, np.sin(tilt), np.cos(tilt)]]]
    )
    q = np.radians([[0, 0, 0, 0, 0, 0], [0, 0, 12.5, 0, 0, 0]])
    box, over, joint, axis = v.excess(points, rot, q)
    np.testing.assert_allclose(box, [0.0, 5.0])
    np.testing.assert_allclose(over, [0.0, 15.0])
    np.testing.assert_allclose(joint, [0.0, 2.5])
    assert axis.tolist() == [0, 3]
    # the policy flags (default) or refuses (strict) a target outside, with the distance
    targets = np.array([[1500.0, 100.0, 1400.0]])
    rot90 = abc_to_matrix(np.array([[0.0, 90.0, 0.0]]))
    far = Validity(
        targets[0] + 50, targets[0] + 60, rot90[0][:, 2], 0.0, np.tile([-360, 360], (6, 1))
    )
    model = load_robot("kr210-paper")
    flagged = Policy(CorrectionSettings(), None, model, 6, validity=far).decide(targets, rot90)
    assert flagged.corrected.all() and flagged.flags[0] & F_REGION
    assert flagged.reason(0).endswith(f"({np.sqrt(3) * 50:.1f} mm from their region)")
    strict = Policy(CorrectionSettings(), None, model, 6, validity=far, strict=True)
    refused = strict.decide(targets, rot90)
    assert refused.code[0] == OUTSIDE_MODEL and (refused.command == targets).all()


@st.composite
def _programs(draw):
    """A KRL .src of 1..6 LIN positions: each inside or outside the residual grid, at a tilt
    of 0..25 deg about X, in KUKA Status 6 or 2."""
    n = draw(st.integers(1, 6))
    rows = []
    for _ in range(n):
        x = draw(st.floats(1350, 1850))
        y = draw(st.floats(-350, 350))
        z = draw(st.floats(1250, 1950))  # above 1800: outside the grid
        c = draw(st.sampled_from([0.0, 3.0, 10.0, 20.0, 25.0]))
        s = draw(st.sampled_from([6, 2]))
        rows.append((round(x, 3), round(y, 3), round(z, 3), c, s))
    return rows


@pytest.fixture(scope="module")
def property_set_up(tmp_path_factory):
    folder = tmp_path_factory.mktemp("property")
    cal = _calibrated(folder / "cal.yaml")
    grid = _grid(folder)  # the true arm (the model's) with the drill, Status 6, no noise
    cell = _cell(folder, grid=grid.name, model="cal.yaml")
    return folder, cal, cell


@settings(max_examples=15, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=_programs())
def test_property_every_corrected_position_lands_and_every_other_is_kept_with_a_reason(
    property_set_up, rows
):
    """Every position rewrite writes as corrected lands within 0.01 mm of its target under the
    model it was corrected with (the drill's tip on the calibrated arm, its own Status); every
    other position is byte-identical and reported with a reason."""
    folder, cal, cell = property_set_up
    lines = ["DEF job( )", "$BASE=BASE_DATA[1]"]
    lines += [f"LIN {{X {x},Y {y},Z {z},A 0,B 90,C {c},S {s}}}" for x, y, z, c, s in rows]
    text = "\n".join([*lines, "END"]) + "\n"
    src = folder / "job.src"
    src.write_text(text)
    out, report = folder / "out.src", folder / "r.csv"
    argv = ["rewrite", str(src), "--cell", str(cell), "-o", str(out), "--report", str(report)]
    assert main([*argv, "--allow-partial", "--decimals", "6", "--force"]) == 0
    written = out.read_text().splitlines()
    report_rows = _rows(report)
    assert len(report_rows) == len(rows)
    for k, (row, (x, y, z, c, s)) in enumerate(zip(report_rows, rows, strict=True)):
        if row["status"] == "corrected":
            new = np.array([[float(row[key]) for key in ("x_new", "y_new", "z_new")]])
            landed = _landed(cal, new, [[0.0, 90.0, c]], s)
            assert np.abs(landed - [x, y, z]).max() < 0.01
            assert written[2 + k] != lines[2 + k]
        else:
            assert written[2 + k] == lines[2 + k]
            assert row["reason"]
            if s == 2:
                assert "Status 2" in row["reason"] or "outside" in row["reason"]


def test_policy_words_are_the_same_through_the_api_and_the_cli(tmp_path, capsys):
    grid = _grid(tmp_path, robot="kr210-paper")
    from accugrid.compensation import GridModel

    policy = Policy.build(CorrectionSettings(), GridModel.from_measurements(grid))
    verdict = policy.decide(np.array([[1500.0, 100.0, 1900.0]]), status=6)
    assert verdict.reason(0) == "outside the grid box by 100.000 mm"
    points = tmp_path / "p.csv"
    points.write_text("id,x,y,z,s\nH,1500,100,1900,6\n")
    argv = ["correct", str(points), "--grid", str(grid), "-o", str(tmp_path / "o.csv")]
    assert main(argv) == 2
    assert f": {verdict.reason(0)} (--allow-partial" in capsys.readouterr().err


def test_a_corrected_hole_that_takes_another_status_is_refused():
    # configuration.allow_change lets a hole take another Status; its correction was made for
    # the program's Status only (grid or model), so a corrected hole may not change
    from accugrid.codegen import program as program_module
    from accugrid.infra.errors import InputError
    from tests.program_helpers import cell_with, panel_points, robot

    c = cell_with(configuration={"status": 0, "allow_change": True})
    pts = panel_points([(0.0, 100.0), (250.0, 300.0)])
    uncorrected = build_program(pts, c, robot(), None)  # no correction: they may change
    assert (uncorrected.configuration.code != 0).any()
    positions, rotations = uncorrected.positions, uncorrected.rotations
    correction = np.full((len(pts), 3), 0.5)
    with pytest.raises(
        InputError, match=r"takes KUKA Status \d \(configuration.allow_change\), but"
    ):
        program_module._configuration(pts, c, robot(), positions, rotations, 0, None, 0, correction)


def test_rewrite_allow_partial_marks_uncorrected_positions_in_the_header(tmp_path, capsys):
    grid = _grid(tmp_path, robot="kr210-paper")
    cell = _cell(tmp_path, grid=grid.name)
    src = tmp_path / "h.src"
    src.write_text(
        "DEF h( )\n$BASE=BASE_DATA[1]\nLIN {X 1500,Y 100,Z 1400,A 0,B 90,C 0,S 6}\n"
        "LIN {X 1500,Y 100,Z 1900,A 0,B 90,C 0,S 6}\nEND\n"
    )
    out = tmp_path / "o.src"
    argv = ["rewrite", str(src), "--cell", str(cell), "-o", str(out), "--header"]
    assert main([*argv, "--allow-partial"]) == 0
    text = out.read_text()
    assert "; not corrected: line 4 LIN: outside the grid box by 100.000 mm" in text
    assert "; positions corrected 1" in text


def test_rewrite_strict_without_a_model_says_outside_positions_are_refused_by_default(
    tmp_path, capsys
):
    grid = _grid(tmp_path, robot="kr210-paper")
    cell = _cell(tmp_path, grid=grid.name)
    src = tmp_path / "s.src"
    src.write_text("DEF s( )\n$BASE=BASE_DATA[1]\nLIN {X 1500,Y 100,Z 1900,A 0,B 90,C 0}\nEND\n")
    argv = ["rewrite", str(src), "--cell", str(cell), "-o", str(tmp_path / "o.src"), "--strict"]
    assert main(argv) == 2  # the old spelling keeps refusing a position outside the grid
    err = capsys.readouterr().err
    assert "note: --strict is no longer needed for positions outside the grid" in err
    assert "1 outside the grid" in err


def test_gcode_positions_take_the_cells_status_against_the_grids(tmp_path, capsys):
    grid = _grid(tmp_path, robot="kr210-paper")
    ngc = tmp_path / "p.ngc"
    ngc.write_text("G90 G21\nG1 X1500 Y100 Z1400 F100\nM2\n")  # program frame = base = robot
    out = tmp_path / "o.ngc"
    for status, code in ((6, 0), (2, 2)):
        cell = _cell(tmp_path, grid=grid.name, status=status)
        assert main(["rewrite", str(ngc), "--cell", str(cell), "-o", str(out), "--force"]) == code
        err = capsys.readouterr().err
        if code:
            assert "in KUKA Status 2: the grid holds only in Status 6" in err


@st.composite
def _jobs(draw):
    """A random smooth error field on a random regular grid (Status 6, A 0 B 90 C 0), a model
    or none, and 1..8 targets inside or outside it, tilted 0..25 deg, in Status 6 or 2."""
    origin = np.array([draw(st.floats(1300, 1500)), draw(st.floats(-400, -200)), 1250.0])
    step = np.array([draw(st.floats(100, 250)) for _ in range(3)])
    coeff = np.array([[draw(st.floats(-1e-3, 1e-3)) for _ in range(3)] for _ in range(3)])
    offset = np.array([draw(st.floats(-1.0, 1.0)) for _ in range(3)])
    model = draw(st.sampled_from([None, "kr210-paper"]))
    n = draw(st.integers(1, 8))
    u = np.array([[draw(st.floats(-0.2, 1.2)) for _ in range(3)] for _ in range(n)])
    tilt = np.array([draw(st.sampled_from([0.0, 4.0, 12.0, 20.0])) for _ in range(n)])
    status = np.array([draw(st.sampled_from([6, 2])) for _ in range(n)])
    return origin, step, coeff, offset, model, u, tilt, status


@settings(max_examples=30)
@given(job=_jobs())
def test_property_the_policy_corrects_exactly_or_leaves_the_target_with_a_reason(job):
    """Over random grids, models and targets: a corrected target lands within 0.01 mm under
    the correction it was made with (the grid's errors, or the calibrated arm carrying the
    drill in the target's own Status plus the residual grid); any other is left as it is with
    a reason, the grid's Status and box among them."""
    origin, step, coeff, offset, model, u, tilt, status = job
    from accugrid.compensation import GridModel

    axes = [origin[a] + step[a] * np.arange(3) for a in range(3)]
    vertices = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    field = offset + (vertices - origin) @ coeff  # a smooth field, mm
    abc = np.tile([0.0, 90.0, 0.0], (len(vertices), 1))
    drill = pose_from_xyzabc(np.array(DRILL))
    settings_ = CorrectionSettings(method="trilinear", iterations=4)
    targets = origin + u * 2 * step
    rotations = np.array([abc_to_matrix(np.array([0.0, 90.0, c])) for c in tilt])
    if model is None:  # the grid measured the arm's error field e = P - M
        measured = GridModel.from_measurements((vertices, vertices - field, abc))
        grid = GridModel(
            measured.origin, measured.step, measured.errors, measured.orientation_abc, status=6
        )
        policy = Policy.build(settings_, grid)
    else:  # the arm is the model plus the field the residual grid measured
        arm = load_robot(model).with_tool(drill)
        poses = np.tile(np.eye(4), (len(vertices), 1, 1))
        poses[:, :3, :3], poses[:, :3, 3] = abc_to_matrix(abc), vertices
        sol = NOMINAL.with_tool(drill).ik(poses, status=6)
        reach = arm.true_robot().fk(sol.q)[:, :3, 3]
        measured = GridModel.from_measurements((vertices, reach - field * 0.1, abc))
        grid = GridModel(
            measured.origin, measured.step, measured.errors, measured.orientation_abc, status=6
        )
        policy = Policy.build(settings_, grid, load_robot(model), None, (drill, drill))
    verdict = policy.decide(targets, rotations, status=status)
    done = verdict.corrected
    reasons = verdict.reasons()
    assert all(reasons[i] for i in np.flatnonzero(~done))
    np.testing.assert_array_equal(verdict.command[~done], targets[~done])
    assert not (done & (status != 6)).any()  # the grid holds in Status 6 only
    inside = ((targets >= grid.origin - 1e-6) & (targets <= grid.upper + 1e-6)).all(axis=1)
    assert not (done & ~inside).any()
    if not done.any():
        return
    command = verdict.command[done]
    if model is None:  # the arm commits the grid's error at the command: M = P' - e(P')
        errors = GridModel.from_measurements((vertices, vertices - field, abc))
        # (at the nearest box point where a command steps out of the box, as the correction)
        landed = command - errors.predict(command, "trilinear", outside="clamp")
        assert np.abs(landed - targets[done]).max() < 0.01
        return
    poses = np.tile(np.eye(4), (len(command), 1, 1))
    poses[:, :3, :3], poses[:, :3, 3] = rotations[done], command
    sol = NOMINAL.with_tool(drill).ik(poses, status=status[done])
    assert sol.ok.all()
    landed = arm.true_robot().fk(sol.q)[:, :3, 3] - 0.1 * (
        offset + (targets[done] - origin) @ coeff
    )  # the arm less the field its grid measured (at the target: the residual grid's r(P))
    assert np.abs(landed - targets[done]).max() < 0.01


def test_krl_model_after_a_one_millimetre_tool_change_lands_the_new_tool(tmp_path, capsys):
    # finding: a model identified with the tool at z 250 and a cell tool of z 251 put every hole
    # 1.00 mm off, exit 0 (the identified TCP was used, not the cell's)
    cal = _calibrated(tmp_path / "cal.yaml", tcp=DRILL)
    new_tool = (0.0, 0.0, 251.0, 0.0, 0.0, 0.0)
    cell = _cell(tmp_path, model="cal.yaml", status=6)
    cell.write_text(cell.read_text().replace("z: 250", "z: 251"))
    points = tmp_path / "p.csv"
    points.write_text("id,x,y,z,a,b,c\nH1,1500,100,1400,0,90,0\n")
    out = tmp_path / "krl"
    assert main(["krl", str(points), "--cell", str(cell), "-o", str(out)]) == 0
    at = {p.name: np.array([p.x, p.y, p.z]) for p in parse_krl(next(out.glob("*.dat")).read_text())}
    # the hole point: on the LIN from the clearance point (2 mm out) to the bottom (10 mm in)
    hole = at["XH1_CLR"] + 2.0 / 12.0 * (at["XH1_BOT"] - at["XH1_CLR"])
    target = np.array([[1500.0, 100.0, 1400.0]])
    landed = _landed(cal, hole[None], [[0.0, 90.0, 0.0]], 6, tool=new_tool)
    assert np.linalg.norm(landed - target) < 1e-3
    # the old rule (the controller with the new tool, the arm carrying the identified TCP)
    from accugrid.compensation.model_correction import model_correct

    tool = pose_from_xyzabc(np.array(new_tool))
    abc = np.array([[0.0, 90.0, 0.0]])
    old = model_correct(load_robot(cal), target, abc, 6, None, controller_tool=tool)
    assert abs(np.linalg.norm(old.command[0] - hole) - 1.0) < 0.05


def _rewrite_model_job(tmp_path: Path, motions: str, status=None) -> tuple[int, Path]:
    """Rewrite a KRL .src of ``motions`` (base 1: the robot frame) with a model-only cell (no
    grid; ``status``: its configuration.status); the exit code and the report."""
    _calibrated(tmp_path / "cal.yaml")
    src = tmp_path / "job.src"
    src.write_text(f"DEF job( )\n$BASE=BASE_DATA[1]\n{motions}END\n")
    cell = _cell(tmp_path, model="cal.yaml", status=status)
    out, report = tmp_path / "out.src", tmp_path / "r.csv"
    argv = ["rewrite", str(src), "--cell", str(cell), "-o", str(out), "--decimals", "6"]
    return main([*argv, "--report", str(report)]), report


def test_rewrite_model_takes_the_programs_last_status_for_a_position_without_s(tmp_path, capsys):
    # finding: an inline position with no S was corrected in Status 0 although the program's
    # own positions before it are Status 6 (a LIN keeps the Status the robot is in)
    first = "X 1500.0,Y 100.0,Z 1400.0,A 0.0,B 90.0,C 0.0"
    second = "X 1550.0,Y 120.0,Z 1380.0,A 0.0,B 90.0,C 0.0"
    code, report = _rewrite_model_job(tmp_path, f"PTP {{{first},S 6,T 27}}\nLIN {{{second}}}\n")
    assert code == 0, capsys.readouterr().err
    rows = _rows(report)
    assert [r["status"] for r in rows] == ["corrected", "corrected"]
    new = np.array([[float(r[k]) for k in ("x_new", "y_new", "z_new")] for r in rows])
    landed = _landed(tmp_path / "cal.yaml", new, np.tile([0.0, 90.0, 0.0], (2, 1)), 6)
    assert np.abs(landed - [[1500.0, 100.0, 1400.0], [1550.0, 120.0, 1380.0]]).max() < 1e-3


def test_rewrite_model_without_any_status_names_configuration_status(tmp_path, capsys):
    # finding: the error proposed --allow-partial where the cell's configuration.status is the fix
    pose = "X 1550.0,Y 120.0,Z 1380.0,A 0.0,B 90.0,C 0.0"
    code, _ = _rewrite_model_job(tmp_path, f"LIN {{{pose}}}\n")
    err = capsys.readouterr().err
    assert code == 2
    assert "job.src:3" in err and "no KUKA Status" in err and "configuration.status" in err
    assert "--allow-partial" not in err and "\n" not in err.strip()
    code, report = _rewrite_model_job(tmp_path, f"LIN {{{pose}}}\n", status=6)
    assert code == 0, capsys.readouterr().err
    new = np.array([[float(r[k]) for k in ("x_new", "y_new", "z_new")] for r in _rows(report)])
    landed = _landed(tmp_path / "cal.yaml", new, [[0.0, 90.0, 0.0]], 6)
    assert np.abs(landed - [1550.0, 120.0, 1380.0]).max() < 1e-3


def _same(a, b) -> bool:
    """Equal values, arrays element by element, dataclasses and grids field by field, paths as
    text."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(a, b)
    if dataclasses.is_dataclass(a) and type(a) is type(b):
        return all(_same(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a))
    if type(a) is type(b) and isinstance(a, GridModel):
        return vars(a).keys() == vars(b).keys() and all(
            _same(v, vars(b)[k]) for k, v in vars(a).items()
        )
    if isinstance(a, tuple | list) and isinstance(b, tuple | list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, str | os.PathLike) and isinstance(b, str | os.PathLike):
        return os.fspath(a) == os.fspath(b)
    return a == b


def _differing(policies: dict[str, Policy], left_out: tuple[str, ...] = ()) -> list[str]:
    """The fields of ``Policy`` in which the policies differ from the first's, by command."""
    (first, one), *others = policies.items()
    return [
        f"{name}.{f.name} differs from {first}'s"
        for name, other in others
        for f in dataclasses.fields(Policy)
        if f.name not in left_out and not _same(getattr(one, f.name), getattr(other, f.name))
    ]


def test_every_command_builds_the_same_policy_from_the_same_cell(tmp_path, monkeypatch):
    # finding: the policy was assembled in four places that drifted: rewrite had no
    # wrist-singularity limit of the cell, krl and gcode no orientation options
    built: list[Policy] = []
    build = Policy.build.__func__

    def spy(cls, *args, **kwargs):
        built.append(build(cls, *args, **kwargs))
        return built[-1]

    monkeypatch.setattr(Policy, "build", classmethod(spy))
    _calibrated(tmp_path / "cal.yaml")
    grid = _grid(tmp_path)
    cell = _cell(tmp_path, grid="grid.csv", model="cal.yaml", status=6)
    cell.write_text(cell.read_text() + "  singular_a5: 8\n")  # configuration: ...
    points = tmp_path / "p.csv"
    points.write_text("id,x,y,z,a,b,c\nH1,1500,100,1400,0,90,0\nH2,1600,-100,1500,10,80,0\n")
    src = tmp_path / "job.src"
    src.write_text(
        "DEF job( )\n$BASE=BASE_DATA[1]\nLIN {X 1500,Y 100,Z 1400,A 0,B 90,C 0,S 6,T 27}\nEND\n"
    )
    options = ["--orientation-tol", "3", "--orientation-limit", "20", "--allow-orientation"]
    options += ["--strict", "--outside", "clamp", "--allow-partial"]
    runs = {
        "krl": ["krl", str(points), "--cell", str(cell), "-o", str(tmp_path / "krl")],
        "gcode": ["gcode", str(points), "--cell", str(cell), "-o", str(tmp_path / "p.ngc")],
        "rewrite": ["rewrite", str(src), "--cell", str(cell), "-o", str(tmp_path / "out.src")],
        "correct": [
            "correct",
            str(points),
            "--grid",
            str(grid),
            "--model",
            str(tmp_path / "cal.yaml"),
        ]
        + [*TOOL, "--status", "6", "-o", str(tmp_path / "c.csv")],
    }
    policies = {}
    for name, argv in runs.items():
        built.clear()
        main([*argv, *options])
        assert len(built) == 1, name
        policies[name] = built[0]
    assert policies["rewrite"].singular_deg == 8.0
    assert policies["krl"].orientation_limit_deg == 20.0 and policies["krl"].strict
    assert policies["krl"].settings.outside == "clamp"
    correct = policies.pop("correct")  # no cell: the default wrist-singularity limit
    assert not _differing(policies)
    assert not _differing({"krl": policies["krl"], "correct": correct}, ("singular_deg",))


def test_rapid_and_gcode_build_the_same_policy_from_an_abb_cell(monkeypatch, tmp_path):
    built: list[Policy] = []
    build = Policy.build.__func__

    def spy(cls, *args, **kwargs):
        built.append(build(cls, *args, **kwargs))
        return built[-1]

    monkeypatch.setattr(Policy, "build", classmethod(spy))
    cell = EXAMPLES / "cell_irb6700.yaml"
    points = EXAMPLES / "wing_panel_points.csv"
    options = ["--orientation-tol", "2", "--orientation-limit", "4", "--allow-partial"]
    policies = {}
    for name, out in (("rapid", "P.mod"), ("gcode", "p.ngc")):
        built.clear()
        main([name, str(points), "--cell", str(cell), "-o", str(tmp_path / out), *options])
        (policies[name],) = built
    assert policies["rapid"].orientation_limit_deg == 4.0
    assert not _differing(policies)


def test_the_api_corrects_by_the_cells_model_and_a_header_says_when_nothing_is(tmp_path):
    # finding: build_program(holes, cell, robot) ignored the cell's correction.model (the
    # command line applies it) and wrote an uncorrected program that did not say so
    from accugrid import render_gcode, render_krl
    from accugrid.codegen.cell import load_cell

    cal = _calibrated(tmp_path / "cal.yaml")
    cell = load_cell(_cell(tmp_path, model="cal.yaml", status=6))
    robot = NOMINAL.with_tool(cell.flange_T_tool)
    pts = parse_points("id,x,y,z,a,b,c\nH1,1500,100,1400,0,90,0\nH2,1600,-100,1500,10,80,0\n", "p")
    program = build_program(pts, cell, robot)
    assert program.corrected
    landed = _landed(cal, pts.xyz + program.correction, pts.abc, 6)
    assert np.abs(landed - pts.xyz).max() < 1e-3
    plain = build_program(pts, cell, robot, None, None)  # asked for no correction
    assert not plain.corrected and not plain.correction.any()
    for prog, says in ((plain, True), (program, False)):
        texts = [render_gcode(prog, ["by hand"])]
        texts += ["".join(text) for text in render_krl(prog, ["by hand"]).values()]
        said = ["grid none, model none: positions are not corrected" in t for t in texts]
        assert said == [says] * 3
