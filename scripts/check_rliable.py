r"""Cross-check of classifiers.experiments.benchmark.aggregate against rliable (not a grip-env
dependency).

rliable 1.2.0 needs arch, which pulls statsmodels; install them aside, not into the venv:

    .venv/bin/python -m pip install --no-deps --target /tmp/rl rliable==1.2.0 arch==8.0.0 \
        statsmodels patsy absl-py
    # arch 8 renamed IIDBootstrap's random_state to seed; rliable 1.2.0 still passes the old name:
    sed -i 's/random_state=random_state, \*\*kwargs)/seed=random_state, **kwargs)/' \
        /tmp/rl/rliable/library.py
    PYTHONPATH=/tmp/rl:. .venv/bin/python scripts/check_rliable.py

Point estimates (IQM, mean, probability of improvement, performance profile) must agree
exactly; the bootstrap intervals (different random streams) to Monte-Carlo error.
"""

from __future__ import annotations

import numpy as np
from rliable import library as rly
from rliable import metrics

from classifiers.experiments.benchmark import aggregate as ours

REPS = 20_000


def main() -> None:
    rng = np.random.default_rng(0)
    scores = {"normal": rng.normal(0.5, 0.3, (5, 13)), "other": rng.normal(0.4, 0.3, (5, 13)),
              "discrete": rng.choice([0.0, 0.5, 1.0], size=(5, 13))}  # fmt: skip
    taus = np.linspace(-1, 2, 31)
    profiles, _ = rly.create_performance_profile(scores, taus, reps=200)
    for name, m in scores.items():
        assert np.isclose(metrics.aggregate_iqm(m), ours.iqm(m)), name
        assert np.isclose(metrics.aggregate_mean(m), ours.mean(m)), name
        assert np.allclose(profiles[name], ours.performance_profile(m, taus)), name
        poi = metrics.probability_of_improvement(m, scores["discrete"])
        assert np.isclose(poi, ours.probability_of_improvement(m, scores["discrete"])), name
    print("point estimates: identical")
    both = lambda x: np.array([metrics.aggregate_iqm(x), metrics.aggregate_mean(x)])  # noqa: E731
    for task_bootstrap in (False, True):
        _, theirs = rly.get_interval_estimates(scores, both, reps=REPS,
                                               task_bootstrap=task_bootstrap,
                                               random_state=np.random.RandomState(1))
        for name, m in scores.items():
            mine = [ours.stratified_bootstrap(m, f, REPS, 2, task_bootstrap)["ci"]
                    for f in (ours.iqm, ours.mean)]  # fmt: skip
            print(f"task_bootstrap={task_bootstrap!s:5} {name:>8}: IQM rliable "
                  f"{np.round(theirs[name][:, 0], 4)} ours {np.round(mine[0], 4)}; mean rliable "
                  f"{np.round(theirs[name][:, 1], 4)} ours {np.round(mine[1], 4)}")


if __name__ == "__main__":
    main()
