"""The robot-neutral configuration and each dialect's words for it (``configuration_words``,
``read_configuration``), reached through the plug-ins the registry names."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from accugrid.codegen.dialects import plugin_of
from accugrid.codegen.rapid.configuration import abb_confdata
from accugrid.infra.errors import InputError
from accugrid.kinematics.configuration import Configuration, quarters
from accugrid.kinematics.robot import load_robot


@lru_cache(maxsize=2)
def robot(name: str):
    return load_robot(name)


def _within_limits(name: str, unit: np.ndarray) -> np.ndarray:
    """Joint vectors (N, 6) rad spread within the robot's limits by ``unit`` (N, 6) in [0, 1]."""
    lo, hi = np.radians(robot(name).joint_limits_deg).T
    return lo + unit * (hi - lo)


@settings(max_examples=60, deadline=None)
@given(
    arrays(int, (12, 6), elements=st.integers(-7, 7)),
    arrays(float, (12, 6), elements=st.floats(1e-6, 1 - 1e-6)),
)
def test_quarters_and_turns_are_the_axis_angles_counted_in_quarter_and_whole_turns(k, part):
    """Angles within quarter k (a fraction ``part`` of it, off its edges, which the next test
    pins): quarter k, the whole turn t of -180 + 360 t <= angle < 180 + 360 t, the sign."""
    deg = 90.0 * (k + part)
    c = Configuration.of_code(np.zeros(len(deg), int), quarters(np.radians(deg)))
    np.testing.assert_array_equal(c.quarter, k)
    np.testing.assert_array_equal(c.turns, np.floor((deg + 180.0) / 360.0))
    np.testing.assert_array_equal(c.negative, deg < 0)


def test_turns_at_the_edges():
    deg = np.array([[-180.0, 180.0, 179.0, -181.0, 540.0, 0.0]])
    c = Configuration.of_code([0], quarters(np.radians(deg)))
    assert c.turns.tolist() == [[0, 1, 0, -1, 2, 0]]  # -180 <= angle < 180: turn 0


@settings(max_examples=40, deadline=None)
@given(arrays(float, (16, 6), elements=st.floats(0.0, 1.0)))
def test_krl_words_are_status_and_turn(unit):
    """S: shoulder + 2 elbow + 4 wrist; T: bit i where A(i+1) < 0, counted here bit by bit."""
    r = robot("kr210")
    q = _within_limits("kr210", unit)
    c = Configuration.of_joints(r, q)
    words = plugin_of("krl").configuration_words(c)
    np.testing.assert_array_equal(words[:, 0], c.shoulder + 2 * c.elbow + 4 * c.wrist)
    turn = sum((q[:, i] < 0).astype(int) * 2**i for i in range(6))
    np.testing.assert_array_equal(words[:, 1], turn)


def test_krl_words_read_back_for_every_status_and_turn():
    s, t = np.meshgrid(np.arange(8), np.arange(64), indexing="ij")
    words = np.stack([s.ravel(), t.ravel()], axis=-1)
    krl = plugin_of("krl")
    back = krl.read_configuration(words)
    np.testing.assert_array_equal(krl.configuration_words(back), words)
    np.testing.assert_array_equal(back.code, words[:, 0])


@settings(max_examples=40, deadline=None)
@given(arrays(float, (16, 6), elements=st.floats(0.0, 1.0)))
def test_rapid_words_of_the_configuration_are_the_confdata_of_the_joints(unit):
    """Within the IRB 6700's limits the wrist centre is behind the lower arm exactly where the
    elbow is down, so the confdata of the neutral configuration is the one the arm's geometry
    gives (``abb_confdata``), and reading it back keeps the flags and axes 1, 4, 6."""
    r = robot("irb6700")
    q = _within_limits("irb6700", unit)
    c = Configuration.of_joints(r, q)
    rapid = plugin_of("rapid")
    words = rapid.configuration_words(c)
    np.testing.assert_array_equal(words, abb_confdata(r, q))
    back = rapid.read_configuration(words)
    for name in ("shoulder", "elbow", "wrist"):
        np.testing.assert_array_equal(getattr(back, name), getattr(c, name))
    np.testing.assert_array_equal(back.quarter[:, [0, 3, 5]], c.quarter[:, [0, 3, 5]])


def test_a_dialect_without_configuration_words_refuses_them():
    c = Configuration.of_code([2], np.zeros((1, 6), int))
    with pytest.raises(InputError, match="G-code programs name no robot configuration"):
        plugin_of("gcode").configuration_words(c)
    with pytest.raises(InputError, match="G-code programs name no robot configuration"):
        plugin_of("gcode").read_configuration(np.zeros((1, 2), int))


def test_indexing_a_configuration_takes_the_same_rows_of_every_field():
    q = np.radians([[0, -90, 90, 0, 20, 0], [30.0, -135.0, -30.0, 0.0, -30.0, -5.0]])
    c = Configuration.of_joints(robot("kr210"), q)
    one = c[1:]
    assert one.code.tolist() == [5] and one.quarter.tolist() == [[0, -2, -1, 0, -1, -1]]
