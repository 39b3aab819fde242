"""Exact comparison of grip selectors on held-out objects.

Every selector sees the same candidates of each test object (the ``max_candidates`` best by
``Q_C``, as ``GripSelect-v0`` shows them) and orders them; the recorded ``success_rate`` of a grip
is taken as its probability of holding, so each object's score is an expectation, with no
sampling noise:

- ``success_rate``: probability that the first pick holds;
- ``success_within_attempts``: the chance that one of the first ``max_attempts`` picks holds;
- ``expected_attempts``: expected number of grips executed, stopping at the first hold or after
  ``max_attempts``.

Attempts share the object's draw when the dataset records every trial's outcome
(``trial_success_0..T-1``): an episode's attempts replay one trial index k, as
``GripSelect-v0`` replays such data, so both are means over k of the picks' recorded trial k
(:func:`shared_attempt_metrics`; a draw that defeats one grip tends to defeat the next). Without
them the attempts are taken as independent, ``1 - prod(1 - p)`` and ``sum_j prod_{i<j}(1 - p_i)``
over the picks' success rates (:func:`attempt_metrics`), which overstates what a retry gains;
the result's ``attempts`` entry says which (:func:`attempt_scoring`).

Selectors: ``rl`` (the trained policy, deterministic; after a failure the tried slot is masked and
the policy asked again, as in the environment), ``random`` (exact expectation over uniformly
random orders, by elementary symmetric polynomials), ``best_qc`` (lowest ``Q_C`` first),
``best_qg`` (lowest ``Q_G`` first), ``classifier_<name>`` (each configured classifier among
"logreg"/"svm", fitted on the training objects' grips, highest ranking score first; each is
reported, so nothing is chosen on the test objects) and ``oracle`` (highest ``success_rate``
first: it holds whenever a holding grip exists).

When the dataset has the graded outcome, each selector also gets ``first_pick_robustness``: the
recorded ``robustness_mean`` (g) of its first pick (random: the mean over the candidates), and
``oracle_robustness`` orders by ``robustness_mean`` (the best first pick that reward can give).

Interval: 95% percentile bootstrap over test objects (the unit of generalisation), the same
resampled objects for every selector; ``n_boot`` resamples from a generator seeded with
``config.learning.seed``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from math import comb
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from classifiers.experiments.selector.data import check_grip_table
from grip_env.columns import trial_success_columns
from grip_env.config import Config
from grip_env.dataset.shards import recorded_trial_successes
from grip_env.dataset.split import held_out_objects
from grip_env.envs.observation import CandidateSet, candidate_sets
from grip_env.envs.select import GripSelectEnv

CLASSIFIER_CHOICES: tuple[str, ...] = ("logreg", "svm")
METRICS: tuple[str, ...] = ("success_rate", "success_within_attempts", "expected_attempts")
ROBUSTNESS_METRIC = "first_pick_robustness"
Ranker = Callable[[CandidateSet], NDArray[np.intp]]
#: (first-pick success, success within attempts, expected attempts).
Attempts = tuple[float, float, float]


def attempt_metrics(p: NDArray[np.float64], max_attempts: int) -> tuple[float, float, float]:
    """(first-pick success, success within attempts, expected attempts) of picks in order ``p``."""
    picks = np.asarray(p, dtype=float)[:max_attempts]
    survive = np.concatenate([[1.0], np.cumprod(1.0 - picks)])
    return float(picks[0]), float(1.0 - survive[-1]), float(survive[:-1].sum())


def random_metrics(p: NDArray[np.float64], max_attempts: int) -> tuple[float, float, float]:
    """:func:`attempt_metrics` averaged exactly over all orders of ``p`` (random picks)."""
    fail = 1.0 - np.asarray(p, dtype=float)
    n, m = fail.size, min(max_attempts, fail.size)
    # e_j: elementary symmetric polynomials of the failure probabilities (coefficients of
    # prod(1 + q_i x)); a uniformly random j-subset all fails with probability e_j / C(n, j).
    elementary = np.array([1.0])
    for q in fail:
        elementary = np.concatenate([elementary, [0.0]]) + np.concatenate([[0.0], q * elementary])
    all_fail = np.array([elementary[j] / comb(n, j) for j in range(m + 1)])
    return float(1.0 - all_fail[1]), float(1.0 - all_fail[m]), float(all_fail[:m].sum())


def shared_attempt_metrics(held: NDArray[np.bool_], max_attempts: int) -> Attempts:
    """:func:`attempt_metrics` when the attempts share the object's draw: ``held`` is (picks,
    trials), each pick's recorded outcome at every trial index k in the order picked; an
    episode replays one k for all its attempts, so each figure is a mean over k."""
    picks = np.asarray(held, dtype=bool)[:max_attempts]
    failed_through = np.cumprod(~picks, axis=0)  # (attempts, trials): every pick so far failed
    survive = np.concatenate([[1.0], failed_through.mean(axis=1)])
    return float(picks[0].mean()), float(1.0 - survive[-1]), float(survive[:-1].sum())


def shared_random_metrics(held: NDArray[np.bool_], max_attempts: int) -> Attempts:
    """:func:`shared_attempt_metrics` averaged exactly over all orders of the candidates
    (``held``: (candidates, trials)): at trial k, with ``f_k`` candidates that failed, a
    uniformly random j-subset all fails with probability ``C(f_k, j) / C(n, j)``."""
    from scipy.special import comb as combinations

    n = held.shape[0]
    m = min(max_attempts, n)
    failed = n - np.asarray(held, dtype=bool).sum(axis=0)
    j = np.arange(m + 1)
    each_k = combinations(failed[None, :], j[:, None]) / combinations(n, j)[:, None]
    all_fail = each_k.mean(axis=1)
    return float(1.0 - all_fail[1]), float(1.0 - all_fail[m]), float(all_fail[:m].sum())


def attempt_scoring(table: pd.DataFrame) -> dict[str, Any]:
    """How attempts are scored on ``table``: ``{"draws": "shared" or "independent", "trials",
    "note"}``; shared when it records every trial's outcome, else the independence formula,
    and the note says why."""
    trials = recorded_trial_successes(table.columns)
    if trials:
        return {"draws": "shared", "trials": trials,
                "note": f"attempts share the object's draw: the mean over the {trials} recorded "
                        "trial indices k of the picks' outcomes at k, as GripSelect-v0 replays "
                        "them"}  # fmt: skip
    return {"draws": "independent", "trials": 0,
            "note": "attempts taken as independent, 1 - prod(1 - p) over the picks' success "
                    "rates, because the dataset does not record each trial's outcome "
                    "(trial_success_0..T-1): this overstates what a retry gains when one draw "
                    "defeats several grips"}  # fmt: skip


def trial_outcomes(found: CandidateSet, trials: int) -> NDArray[np.bool_]:
    """(candidates, trials) recorded outcome of each kept candidate at each trial index."""
    return recorded_outcomes(found.rows, trials, found.object_id)


def recorded_outcomes(rows: pd.DataFrame, trials: int, object_id: str) -> NDArray[np.bool_]:
    """(rows, trials) of ``trial_success_0..trials-1``; ValueError when one is missing (a table
    whose trials are recorded for some objects only), rather than a NaN read as a hold."""
    values = rows[list(trial_success_columns(trials))]
    if values.isna().to_numpy().any():
        raise ValueError(f"object {object_id!r} lacks some of its trials' outcomes "
                         f"(trial_success_0..{trials - 1}): score attempts on objects that "
                         f"record every trial, or drop those columns to assume independence")
    return values.to_numpy(bool)


def action_probabilities(model: Any, sets: Sequence[CandidateSet],
                         masks: NDArray[np.int8] | None = None) -> NDArray[np.float64]:
    """(sets, K) probability of the policy picking each slot of each set (masked softmax), in
    one batched forward pass; ``masks`` replaces the sets' own masks (slots already tried, and
    failed: a policy whose observation has ``failed`` (the retry setting) sees them there)."""
    import torch as th

    if masks is None:
        masks = np.stack([found.mask for found in sets])
    observation = {"features": np.stack([found.features for found in sets]), "mask": masks}
    if "failed" in getattr(model.observation_space, "spaces", {}):
        observation["failed"] = np.stack([found.mask for found in sets]) - masks
    tensor, _ = model.policy.obs_to_tensor(observation)
    with th.no_grad():
        distribution = model.policy.get_distribution(tensor, action_masks=masks > 0)
        return distribution.distribution.probs.cpu().numpy().astype(np.float64)


def policy_orders(model: Any, sets: Sequence[CandidateSet],
                  max_attempts: int) -> list[NDArray[np.intp]]:
    """The slots the deterministic policy tries in turn on each set, each failure masked as the
    environment does: one batched forward pass an attempt, not one a set."""
    counts = np.array([found.count for found in sets])
    tries = np.minimum(counts, max_attempts)
    masks = np.stack([found.mask for found in sets]) if sets else np.zeros((0, 0), np.int8)
    orders = np.zeros((len(sets), int(tries.max(initial=0))), dtype=np.intp)
    for attempt in range(orders.shape[1]):
        trying = np.flatnonzero(tries > attempt)
        picks = action_probabilities(model, [sets[i] for i in trying], masks[trying]).argmax(axis=1)
        orders[trying, attempt] = picks
        masks[trying, picks] = 0
    return [order[:n] for order, n in zip(orders, tries, strict=True)]


def order_scores(order: NDArray[np.intp], count: int) -> NDArray[np.float64]:
    """Scores ``count - j`` for the j-th slot of ``order`` (0 for slots it never reaches): a
    static order of them is ``order``, as a policy's picks after each failure make it."""
    scores = np.zeros(count)
    scores[order] = count - np.arange(len(order))
    return scores


def _ascending(column: str) -> Ranker:
    return lambda found: np.argsort(found.rows[column].to_numpy(float), kind="stable")


def _precomputed(sets: Sequence[CandidateSet], orders: Sequence[NDArray[np.intp]]) -> Ranker:
    by_object = {found.object_id: order for found, order in zip(sets, orders, strict=True)}
    return lambda found: by_object[found.object_id]


def _oracle(found: CandidateSet) -> NDArray[np.intp]:
    return np.argsort(-found.success_rate[: found.count], kind="stable")


def _robustness_oracle(found: CandidateSet) -> NDArray[np.intp]:
    return np.argsort(-found.rows["robustness_mean"].to_numpy(float), kind="stable")


def _classifier_ranker(model: Any) -> Ranker:
    from classifiers.evaluation.cross_validation import ranking_score

    return lambda found: np.argsort(-ranking_score(model, found.rows), kind="stable")


def fit_classifiers(
    train: pd.DataFrame, config: Config, names: Sequence[str] | None = None
) -> dict[str, Any]:
    """Fit the configured classifiers (among "logreg", "svm") on the training grips.

    Returns an empty dict when the ``classifiers`` models are not available or the training grips
    hold a single class.
    """
    try:
        from classifiers.learners.models import make_model
    except ImportError:
        return {}
    chosen = (
        names
        if names is not None
        else [name for name in config.learning.models if name in CLASSIFIER_CHOICES] or ["logreg"]
    )
    if train["success"].nunique() < 2:
        return {}
    return {name: make_model(name, config.learning.seed).fit(train, train["success"])
            for name in chosen}  # fmt: skip


def bootstrap_interval(values: NDArray[np.float64], resamples: NDArray[np.intp]) -> dict[str, Any]:
    """Mean and 95% percentile interval of ``values`` over object resamples."""
    means = values[resamples].mean(axis=1)
    low, high = np.percentile(means, [2.5, 97.5])
    return {"mean": float(values.mean()), "ci": [float(low), float(high)]}


def training_baselines(table: pd.DataFrame, config: Config,
                       objects: Sequence[str] | None = None) -> dict[str, float]:
    """Expected episode reward of random, best-Q_C and oracle picks on the training objects
    (those of them in ``objects`` when given: the ones a retry selector trained on).

    Objects are drawn uniformly per episode, each showing its ``max_candidates`` best by Q_C.
    Success reward: the chance of a hold within ``max_attempts``, with the attempts sharing
    the episode's trial when ``table`` records every trial's outcome (:func:`attempt_scoring`);
    robustness reward (one attempt only): the first pick's ``robustness_mean /
    sim.reference_level_g``. Empty when the episode reward has no closed form (robustness with
    several attempts).
    """
    learning, selector = config.learning, config.selector
    robust = selector.reward == "robustness"
    if robust and (selector.max_attempts > 1 or "robustness_mean" not in table.columns):
        return {}
    ids = table["object_id"].astype(str)
    train_ids, _ = held_out_objects(ids, learning)
    if objects is not None:
        kept = set(objects)
        train_ids = tuple(o for o in train_ids if o in kept)
    trials = recorded_trial_successes(table.columns)
    rows: dict[str, list[float]] = {"random": [], "best Q_C": [], "oracle": []}
    for _, frame in table[ids.isin(train_ids).to_numpy()].groupby("object_id"):
        shown = frame.sort_values("Q_C", kind="stable").head(selector.max_candidates)
        if robust:
            value = shown["robustness_mean"].to_numpy(float) / config.sim.reference_level_g
            rows["random"].append(value.mean())
            rows["best Q_C"].append(value[0])
            rows["oracle"].append(value.max())
            continue
        p = shown["success_rate"].to_numpy(float)
        best = np.argsort(-p, kind="stable")
        if trials:
            held = recorded_outcomes(shown, trials, str(shown["object_id"].iloc[0]))
            rows["random"].append(shared_random_metrics(held, selector.max_attempts)[1])
            rows["best Q_C"].append(shared_attempt_metrics(held, selector.max_attempts)[1])
            rows["oracle"].append(shared_attempt_metrics(held[best], selector.max_attempts)[1])
            continue
        rows["random"].append(random_metrics(p, selector.max_attempts)[1])
        rows["best Q_C"].append(attempt_metrics(p, selector.max_attempts)[1])
        rows["oracle"].append(attempt_metrics(p[best], selector.max_attempts)[1])
    return {name: float(np.mean(v)) for name, v in rows.items() if v}


def evaluate_selectors(
    model: Any,
    data: pd.DataFrame,
    config: Config,
    classifiers: Sequence[str] | None = None,
    n_boot: int = 2000,
) -> dict[str, Any]:
    """Compare the RL selector with the baselines on the test objects (see the module docstring).

    Returns:
        ``{"policies": {name: {metric: {"mean", "ci"}, "per_object": [...]}}, "split": {...},
        "max_attempts", "max_candidates", "attempts", "interval"}``; ``attempts`` says whether
        the attempts shared the object's draw or were taken as independent, and why
        (:func:`attempt_scoring`).
    """
    table = check_grip_table(data)
    ids = table["object_id"].astype(str)
    learning, selector = config.learning, config.selector
    train_ids, test_ids = held_out_objects(ids, learning)
    sets = _test_candidate_sets(table, config, test_ids)
    if not sets:
        raise ValueError("no test object has a candidate grip")
    rankers: dict[str, Ranker] = {
        "rl": _precomputed(sets, policy_orders(model, sets, selector.max_attempts)),
        "best_qc": _ascending("Q_C"),
        "best_qg": _ascending("Q_G"),
    }
    fitted = fit_classifiers(table[ids.isin(train_ids).to_numpy()], config, classifiers)
    rankers.update({f"classifier_{name}": _classifier_ranker(m) for name, m in fitted.items()})
    robust = "robustness_mean" in table.columns
    scoring = attempt_scoring(table)
    rankers["oracle"] = _oracle
    if robust:
        rankers["oracle_robustness"] = _robustness_oracle
    trials = scoring["trials"]
    scores = {name: _score(sets, rank, selector.max_attempts, robust, trials)
              for name, rank in rankers.items()}  # fmt: skip
    scores["random"] = np.array([
        [*(shared_random_metrics(trial_outcomes(s, trials), selector.max_attempts) if trials
           else random_metrics(s.success_rate[: s.count], selector.max_attempts)),
         *([float(s.rows["robustness_mean"].mean())] if robust else [])]
        for s in sets
    ])  # fmt: skip
    resamples = np.random.default_rng(learning.seed).integers(len(sets), size=(n_boot, len(sets)))
    metrics = (*METRICS, ROBUSTNESS_METRIC) if robust else METRICS
    policies = {name: _summary(values, resamples, metrics) for name, values in scores.items()}
    return {
        "policies": policies,
        "split": {"train": list(train_ids), "test": [s.object_id for s in sets],
                  "test_fraction": learning.test_fraction, "seed": learning.seed},
        "max_attempts": selector.max_attempts,
        "max_candidates": selector.max_candidates,
        "attempts": scoring,
        "reward": selector.reward,
        "interval": f"95% percentile bootstrap over test objects, {n_boot} resamples",
    }  # fmt: skip


def held_out_candidate_sets(table: pd.DataFrame, config: Config) -> list[CandidateSet]:
    """The candidate sets of the held-out objects (:func:`~grip_env.dataset.held_out_objects`)."""
    _, test_ids = held_out_objects(table["object_id"].astype(str), config.learning)
    return _test_candidate_sets(table, config, test_ids)


def _test_candidate_sets(
    table: pd.DataFrame, config: Config, test_ids: Sequence[str]
) -> list[CandidateSet]:
    """The test objects' candidates, scaled exactly as the training environment scales them."""
    train_env = GripSelectEnv(data=table, config=config, split="train")
    scaler, k = train_env.scaler, train_env.max_candidates
    train_env.close()
    frames = dict(iter(table.groupby(table["object_id"].astype(str), sort=True)))
    found = [oid for oid in test_ids if oid in frames]
    sets = candidate_sets(found, [frames[oid] for oid in found], scaler, k)
    return [found for found in sets if found.count]


def _summary(values: NDArray[np.float64], resamples: NDArray[np.intp],
             metrics: Sequence[str] = METRICS) -> dict[str, Any]:
    """Each metric's mean and interval, and the per-object first-pick success."""
    summary: dict[str, Any] = {
        metric: bootstrap_interval(values[:, k], resamples) for k, metric in enumerate(metrics)
    }
    summary["per_object"] = values[:, 0].round(6).tolist()
    return summary


def _score(sets: list[CandidateSet], rank: Ranker, max_attempts: int,
           robust: bool = False, trials: int = 0) -> NDArray[np.float64]:
    """(objects, metrics) array of :func:`attempt_metrics`, or with ``trials`` recorded by index
    :func:`shared_attempt_metrics` (and the first pick's robustness)."""
    rows = []
    for found in sets:
        order = rank(found)
        row = list(shared_attempt_metrics(trial_outcomes(found, trials)[order], max_attempts)
                   if trials else attempt_metrics(found.success_rate[order], max_attempts))
        if robust:
            row.append(float(found.rows["robustness_mean"].to_numpy(float)[order[0]]))
        rows.append(row)
    return np.array(rows)
