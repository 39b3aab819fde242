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

When the environment replays trials by index (data recording every trial's outcome: an
episode's attempts replay one trial k), both are means over k instead
(:func:`shared_random_return`, :func:`shared_oracle_return`): at k, ``f_k`` of the ``n``
candidates failed, and a uniform ``m``-subset all fails with probability
``C(f_k, m) / C(n, m)``; the oracle's order (highest rates first, ties to the lower slot) fails
when each of its first ``m`` grips failed at k. With one attempt they equal the formulas above.
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


def shared_random_return(held: NDArray[np.bool_], max_attempts: int) -> float:
    """:func:`random_return` when the attempts replay one trial k: ``held`` is (candidates,
    trials), each candidate's recorded outcome at every k."""
    n = held.shape[0]
    m = min(max_attempts, n)
    failed = n - held.sum(axis=0)
    return float(1.0 - np.mean([comb(int(f), m) for f in failed]) / comb(n, m))


def shared_oracle_return(held: NDArray[np.bool_], rates: NDArray[np.float64],
                         max_attempts: int) -> float:
    """:func:`oracle_return` when the attempts replay one trial k (highest ``rates`` first,
    ties to the lower slot)."""
    order = np.argsort(-rates, kind="stable")[:max_attempts]
    return float(held[order].any(axis=0).mean())


def reference_returns(sets: Sequence[CandidateSet], max_attempts: int,
                      trials: int = 0) -> tuple[float, float]:
    """(random, oracle) expected return per episode over the objects of ``sets``; with
    ``trials`` the attempts replay one trial index k (``trial_success_0..trials-1``)."""
    rates = [s.success_rate[: s.count] for s in sets if s.count]
    if not rates or any(np.isnan(r).any() for r in rates):
        raise ValueError("reference returns need recorded success rates of every candidate")
    if trials:
        from grip_env.columns import trial_success_columns

        columns = list(trial_success_columns(trials))
        held = [s.rows[columns].to_numpy(bool) for s in sets if s.count]
        low = float(np.mean([shared_random_return(h, max_attempts) for h in held]))
        high = float(np.mean([shared_oracle_return(h, r, max_attempts)
                              for h, r in zip(held, rates, strict=True)]))  # fmt: skip
        return low, high
    low = float(np.mean([random_return(r, max_attempts) for r in rates]))
    high = float(np.mean([oracle_return(r, max_attempts) for r in rates]))
    return low, high
