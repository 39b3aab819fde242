"""Feature throughput: the numpy core, the DataFrame entry and the per-grip Python reference.

Run ``python -m pytest tests/benchmarks/test_bench_features.py --benchmark-enable``; grips per
second are in each benchmark's ``extra_info`` (and are OPS times the row count). Goal: at least
1,000,000 grips/s on one core and 50 times the per-grip Python. Nothing about time is asserted.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from grip_env.params import GraspParams
from grip_env.planning.features import (
    OUTPUT_NAMES,
    REQUIRED_COLUMNS,
    compute_features,
    features_from_arrays,
)
from tests.benchmarks.reference_features import random_grip_table, reference_features

VECTORISED_ROWS = 100_000
REFERENCE_ROWS = 2_000
PARAMS = GraspParams()


@pytest.fixture(scope="module")
def big_table() -> pd.DataFrame:
    return random_grip_table(VECTORISED_ROWS, seed=42)


def _record_rate(benchmark, rows: int) -> None:
    benchmark.extra_info["grips"] = rows
    stats = getattr(benchmark, "stats", None)
    if stats is not None:
        benchmark.extra_info["grips_per_s"] = round(rows / stats.stats.mean)


def test_bench_core_on_arrays(benchmark, big_table: pd.DataFrame) -> None:
    arrays = {name: big_table[name].to_numpy() for name in REQUIRED_COLUMNS}
    benchmark.group = "features"
    result = benchmark(features_from_arrays, arrays, PARAMS)
    _record_rate(benchmark, VECTORISED_ROWS)
    assert result.shape == (VECTORISED_ROWS, len(OUTPUT_NAMES))
    assert np.isfinite(result).all()


def test_bench_dataframe_entry(benchmark, big_table: pd.DataFrame) -> None:
    benchmark.group = "features"
    result = benchmark(compute_features, big_table, PARAMS)
    _record_rate(benchmark, VECTORISED_ROWS)
    assert result.shape == (VECTORISED_ROWS, len(OUTPUT_NAMES))


def test_bench_per_grip_reference(benchmark, big_table: pd.DataFrame) -> None:
    table = big_table.iloc[:REFERENCE_ROWS]
    benchmark.group = "features"
    result = benchmark(reference_features, table, PARAMS)
    _record_rate(benchmark, REFERENCE_ROWS)
    np.testing.assert_allclose(result, compute_features(table, PARAMS), rtol=1e-9, atol=1e-9)
