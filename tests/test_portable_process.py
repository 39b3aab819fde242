"""The held worker that planning, perception and trials run in when this process's kernels are not
portable (:mod:`grip_env.portable_process`): the same results, the same errors, and a worker
that stops cleanly and comes back after a loss.

The suite's own process is held at x86-64-v3, so these tests make the portable functions delegate
as they do after ``import numpy, grip_env`` on an AVX-512 CPU; test_portable_math checks, on such a
CPU, that a process whose numpy came first gets the recorded bits."""

from __future__ import annotations

import os
import threading

import pandas as pd
import pytest

from grip_env import portable_process
from grip_env.objects import make_shape
from grip_env.pipeline import candidates
from grip_env.sim import run_trials
from grip_env.sim.camera import perceive
from grip_env.sim.world import World


@pytest.fixture
def delegating(monkeypatch: pytest.MonkeyPatch):  # type: ignore[no-untyped-def]
    """Portable functions called here run in the held worker."""
    monkeypatch.setattr(portable_process, "_portable_here", lambda: False)
    yield
    portable_process.stop_worker()


def _worker_pid() -> int:
    assert portable_process._running is not None
    return portable_process._running.process.pid


@pytest.mark.slow
def test_plans_perception_trials_and_errors_in_the_worker_are_those_made_here(delegating):
    box = make_shape("rectangle")
    with portable_process.in_place():
        here = candidates(box)
        seen_here = perceive(box)
        trials_here = run_trials(box, here.head(2), trials=2, seed=5)
    there = candidates(box)
    worker = _worker_pid()
    assert worker != os.getpid()
    with World() as world:  # a cache of this process: the worker renders in its own
        seen_there = perceive(box, world=world)
    pd.testing.assert_frame_equal(there, here, check_exact=True)
    assert seen_there.contour.tobytes() == seen_here.contour.tobytes()
    pd.testing.assert_frame_equal(run_trials(box, there.head(2), trials=2, seed=5), trials_here,
                                  check_exact=True)
    with pytest.raises(ValueError, match="trials must be a positive integer, got 0") as raised:
        run_trials(box, there.head(1), trials=0)
    assert any("x86-64-v3 worker" in note for note in raised.value.__notes__)
    with pytest.raises(ValueError, match="obj must be a PlanarObject"):
        candidates("rectangle")  # type: ignore[arg-type]
    assert _worker_pid() == worker  # one worker, kept for the next calls and past errors


@pytest.mark.slow
def test_a_lost_worker_is_replaced_and_a_stopped_one_exits(delegating):
    box = make_shape("rectangle")
    first = candidates(box)
    lost = portable_process._running.process  # type: ignore[union-attr]
    lost.kill()
    lost.wait()
    pd.testing.assert_frame_equal(candidates(box), first, check_exact=True)
    replaced = portable_process._running.process  # type: ignore[union-attr]
    assert replaced.pid != lost.pid
    killer = threading.Timer(1.0, replaced.kill)  # during a call: the call says so
    killer.start()
    with pytest.raises(RuntimeError, match="worker running run_trials died"):
        run_trials(box, first.head(4), trials=100)
    killer.join()
    assert portable_process._running is None
    pd.testing.assert_frame_equal(candidates(box), first, check_exact=True)
    last = portable_process._running.process  # type: ignore[union-attr]
    portable_process.stop_worker()
    assert last.poll() == 0  # it left its loop and exited by itself
    assert portable_process._running is None


def test_where_no_worker_can_start_the_calls_run_here_and_say_so(monkeypatch):
    monkeypatch.setattr(portable_process, "math_is_portable", lambda: False)
    assert not portable_process._portable_here.__wrapped__()  # POSIX: the worker
    monkeypatch.setattr(portable_process.os, "name", "nt")
    with pytest.warns(RuntimeWarning, match="no held worker runs on this platform"):
        assert portable_process._portable_here.__wrapped__()
