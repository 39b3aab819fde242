"""Independent fits spread over worker processes, one thread each.

Every learning stage fits many models that do not depend on one another: the folds of a
cross-validation, the held-out and per-family fits, the refits that are saved. On the standard
dataset (about 15,000 grips) each takes seconds, so they run in ``learning.workers`` processes
(joblib's loky pool), each with its native thread pools at one thread
(:func:`classifiers.learners.threads.single_threaded`). A fit is seeded by its own estimator
alone, so the fitted models are the same whatever the number of workers. Below
:data:`PARALLEL_MIN_GRIPS` training grips, starting the processes costs more than it saves and
everything runs in this one.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Any, TypeVar

import numpy as np
import pandas as pd
from joblib import Parallel, delayed
from sklearn.base import BaseEstimator

from classifiers.learners.threads import single_threaded
from grip_env.shutdown import raise_if_signalled

#: The fewest training grips whose fits are spread over ``learning.workers`` processes.
PARALLEL_MIN_GRIPS = 2000

Result = TypeVar("Result")
#: One fit: an unfitted estimator, its training table and its target.
Fit = tuple[BaseEstimator, pd.DataFrame, np.ndarray]


def worker_count(grips: int, workers: int, jobs: int) -> int:
    """The processes ``jobs`` fits on ``grips`` training grips are run in."""
    return max(1, min(workers if grips >= PARALLEL_MIN_GRIPS else 1, jobs))


def run_all(task: Callable[..., Result], jobs: Sequence[tuple[Any, ...]], grips: int,
            workers: int) -> list[Result]:
    """``[task(*job) for job in jobs]``, in order, each call on one thread, in up to
    ``workers`` processes when ``grips`` is at least :data:`PARALLEL_MIN_GRIPS`. A stop signal
    that a job's library code lost stops the work at the job's end
    (:func:`grip_env.shutdown.raise_if_signalled`)."""
    if not jobs:
        return []
    count = worker_count(grips, workers, len(jobs))
    if count == 1:
        done: Iterable[Result] = (_one_thread(task, *job) for job in jobs)
    else:
        done = Parallel(n_jobs=count, return_as="generator")(
            delayed(_one_thread)(task, *job) for job in jobs)
    found = []
    for result in done:
        raise_if_signalled()
        found.append(result)
    return found


def fit_all(fits: Iterable[Fit], workers: int) -> list[BaseEstimator]:
    """Each ``(estimator, X, y)`` fitted (the estimator itself when fitted here, a fitted copy
    when fitted in a worker); returned in order."""
    fits = list(fits)
    grips = max((len(X) for _, X, _ in fits), default=0)
    return run_all(_fit, fits, grips, workers)


def _fit(estimator: BaseEstimator, X: pd.DataFrame, y: np.ndarray) -> BaseEstimator:
    return estimator.fit(X, y)


def _one_thread(task: Callable[..., Result], *args: Any) -> Result:
    with single_threaded():
        return task(*args)
