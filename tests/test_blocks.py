"""Block work on a few threads (infra.blocks): the serial loop's results and failures."""

from __future__ import annotations

import os
import threading
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from program_helpers import cell, cell_with, panel_points, robot

from accugrid.codegen import program
from accugrid.infra import blocks
from accugrid.infra.errors import InputError

# 48 holes of the example panel (base x, y mm)
ROWS = np.array([[x, y] for y in (150.0, 450.0) for x in np.arange(0.0, 576.0, 25.0)])


class Failed(Exception):
    """The error a test block raises; carries its start."""


@settings(max_examples=60, deadline=None)
@given(
    count=st.integers(0, 40),
    workers=st.integers(1, 5),
    failing=st.sets(st.integers(0, 39), max_size=4),
)
def test_every_block_before_the_first_failure_runs_once_and_that_failure_is_raised(
    count, workers, failing
):
    starts = list(range(count))
    ran = []
    lock = threading.Lock()

    def work(start: int) -> None:
        with lock:
            ran.append(start)
        if start in failing:
            raise Failed(start)

    finished = []

    def done(start: int) -> None:  # every block up to start has run, told in order
        assert threading.current_thread() is threading.main_thread()
        with lock:
            assert set(range(start + 1)) <= set(ran)
        finished.append(start)

    first = min((s for s in starts if s in failing), default=None)
    if first is None:
        blocks.run_blocks(work, starts, workers, done)
    else:
        with pytest.raises(Failed) as info:
            blocks.run_blocks(work, starts, workers, done)
        assert info.value.args == (first,)
    assert len(ran) == len(set(ran))  # no block twice
    assert set(range(count if first is None else first)) <= set(ran)
    assert finished == starts[: count if first is None else first]


def test_no_more_blocks_in_flight_than_threads():
    running, most = 0, 0
    lock = threading.Lock()

    def work(start: int) -> None:
        nonlocal running, most
        with lock:
            running += 1
            most = max(most, running)
        time.sleep(0.002)  # lets other threads start theirs, if the pool allowed it
        with lock:
            running -= 1

    for workers in (1, 2, 3):
        most = 0
        blocks.run_blocks(work, range(12), workers)
        assert 1 <= most <= workers


def test_blocks_write_the_same_output_as_the_serial_loop():
    values = np.random.default_rng(1).normal(size=1000)
    serial, threaded = np.empty(1000), np.empty(1000)

    def into(out):
        def work(start: int) -> None:
            out[start : start + 64] = np.sin(values[start : start + 64]) ** 2

        return work

    blocks.run_blocks(into(serial), range(0, 1000, 64), 1)
    blocks.run_blocks(into(threaded), range(0, 1000, 64), 3)
    np.testing.assert_array_equal(threaded, serial)
    np.testing.assert_array_equal(serial, np.sin(values) ** 2)


def test_threads_is_the_affinity_mask_within_the_limit():
    n = blocks.threads()
    assert 1 <= n <= blocks.MAX_THREADS
    if hasattr(os, "sched_getaffinity"):
        assert n == min(len(os.sched_getaffinity(0)), blocks.MAX_THREADS)


def _ik_of_program(monkeypatch, c, threads: int):
    """build_program's IK blocks (small blocks, ``threads`` threads) and one IK call over all."""
    pts = panel_points(ROWS)
    monkeypatch.setattr(program, "IK_BLOCK", 7)
    monkeypatch.setattr(blocks, "threads", lambda: threads)
    built = program.build_program(pts, c, robot(), None)
    positions, rotations = built.positions, c.robot_T_base[:3, :3] @ built.rotations
    stages = 3 if c.drilling.retract_mm == c.drilling.approach_mm else 4

    def poses(holes):
        return program._poses(c, positions[holes, :stages], rotations[holes])

    sol = program._ik_blocks(robot(), poses, len(pts), stages, 2, 0)
    whole = robot().ik(poses(slice(None)).reshape(-1, 4, 4), status=2, turn=0)
    return sol, whole


@pytest.mark.parametrize("threads", [1, 2, 3])
@pytest.mark.parametrize("retract", [30.0, 20.0])
def test_threaded_ik_blocks_equal_one_ik_call(monkeypatch, threads, retract):
    c = cell_with(drilling={"retract_mm": retract})
    sol, whole = _ik_of_program(monkeypatch, c, threads)
    assert len(sol.ok) > 7 * threads  # several blocks per thread
    np.testing.assert_array_equal(sol.q, whole.q)  # the turns follow from the joints
    for field in ("ok", "reason", "status"):
        assert getattr(sol, field).tolist() == getattr(whole, field).tolist(), field


def test_an_error_in_a_threaded_ik_block_surfaces_as_in_the_serial_run(monkeypatch):
    pts = panel_points(ROWS)
    monkeypatch.setattr(program, "IK_BLOCK", 6)
    messages = []
    for threads in (1, 2):
        monkeypatch.setattr(blocks, "threads", lambda n=threads: n)
        calls = []
        real_ik = type(robot()).ik

        def failing_ik(self, poses, *args, calls=calls, real_ik=real_ik, **kwargs):
            calls.append(len(poses))
            if len(calls) == 4:  # the 3rd block (the first call is the first pose's default)
                raise InputError("robot test: no closed-form inverse")
            return real_ik(self, poses, *args, **kwargs)

        monkeypatch.setattr(type(robot()), "ik", failing_ik)
        with pytest.raises(InputError) as info:
            program.build_program(pts, cell(), robot(), None)
        messages.append(info.value.message)
        monkeypatch.setattr(type(robot()), "ik", real_ik)
    assert messages == ["robot test: no closed-form inverse"] * 2
