"""Speed of grip execution: trials per second on one core and physics steps per trial."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from grip_env.config import Config
from grip_env.objects import make_shape
from grip_env.sim import TrialScene, grip_plans
from grip_env.sim.uncertainty import trial_noises

OPPOSED = {"hand_x": 0.0, "hand_y": 0.0, "hand_yaw": np.pi / 2, "spread": 0.0,
           "p1_x": 25.0, "p1_y": 27.5, "p2_x": -25.0, "p2_y": 27.5, "p3_x": 0.0, "p3_y": -27.5}


@pytest.fixture(scope="module")
def scene():
    with TrialScene(make_shape("rectangle"), Config()) as built:
        yield built


def test_bench_one_trial(benchmark, scene):
    plan = grip_plans(pd.DataFrame([OPPOSED]))[0]
    noises = iter(trial_noises(scene.config, 0, 0, [0], range(10_000))[0])
    result = benchmark(lambda: scene.run(plan, next(noises)))
    benchmark.extra_info["steps_per_trial"] = result.steps
    assert result.steps <= 480


def test_bench_rebuild_scene(benchmark):
    """What a clean trial costs on top of its steps: a new world with table, object and hand."""
    obj, config = make_shape("rectangle"), Config()
    benchmark(lambda: TrialScene(obj, config).close())
