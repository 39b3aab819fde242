"""Candidate generation time per default object (regions found from the polygon, default config).

Run ``python -m pytest tests/benchmarks/test_bench_candidates.py --benchmark-enable``; the goal
is a median of at most 20 ms per object on one core. The row count is in each benchmark's
``extra_info``. Nothing about time is asserted.
"""

from __future__ import annotations

import pytest

from grip_env.config import Config
from grip_env.objects import load_object_set
from grip_env.params import GraspParams
from grip_env.perception.regions import find_regions
from grip_env.planning.pipeline import candidates

CONFIG = Config()
PARAMS = GraspParams()


@pytest.mark.parametrize("obj", load_object_set("default"), ids=lambda o: o.name)
def test_bench_candidates(benchmark, obj):
    table = benchmark(candidates, obj, PARAMS, CONFIG)
    benchmark.extra_info["rows"] = len(table)


@pytest.mark.parametrize("obj", load_object_set("default"), ids=lambda o: o.name)
def test_bench_candidates_given_regions(benchmark, obj):
    """Synthesis, search and features alone (regions found once beforehand)."""
    regions = find_regions(obj, CONFIG.perception, PARAMS)
    table = benchmark(candidates, obj, PARAMS, CONFIG, regions=regions)
    benchmark.extra_info["rows"] = len(table)
