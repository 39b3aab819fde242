"""Selection metrics: how good the grip a method picks is, per object, computed exactly.

Input: the candidates of each held-out object with their recorded outcomes (``success_rate``,
the grip's probability of holding; ``robustness_mean``, the highest disturbance held, g) and a
method's ``score`` per candidate (higher = pick first), for one or several runs (``seed``).

Ties in a method's scores are broken uniformly at random, and every metric is its exact
expectation over those tie-breaks (no sampling): a tie group of size ``g`` spanning the positions
``a .. a+g-1`` gives each member the mean of those positions' weights. So a method whose scores
are all equal *is* the random picker, and a choice (one index) is a score of 1 for the chosen
candidate and 0 for the rest (the rest in random order).

Per (method, seed, object):

- ``success``: expected success rate of the top-1 pick; ``robustness``: its expected
  ``robustness_mean``;
- ``regret``: ``max(success_rate) - success`` (the oracle in hindsight, from the recorded
  trials); ``robustness_regret`` likewise;
- ``ndcg5``: NDCG@5 with the success rate as linear gain, discount ``1 / log2(1 + position)``;
  NaN when no candidate ever held (every order is ideal: the object says nothing);
- ``normalised``: ``(success - random) / (oracle - random)``, random = the mean success rate of
  the candidates (the exact expectation of a uniform pick), oracle = the maximum. 0 is random,
  1 the oracle. When ``oracle == random`` (all candidates share one success rate) every pick is
  the oracle's: the score is NaN and the object is left out of the aggregates (it cannot tell
  methods apart), for every method alike;
- ``success_at_k`` (k = 1..5): chance that one of the top-k picks holds, ``1 - prod(1 - p)``
  over them, assuming the grips' trials are independent Bernoulli draws with the recorded rates
  (what the replay backend of ``GripSelect-v0``/``GripAccept-v0`` draws). Under that assumption
  the chance depends only on the set of grips tried, not their order, so it is also what an
  agent of ``GripAccept-v0`` that executes exactly these k candidates earns. Tie groups that the
  budget cuts through are averaged exactly over random subsets (elementary symmetric
  polynomials of the failure probabilities, from power sums by Newton's identities);
- ``attempts``: expected number of grips executed with a budget of 5 attempts (or all the
  candidates, when fewer), stopping at the first hold.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.special import comb

KEYS = ("method", "seed", "object_id")
NDCG_DEPTH = 5
MAX_ATTEMPTS = 5
METRICS = ("success", "robustness", "regret", "robustness_regret", "ndcg5", "normalised",
           *(f"success_at_{k}" for k in range(1, MAX_ATTEMPTS + 1)), "attempts")  # fmt: skip
#: Degenerate object: oracle and random success closer than this.
DEGENERATE = 1e-12


def check_candidates(candidates: pd.DataFrame) -> pd.DataFrame:
    """The checked candidate table: ``object_id``, ``candidate``, ``success_rate`` (and
    ``robustness_mean``, NaN when not recorded)."""
    needed = ["object_id", "candidate", "success_rate"]
    missing = [c for c in needed if c not in candidates.columns]
    if missing:
        raise ValueError(f"candidate table lacks the columns {missing}")
    rate = candidates["success_rate"].to_numpy(float)
    if not np.all(np.isfinite(rate)) or rate.min() < 0 or rate.max() > 1:
        raise ValueError("success_rate must be finite and within [0, 1] for every candidate")
    if candidates.duplicated(["object_id", "candidate"]).any():
        raise ValueError("candidate table repeats an (object_id, candidate) pair")
    frame = candidates.copy()
    if "robustness_mean" not in frame.columns:
        frame["robustness_mean"] = np.nan
    return frame


def object_references(candidates: pd.DataFrame) -> pd.DataFrame:
    """Per object: ``oracle`` (max success rate), ``random`` (mean), their robustness
    counterparts, the ideal DCG@5 and whether the object is degenerate (oracle == random)."""
    frame = check_candidates(candidates)
    by = frame.groupby("object_id", sort=True)
    position = by["success_rate"].rank(method="first", ascending=False).to_numpy(int) - 1
    ideal = frame["success_rate"].to_numpy(float) * _discount(position)
    refs = pd.DataFrame({
        "oracle": by["success_rate"].max(), "random": by["success_rate"].mean(),
        "oracle_robustness": by["robustness_mean"].max(),
        "random_robustness": by["robustness_mean"].mean(),
        "idcg": pd.Series(ideal, index=frame.index).groupby(frame["object_id"]).sum(),
        "candidates": by.size(),
    })  # fmt: skip
    refs["degenerate"] = (refs["oracle"] - refs["random"]) <= DEGENERATE
    return refs


def selection_metrics(candidates: pd.DataFrame, scores: pd.DataFrame) -> pd.DataFrame:
    """Per (method, seed, object) metrics of the module docstring, one row each.

    Args:
        candidates: one row per (object_id, candidate) with ``success_rate`` (and
            ``robustness_mean`` when recorded).
        scores: ``method``, ``seed``, ``object_id``, ``candidate``, ``score``: every candidate of
            every object scored once per (method, seed).
    """
    frame = _scored(check_candidates(candidates), scores)
    keys = list(KEYS)
    grouped = frame.groupby(keys, sort=True)["score"]
    start = grouped.rank(method="min", ascending=False).to_numpy(int) - 1
    stop = grouped.rank(method="max", ascending=False).to_numpy(int)
    size = stop - start
    p = frame["success_rate"].to_numpy(float)
    first = (start == 0) / size
    cumulative = np.concatenate([[0.0], np.cumsum(_discount(np.arange(stop.max())))])
    mean_discount = (cumulative[stop] - cumulative[start]) / size
    per_row = pd.DataFrame({
        "success": first * p, "robustness": first * frame["robustness_mean"].to_numpy(float),
        "dcg": mean_discount * p,
    })  # fmt: skip
    out = per_row.groupby([frame[k] for k in keys], sort=True).sum(min_count=1)
    out = out.join(_within_attempts(frame, start, size))
    refs = object_references(candidates)
    ref = refs.loc[out.index.get_level_values("object_id")]
    values = {name: ref[name].to_numpy() for name in refs.columns}
    out["regret"] = values["oracle"] - out["success"].to_numpy()
    out["robustness_regret"] = values["oracle_robustness"] - out["robustness"].to_numpy()
    idcg = values["idcg"].astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        out["ndcg5"] = np.where(idcg > 0, out["dcg"].to_numpy() / idcg, np.nan)
        spread = values["oracle"] - values["random"]
        normalised = (out["success"].to_numpy() - values["random"]) / spread
    out["normalised"] = np.where(values["degenerate"].astype(bool), np.nan, normalised)
    return out.drop(columns="dcg")[list(METRICS)].reset_index()


def _scored(candidates: pd.DataFrame, scores: pd.DataFrame) -> pd.DataFrame:
    """Scores joined to outcomes; every (method, seed) must score exactly every candidate."""
    needed = [*KEYS, "candidate", "score"]
    missing = [c for c in needed if c not in scores.columns]
    if missing:
        raise ValueError(f"score table lacks the columns {missing}")
    if not np.all(np.isfinite(scores["score"].to_numpy(float))):
        bad = scores.loc[~np.isfinite(scores["score"].to_numpy(float)), "method"].unique()
        raise ValueError(f"methods {sorted(map(str, bad))} give NaN or infinite scores")
    if scores.duplicated([*KEYS, "candidate"]).any():
        raise ValueError("score table scores a candidate twice for one (method, seed)")
    frame = scores[needed].merge(
        candidates[["object_id", "candidate", "success_rate", "robustness_mean"]],
        on=["object_id", "candidate"], how="left", validate="many_to_one")  # fmt: skip
    if frame["success_rate"].isna().any():
        raise ValueError("score table scores candidates that are not in the candidate table")
    counts = frame.groupby(list(KEYS)).size()
    expected = candidates.groupby("object_id").size()
    runs = frame.groupby(["method", "seed"]).size()
    if not np.array_equal(counts.to_numpy(),
                          expected.loc[counts.index.get_level_values("object_id")].to_numpy()) or (
            runs.to_numpy() != expected.sum()).any():  # fmt: skip
        raise ValueError("every (method, seed) must score every candidate of every object")
    return frame


def _discount(position: np.ndarray) -> np.ndarray:
    """NDCG@5 weight of 0-based ``position``: ``1 / log2(position + 2)`` within depth 5, else 0."""
    position = np.asarray(position)
    return np.where(position < NDCG_DEPTH, 1.0 / np.log2(position + 2.0), 0.0)


def _within_attempts(frame: pd.DataFrame, start: np.ndarray, size: np.ndarray) -> pd.DataFrame:
    """``success_at_1..5`` and ``attempts`` per (method, seed, object), exact over tie-breaks."""
    q = 1.0 - frame["success_rate"].to_numpy(float)
    groups = frame[list(KEYS)].assign(start=start, size=size)
    powers = pd.DataFrame({f"p{j}": q**j for j in range(1, MAX_ATTEMPTS + 1)})
    sums = powers.groupby([groups[c] for c in groups.columns], sort=True).sum().reset_index()
    elementary = _elementary(sums[[f"p{j}" for j in range(1, MAX_ATTEMPTS + 1)]].to_numpy())
    g, a = sums["size"].to_numpy(int), sums["start"].to_numpy(int)
    budgets = np.arange(0, MAX_ATTEMPTS + 1)
    tried = np.clip(budgets[None, :] - a[:, None], 0, g[:, None])  # members tried per budget
    subsets = comb(g[:, None], tried)
    fail = np.take_along_axis(elementary, tried, axis=1) / subsets
    table = pd.DataFrame(fail, columns=[f"f{k}" for k in budgets])
    all_fail = table.groupby([sums[k] for k in KEYS], sort=True).prod()
    out = pd.DataFrame(index=all_fail.index)
    for k in range(1, MAX_ATTEMPTS + 1):
        out[f"success_at_{k}"] = 1.0 - all_fail[f"f{k}"]
    count = frame.groupby(list(KEYS), sort=True).size().loc[all_fail.index].to_numpy()
    tries = np.arange(MAX_ATTEMPTS)[None, :] < count[:, None]  # no attempt beyond the candidates
    before = all_fail[[f"f{k}" for k in range(MAX_ATTEMPTS)]].to_numpy()
    out["attempts"] = (before * tries).sum(axis=1)
    return out


def _elementary(power_sums: np.ndarray) -> np.ndarray:
    """Elementary symmetric polynomials e_0..e_m from power sums p_1..p_m (Newton's identities)."""
    rows, m = power_sums.shape
    e = np.zeros((rows, m + 1))
    e[:, 0] = 1.0
    for n in range(1, m + 1):
        terms = [(-1) ** (i - 1) * e[:, n - i] * power_sums[:, i - 1] for i in range(1, n + 1)]
        e[:, n] = np.sum(terms, axis=0) / n
    return np.clip(e, 0.0, None)
