"""Environment throughput: replayed steps (goal >= 20,000 per second on one core) and live steps.

Run ``python -m pytest tests/benchmarks/test_bench_envs.py --benchmark-enable``; steps per second
are in each benchmark's ``extra_info``. A replayed step with one attempt ends the episode,
so each of its steps includes a ``reset``. Nothing about time is asserted.
"""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

import grip_env  # noqa: F401  (registers the environments)
from grip_env.envs import GripAcceptEnv, GripSelectEnv
from tests.test_envs import synthetic_dataset

REPLAY_STEPS = 20_000
LIVE_STEPS = 3


def _record_rate(benchmark, steps: int) -> None:
    benchmark.extra_info["steps"] = steps
    stats = getattr(benchmark, "stats", None)
    if stats is not None:
        benchmark.extra_info["steps_per_s"] = round(steps / stats.stats.mean)


def _run(env: gymnasium.Env, steps: int, action: int) -> float:
    total = 0.0
    env.reset(seed=0)
    for _ in range(steps):
        _, reward, terminated, truncated, _ = env.step(action)
        total += reward
        if terminated or truncated:
            env.reset()
    return total


@pytest.fixture(scope="module")
def data():
    return synthetic_dataset(sizes=(50, 80, 30, 100, 64, 10))


@pytest.mark.parametrize("cls", [GripSelectEnv, GripAcceptEnv])
def test_bench_replay_steps(benchmark, data, cls) -> None:
    env = cls(data, max_candidates=64, max_attempts=1)
    benchmark.group = "env replay"
    total = benchmark.pedantic(_run, args=(env, REPLAY_STEPS, 1), rounds=3, iterations=1)
    _record_rate(benchmark, REPLAY_STEPS)
    assert 0 <= total <= REPLAY_STEPS


def test_bench_replay_steps_through_make(benchmark, data) -> None:
    env = gymnasium.make("GripSelect-v0", data=data, max_attempts=1)
    benchmark.group = "env replay"
    benchmark.pedantic(_run, args=(env, REPLAY_STEPS, 0), rounds=3, iterations=1)
    _record_rate(benchmark, REPLAY_STEPS)


@pytest.mark.slow
def test_bench_live_steps(benchmark) -> None:
    sim = pytest.importorskip("grip_env.sim")
    if not hasattr(sim, "run_trials"):
        pytest.skip("grip_env.sim.run_trials is not available")
    env = GripSelectEnv(objects=["rectangle"], max_attempts=1)
    env.reset(seed=0)  # computes the candidates outside the timing
    benchmark.group = "env live"
    total = benchmark.pedantic(_run, args=(env, LIVE_STEPS, 0), rounds=1, iterations=1)
    _record_rate(benchmark, LIVE_STEPS)
    assert np.isfinite(total)
