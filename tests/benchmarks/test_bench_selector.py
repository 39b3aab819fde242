"""RL selector training speed: wall time per 1,000 timesteps of MaskablePPO on GripSelect-v0.

Run ``python -m pytest tests/benchmarks/test_bench_selector.py --benchmark-enable``; seconds per
1,000 timesteps are in each benchmark's ``extra_info``. Replay backend on a synthetic table of
40 objects (10-40 grips each, K = 64), 4 envs in a DummyVecEnv, the training hyper-parameters of
``train_selector``; torch on one thread: on the 2-core target small networks are
10 times slower with 2 torch threads (measured: 95 s vs 9.6 s per 1,024 steps under load).
Nothing about time is asserted.
"""

from __future__ import annotations

import pytest

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments.selector.training import (
    make_selector_env,
    make_selector_model,
    torch_threads,
)
from grip_env.config import load_config

TIMESTEPS = 1024


@pytest.mark.slow
@pytest.mark.parametrize(("policy", "threads"), [("set", 1), ("flat", 1)])
def test_bench_training_per_1000_steps(benchmark, policy: str, threads: int) -> None:
    table = synthetic_grips(n_objects=40, seed=0)
    config = load_config()
    env = make_selector_env(table, config, "train", seed=0)

    def train() -> int:
        with torch_threads(threads):
            model = make_selector_model(env, policy, seed=0)
            model.learn(TIMESTEPS)
        return model.num_timesteps

    benchmark.group = "selector training"
    steps = benchmark.pedantic(train, rounds=3, iterations=1)
    stats = getattr(benchmark, "stats", None)
    if stats is not None:
        benchmark.extra_info["s_per_1000_steps"] = round(stats.stats.mean * 1000 / steps, 3)
    assert steps >= TIMESTEPS
