"""Exact expected returns of the uniform-random and the oracle policy on ``GripSelect-v0``.

Minari normalises a score with ``ref_min_score`` (a random policy's mean return) and
``ref_max_score`` (an expert's). Replay draws each execution as ``Bernoulli(p)`` with the grip's
recorded success rate ``p``, rewarding 1 for a hold and 0 for a drop, and an episode draws its
object uniformly; so both are exact expectations, not Monte-Carlo estimates:

- random (uniform over the valid slots, without repeats): ``1 - E[prod_{i in S} (1 - p_i)]``
  for ``S`` a uniform subset of ``m = min(max_attempts, n)`` of the ``n`` candidates, whose
  expectation is ``e_m(1 - p) / C(n, m)`` (``e_m``: the elementary symmetric polynomial);
- oracle (the highest recorded success rates first): ``1 - prod_{top m} (1 - p_i)``;

each averaged over the objects with a candidate.
"""

from __future__ import annotations

from collections.abc import Sequence
from math import comb

import numpy as np
from numpy.typing import NDArray

from grip_env.envs.observation import CandidateSet


def elementary_symmetric(values: NDArray[np.float64], order: int) -> float:
    """``e_order(values)``: the sum over all subsets of ``order`` values of their product."""
    e = np.zeros(order + 1)
    e[0] = 1.0
    for value in values:  # e_j <- e_j + value * e_{j-1}, highest j first
        e[1:] = e[1:] + value * e[:-1]
    return float(e[order])


def random_return(rates: NDArray[np.float64], max_attempts: int) -> float:
    """Expected return of a uniform pick without repeats among candidates of ``rates``."""
    m = min(max_attempts, len(rates))
    return 1.0 - elementary_symmetric(1.0 - rates, m) / comb(len(rates), m)


def oracle_return(rates: NDArray[np.float64], max_attempts: int) -> float:
    """Expected return of picking the highest success rates first."""
    top = np.sort(rates)[::-1][:max_attempts]
    return float(1.0 - np.prod(1.0 - top))


def reference_returns(sets: Sequence[CandidateSet], max_attempts: int) -> tuple[float, float]:
    """(random, oracle) expected return per episode over the objects of ``sets``."""
    rates = [s.success_rate[: s.count] for s in sets if s.count]
    if not rates or any(np.isnan(r).any() for r in rates):
        raise ValueError("reference returns need recorded success rates of every candidate")
    low = float(np.mean([random_return(r, max_attempts) for r in rates]))
    high = float(np.mean([oracle_return(r, max_attempts) for r in rates]))
    return low, high
