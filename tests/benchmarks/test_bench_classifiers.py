"""Training and prediction time of every model, and ε throughput.

Run ``python -m pytest tests/benchmarks/test_bench_classifiers.py --benchmark-enable``. The
100,000-grip cases run only with ``--benchmark-enable`` (SVM training is quadratic in the rows and
takes minutes there). Nothing about time is asserted; rates are in ``extra_info``.
"""

from __future__ import annotations

import pandas as pd
import pytest

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.learners.models import MODEL_NAMES, make_model
from grip_env.planning.epsilon import epsilon_quality

pytestmark = pytest.mark.slow

SIZES = {10_000: 400, 100_000: 4_000}  # grips → objects (25 grips per object on average)


@pytest.fixture(scope="module", params=list(SIZES), ids=lambda n: f"{n}grips")
def table(request) -> pd.DataFrame:
    grips = request.param
    if grips > 10_000 and not request.config.getoption("benchmark_enable", False):
        pytest.skip("100k-grip benchmarks run only with --benchmark-enable")
    return synthetic_grips(n_objects=SIZES[grips], grips=(10, 40), seed=0).iloc[:grips]


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_bench_train(benchmark, table: pd.DataFrame, name: str) -> None:
    benchmark.group = f"train {len(table)}"
    model = benchmark.pedantic(
        lambda: make_model(name, seed=0).fit(table, table["success"]), rounds=1, iterations=1
    )
    benchmark.extra_info["grips"] = len(table)
    assert model.predict_proba(table.iloc[:5]).shape == (5, 2)


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_bench_predict(benchmark, table: pd.DataFrame, name: str) -> None:
    benchmark.group = f"predict {len(table)}"
    model = make_model(name, seed=0).fit(table.iloc[:5_000], table["success"].iloc[:5_000])
    proba = benchmark.pedantic(model.predict_proba, args=(table,), rounds=3, iterations=1)
    benchmark.extra_info["grips"] = len(table)
    assert proba.shape == (len(table), 2)


@pytest.mark.parametrize("method", ["vectorised", "qhull"])
def test_bench_epsilon(benchmark, table: pd.DataFrame, method: str) -> None:
    benchmark.group = f"epsilon {len(table)}"
    eps = benchmark.pedantic(epsilon_quality, args=(table,), kwargs={"method": method}, rounds=2)
    benchmark.extra_info["grips"] = len(table)
    assert eps.shape == (len(table),)
