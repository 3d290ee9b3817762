"""The program model: one grid correction per hole in the right frames, a straight drill axis,
IK-checked poses with a constant Status, and errors/warnings that name the hole."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from program_helpers import (
    cell,
    cell_with,
    error_field,
    grid,
    near_singular_wrist,
    panel_points,
    robot,
)

from accugrid.codegen.krl.configuration import configuration_words
from accugrid.codegen.points import parse_points
from accugrid.codegen.program import STAGES, _branch_jumps, build_program
from accugrid.compensation.policy import PolicyRequest
from accugrid.compensation.settings import CorrectionSettings
from accugrid.infra.errors import InputError
from accugrid.infra.textsafe import fixed
from accugrid.kinematics.frames import pose_from_xyzabc, transform_points

ROWS = np.array([[x, y] for y in (150.0, 450.0) for x in np.arange(0.0, 576.0, 25.0)])


def robot_poses(program, stage):
    """robot_T_tcp (N, 4, 4) of one stage, built independently of the program code."""
    c = program.cell
    poses = np.tile(np.eye(4), (len(program), 1, 1))
    poses[:, :3, :3] = c.robot_T_base[:3, :3] @ program.rotations
    poses[:, :3, 3] = transform_points(c.robot_T_base, program.positions[:, stage])
    return poses


def test_nominal_positions_lie_on_the_drill_axis():
    pts = panel_points(ROWS)
    prog = build_program(pts, cell(), robot(), None)
    c = cell()
    axis = prog.rotations[:, :, 2]
    np.testing.assert_allclose(axis, pts.axis, atol=1e-12)
    expected = {
        "APP": pts.xyz - c.drilling.approach_mm * axis,
        "CLR": pts.xyz - c.drilling.clearance_mm * axis,
        "BOT": pts.xyz + 7.0 * axis,  # depth column
        "RET": pts.xyz - c.drilling.retract_mm * axis,
    }
    for k, stage in enumerate(STAGES):
        np.testing.assert_allclose(prog.nominal[:, k], expected[stage], atol=1e-9)
    # without a grid nothing moves
    np.testing.assert_array_equal(prog.positions, prog.nominal)
    assert not prog.corrected and prog.largest_correction()[0] == 0.0


def test_every_stage_gets_the_hole_correction():
    pts = panel_points(ROWS)
    prog = build_program(pts, cell(), robot(), grid())
    c = cell()
    hole_robot = transform_points(c.robot_T_base, pts.xyz)
    e = grid().predict(hole_robot)  # the grid's own prediction at the hole point
    np.testing.assert_allclose(prog.correction, e, atol=1e-9)
    for k in range(4):
        moved = transform_points(c.robot_T_base, prog.positions[:, k]) - transform_points(
            c.robot_T_base, prog.nominal[:, k]
        )
        np.testing.assert_allclose(moved, e, atol=1e-9)
    # the field is not constant: the approach point's own error would differ
    app_robot = transform_points(c.robot_T_base, prog.nominal[:, 0])
    assert np.abs(grid().predict(app_robot) - e).max() > 1e-3
    # hence the corrected drill axis is the nominal one, shifted
    d = prog.positions[:, 2] - prog.positions[:, 0]
    d /= np.linalg.norm(d, axis=1)[:, None]
    np.testing.assert_allclose(d, prog.rotations[:, :, 2], atol=1e-12)
    length, hole = prog.largest_correction()
    assert length == pytest.approx(np.linalg.norm(e, axis=1).max())
    assert hole == int(np.argmax(np.linalg.norm(e, axis=1)))


def test_correction_iterations_come_from_the_cell():
    pts = panel_points(ROWS)
    c = dataclasses.replace(cell(), correction=CorrectionSettings(iterations=3))
    prog = build_program(pts, c, robot(), grid())
    hole_robot = transform_points(c.robot_T_base, pts.xyz)
    np.testing.assert_allclose(
        prog.correction, grid().correct(hole_robot, iterations=3) - hole_robot, atol=1e-9
    )
    once = build_program(pts, cell(), robot(), grid()).correction
    assert np.abs(prog.correction - once).max() > 1e-4


def test_ik_status_constant_and_fk_reproduces_every_pose():
    pts = panel_points(ROWS)
    prog = build_program(pts, cell(), robot(), grid())
    status, turn = np.moveaxis(configuration_words(prog.configuration), -1, 0)
    assert status.shape == (len(pts), 4)
    assert len(set(status.ravel().tolist())) == 1
    for stage in range(4):
        poses = robot_poses(prog, stage)
        sol = robot().ik(poses, status=status[:, stage], turn=turn[:, stage])
        assert sol.ok.all()
        np.testing.assert_allclose(robot().fk(sol.q), poses, atol=1e-6)
    assert prog.warnings == []


def test_unreachable_hole_is_named():
    text = "id,x,y,z,a,b,c\nNEAR,0,150,0,-90,0,180\nFAR-AWAY,0,150,-3000,-90,0,180\n"
    with pytest.raises(InputError) as info:
        build_program(parse_points(text, "p.csv"), cell(), robot(), None)
    assert "hole 'FAR-AWAY'" in info.value.message
    assert "not reachable" in info.value.message
    assert (info.value.path, info.value.line) == ("p.csv", 3)


def test_hole_outside_the_grid_is_named():
    # base y 1500 -> robot Z 2500, above the grid (Z 1100..2100) but reachable
    text = "id,x,y,z,i,j,k\nIN,0,150,0,0,0,-1\nHIGH,0,1200,0,0,0,-1\n"
    with pytest.raises(InputError) as info:
        build_program(parse_points(text, "p.csv"), cell(), robot(), grid())
    assert "1 hole(s) cannot be corrected (1 outside the grid)" in info.value.message
    assert "hole 'HIGH' (p.csv:3): outside the grid box by 100.000 mm" in info.value.message
    partial = PolicyRequest(allow_partial=True)
    prog = build_program(parse_points(text, "p.csv"), cell(), robot(), grid(), request=partial)
    assert prog.correction[1].tolist() == [0.0, 0.0, 0.0] and prog.correction[0].any()
    assert prog.uncorrected == ["not corrected: hole HIGH: outside the grid box by 100.000 mm"]


def test_status_that_cannot_be_kept_is_an_error_unless_allowed():
    pts = panel_points(ROWS[:3])
    c = cell_with(configuration={"status": 0})  # elbow below the A2-A3 line: A2 beyond its limit
    with pytest.raises(InputError, match="with Status 0: A2 outside limits") as info:
        build_program(pts, c, robot(), None)
    assert "configuration.allow_change" in info.value.message
    prog = build_program(pts, cell_with(c, configuration={"allow_change": True}), robot(), None)
    assert any("another Status than 0" in w for w in prog.warnings)
    assert (prog.configuration.code != 0).all()


def test_wrist_singularity_warning_names_the_hole():
    c = cell()
    points, base_T_tcp = near_singular_wrist()
    prog = build_program(points, c, robot(), None)
    assert len(prog.warnings) == 1
    assert "wrist singularity" in prog.warnings[0] and "hole 'SING-1'" in prog.warnings[0]
    x = np.concatenate([points.xyz[0] - c.drilling.approach_mm * base_T_tcp[:3, 2], points.abc[0]])
    np.testing.assert_allclose(pose_from_xyzabc(x)[:3, 3], base_T_tcp[:3, 3], atol=1e-6)


def test_orientation_far_from_the_grid_is_flagged_or_refused_as_in_correct():
    # drill axis tilted 10 deg (flagged) or 20 deg (beyond the limit: refused, as correct and
    # rewrite do) away from base -Z (robot +X): still reachable
    for deg, refused in ((10, False), (20, True)):
        t = np.radians(deg)
        text = f"id,x,y,z,i,j,k\nTILT,100,300,0,{np.sin(t):.6f},0,{-np.cos(t):.6f}\n"
        if refused:
            with pytest.raises(InputError, match="orientation 20.0 deg from the grid's"):
                build_program(parse_points(text, "t.csv"), cell(), robot(), grid())
            continue
        prog = build_program(parse_points(text, "t.csv"), cell(), robot(), grid())
        assert any(
            "orientation 10.0 deg from the grid's" in w and "TILT" in w for w in prog.warnings
        )


def test_points_without_orientation_or_holes_are_refused():
    with pytest.raises(InputError, match="no orientation"):
        build_program(parse_points("x,y,z\n0,150,0\n", "p.csv"), cell(), robot(), None)
    with pytest.raises(InputError, match="no drilling points"):
        build_program(parse_points("x,y,z,i,j,k\n", "p.csv"), cell(), robot(), None)


def test_axis_opposite_the_reference_is_refused():
    # base +Z = robot -X: pointing the drill back at the robot, 180 deg from the reference
    with pytest.raises(InputError, match="more than 150 deg") as info:
        build_program(
            parse_points("id,x,y,z,i,j,k\nBACK,0,150,0,0,0,1\n", "p.csv"), cell(), robot(), None
        )
    assert "hole 'BACK'" in info.value.message and info.value.column == 5


def test_program_frame_conversion_keeps_the_robot_pose():
    pts = panel_points(ROWS[:5])
    prog = build_program(pts, cell(), robot(), grid())
    robot_T_program = pose_from_xyzabc(np.array([1500.0, -100.0, 900.0, 30.0, -10.0, 5.0]))
    pos, abc = prog.in_frame(robot_T_program)
    poses = np.tile(np.eye(4), (len(prog), 1, 1))
    poses[:, :3, :3] = pose_from_xyzabc(np.column_stack([pos[:, 0], abc]))[:, :3, :3]
    poses[:, :3, 3] = pos[:, 0]
    np.testing.assert_allclose(robot_T_program @ poses, robot_poses(prog, 0), atol=1e-9)


@given(
    st.lists(
        st.tuples(st.floats(-100, 650), st.floats(100, 550)), min_size=1, max_size=12, unique=True
    )
)
def test_any_panel_point_set_keeps_axis_straight_and_status(xy):
    pts = panel_points(np.array(xy))
    prog = build_program(pts, cell(), robot(), grid())
    d = prog.positions - prog.positions[:, :1]
    # all four positions on one line along the tool Z axis
    cross = np.cross(d, prog.rotations[:, None, :, 2])
    assert np.abs(cross).max() < 1e-9
    assert len(set(prog.configuration.code.ravel().tolist())) == 1
    np.testing.assert_allclose(
        prog.correction, error_field(transform_points(cell().robot_T_base, pts.xyz)), atol=0.2
    )


@settings(max_examples=40, deadline=None)
@given(
    steps=arrays(float, (12, 3, 6), elements=st.floats(-1.0, 1.0)),
    flips=st.sets(st.tuples(st.integers(0, 11), st.integers(0, 2), st.integers(0, 5)), max_size=3),
)
def test_a_joint_move_over_180_deg_between_poses_names_its_hole(steps, flips):
    """``_branch_jumps`` against the plain rule: the largest |A_i| change between consecutive
    poses (hole by hole, stage by stage) over 180 deg is an error naming the hole of the
    later pose, or with allow_change a warning counting such moves."""
    q = np.cumsum(steps.reshape(-1, 6), axis=0).reshape(12, 3, 6)  # moves of up to 1 rad
    for hole, stage, axis in flips:
        q[hole, stage:, axis] += np.radians(200.0)  # a jump of 200 deg +- 57 deg
        if hole + 1 < 12:
            q[hole + 1 :, :, axis] += np.radians(200.0)
    seq = q.reshape(-1, 6)
    moves = [float(np.degrees(np.max(np.abs(seq[i + 1] - seq[i])))) for i in range(len(seq) - 1)]
    over = [i for i, m in enumerate(moves) if m > 180.0]
    pts = panel_points(ROWS[:12])
    if not over:
        assert _branch_jumps(pts, cell(), q) == []
        return
    hole = (over[0] + 1) // 3
    change = np.abs(seq[over[0] + 1] - seq[over[0]])
    largest = {i + 1 for i in np.flatnonzero(change == change.max())}  # axes tied for the most
    with pytest.raises(InputError) as info:
        _branch_jumps(pts, cell(), q)
    named = re.match(
        rf"hole 'H{hole + 1}': A(\d) turns (\d+) deg from the previous pose", info.value.message
    )
    assert named and int(named[1]) in largest and named[2] == f"{moves[over[0]]:.0f}"
    assert info.value.line == hole + 2
    allowed = cell_with(configuration={"allow_change": True})
    (warning,) = _branch_jumps(pts, allowed, q)
    assert warning.endswith(f"; {len(over)} such move(s) in the program")


@settings(max_examples=30, deadline=None)
@given(
    rows=st.lists(
        st.tuples(
            st.text(st.characters(blacklist_characters=',"#\r\x00'), min_size=1, max_size=6),
            st.one_of(st.none(), st.floats(0.1, 30.0)),
            st.one_of(st.none(), st.floats(0.1, 20.0)),
        ),
        min_size=1,
        max_size=8,
        unique_by=lambda row: row[0].strip(),
    ),
    cut=st.data(),
)
def test_labels_are_id_depth_and_diameter_of_each_hole(rows, cut):
    """Program.labels: per hole "<id> depth <d>" and " dia <t>" when the diameter is given,
    both with 3 decimals as ``fixed`` writes them (the depth: the cell's when not given); ids as
    read, whatever they hold."""
    rows = [r for r in rows if r[0].strip()]
    if not rows:
        return
    text = "id,x,y,z,i,j,k,diameter,depth\n" + "".join(
        f'"{i}",{25.0 * n},150,0,0,0,-1,{"" if d is None else d},{"" if h is None else h}\n'
        for n, (i, d, h) in enumerate(rows)
    )
    prog = build_program(parse_points(text, "l.csv"), cell(), robot(), None)
    default = cell().drilling.depth_mm
    expected = [
        f"{i.strip()} depth {fixed(default if h is None else h, 3)}"
        + ("" if d is None else f" dia {fixed(d, 3)}")
        for i, d, h in rows
    ]
    assert prog.labels() == expected
    lo = cut.draw(st.integers(0, len(rows)))
    hi = cut.draw(st.integers(lo, len(rows)))
    assert prog.labels(lo, hi) == expected[lo:hi]


def test_a_drill_axis_too_far_from_the_reference_names_the_hole():
    # base (0, 0, -1) is the reference tool Z; (0, 0, 1) is 180 deg from it
    text = "id,x,y,z,i,j,k\nOK,0,150,0,0,0,-1\nBACK,25,150,0,0,0,1\n"
    with pytest.raises(InputError) as info:
        build_program(parse_points(text, "t.csv"), cell(), robot(), None)
    assert info.value.message == (
        "hole 'BACK': the drill axis i,j,k is more than 150 deg from the reference tool axis "
        "(configuration.reference); give a,b,c for this hole or turn the reference"
    )
    assert (info.value.path, info.value.line, info.value.column) == ("t.csv", 3, 5)
