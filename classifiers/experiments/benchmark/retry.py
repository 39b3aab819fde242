"""The retry task: success within m attempts when the attempts share the object's draw.

A robot whose first grip slips tries again on the same object, under the same friction and mass.
The recorded trials share their draws across an object's grips (trial k of every grip met the
same friction, mass and pose noise), so for a static order of grips

    shared_at_m = mean over k of [any of the first m grips held at trial k]

is the chance of a hold within m attempts when an episode's attempts replay one trial index k
(``GripSelect-v0`` / ``GripAccept-v0`` with ``max_attempts = m`` on data with per-trial outcomes).
The leaderboard's ``success_at_m`` = ``1 - prod(1 - p)`` over the same grips treats the attempts
as independent; ``overstatement_at_m`` = ``success_at_m - shared_at_m`` is how much that
assumption adds (positive when failures go together: a draw that defeats one grip defeats
others).

Ties in a method's scores are broken uniformly at random, and ``shared_at_m`` is its exact
expectation over the tie-breaks: for one k, a tie group of size ``g`` with ``s`` grips that held
at k, cut by the budget after ``j`` of its members, fails with probability
``C(g - s, j) / C(g, j)``, and the groups fail independently of each other's order.

Needs the per-trial columns (:func:`grip_env.columns.trial_columns`): a dataset made by
``grip-env generate`` now, or the standard dataset's re-simulated trials
(:func:`grip_env.dataset.trial_outcomes.with_trial_outcomes`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy.special import comb

from classifiers.experiments.benchmark.aggregate import estimate, mean, paired_bootstraps
from classifiers.experiments.benchmark.leaderboard import REFERENCE, metric_matrices
from classifiers.experiments.benchmark.selection import KEYS, selection_metrics
from grip_env.columns import trial_success_columns
from grip_env.config import Config
from grip_env.dataset.shards import recorded_trial_successes

#: Attempts the retry task scores (success within 1, 2 and 3).
RETRY_ATTEMPTS = 3


def shared_columns(attempts: int = RETRY_ATTEMPTS) -> list[str]:
    """``shared_at_1`` .. ``shared_at_{attempts}``."""
    return [f"shared_at_{m}" for m in range(1, attempts + 1)]


def retry_metrics(candidates: pd.DataFrame, scores: pd.DataFrame,
                  attempts: int = RETRY_ATTEMPTS) -> pd.DataFrame:
    """Per (method, seed, object): ``shared_at_1..m`` (shared draws, exact over tie-breaks),
    the leaderboard's ``success_at_1..m`` (independent attempts), ``overstatement_at_1..m`` and
    ``ceiling`` (the share of trial indices at which some candidate held: what a policy that
    knew the draw would reach, in one attempt; no policy exceeds it).

    Args:
        candidates: one row per (object_id, candidate) with ``success_rate`` and the per-trial
            columns ``trial_success_0..T-1``.
        scores: the benchmark's score table (``method, seed, object_id, candidate, score``).

    Raises:
        ValueError: the candidates lack the per-trial columns, or ``attempts`` is not 1..5.
    """
    trials = recorded_trial_successes(candidates.columns)
    if not trials:
        raise ValueError("the retry task needs every trial's outcome (trial_success_0..T-1), "
                         "which these candidates do not record: generate the dataset again, or "
                         "add the re-simulated trials (grip_env.dataset.trial_outcomes)")
    if not 1 <= attempts <= 5:
        raise ValueError(f"attempts must be within 1..5, got {attempts!r}")
    independent = selection_metrics(candidates, scores).set_index(list(KEYS))
    frame = scores[[*KEYS, "candidate", "score"]].merge(
        candidates[["object_id", "candidate", *trial_success_columns(trials)]],
        on=["object_id", "candidate"], how="left", validate="many_to_one")
    grouped = frame.groupby(list(KEYS), sort=True)["score"]
    start = grouped.rank(method="min", ascending=False).to_numpy(int) - 1
    size = grouped.rank(method="max", ascending=False).to_numpy(int) - start
    held = frame[list(trial_success_columns(trials))].to_numpy(float)
    tie = frame[list(KEYS)].assign(start=start, size=size)
    sums = pd.DataFrame(held, columns=range(trials)).groupby(
        [tie[c] for c in tie.columns], sort=True).sum().reset_index()
    g, a = sums["size"].to_numpy(int), sums["start"].to_numpy(int)
    s = sums[list(range(trials))].to_numpy(float)  # members that held at trial k
    out = pd.DataFrame(index=independent.index)
    for m in range(1, attempts + 1):
        tried = np.clip(m - a, 0, g)[:, None]  # members of each tie group within the budget
        fail = comb(g[:, None] - s, tried) / comb(g[:, None], tried)
        all_fail = pd.DataFrame(fail).groupby([sums[k] for k in KEYS], sort=True).prod()
        shared = 1.0 - all_fail.mean(axis=1)
        out[f"shared_at_{m}"] = shared.loc[out.index].to_numpy()
        out[f"success_at_{m}"] = independent[f"success_at_{m}"]
        out[f"overstatement_at_{m}"] = out[f"success_at_{m}"] - out[f"shared_at_{m}"]
    columns = list(trial_success_columns(trials))
    any_held = candidates.groupby("object_id")[columns].any().mean(axis=1)
    out["ceiling"] = any_held.loc[out.index.get_level_values("object_id")].to_numpy()
    return out.reset_index()


def retry_leaderboard(metrics: pd.DataFrame, reps: int = 2000, seed: int = 0,
                      reference: str = REFERENCE, attempts: int = RETRY_ATTEMPTS,
                      ) -> dict[str, Any]:
    """Per method and m: ``shared_at_m`` (mean over objects and runs, 95 % stratified bootstrap
    interval), its difference from ``reference`` paired over the same resampled objects, and
    the overstatement of the independence formula with its interval; and ``ceiling``, the mean
    over objects of :func:`retry_metrics`' ceiling. Every object counts."""
    objects = sorted(set(metrics["object_id"]))
    ceiling = metrics.groupby("object_id")["ceiling"].first()
    board: dict[str, Any] = {"objects": len(objects), "attempts": attempts,
                             "reference": reference, "ceiling": float(ceiling.mean()),
                             "methods": {}}
    columns = [*shared_columns(attempts),
               *(f"overstatement_at_{m}" for m in range(1, attempts + 1))]
    matrices = {c: metric_matrices(metrics, c, objects) for c in columns}
    boots = {c: paired_bootstraps(matrices[c], reps, seed, task_bootstrap=True, objects=objects)
             for c in columns}
    for name in matrices[columns[0]]:
        row: dict[str, Any] = {"runs": int(matrices[columns[0]][name].shape[0])}
        for m in range(1, attempts + 1):
            shared, over = f"shared_at_{m}", f"overstatement_at_{m}"
            value, boot = matrices[shared], boots[shared]
            row[shared] = estimate(mean(value[name]), mean(boot[name]))
            row[f"{shared}_minus_{reference}"] = estimate(
                mean(value[name]) - mean(value[reference]),
                mean(boot[name]) - mean(boot[reference]))
            row[over] = estimate(mean(matrices[over][name]), mean(boots[over][name]))
        board["methods"][name] = row
    return board


#: A policy for the retry task: (observation, valid-action mask) -> the slot to execute.
RetryPolicy = Callable[[dict[str, np.ndarray], np.ndarray], int]


def policy_retry_metrics(table: pd.DataFrame, object_ids: Sequence[str], policy: RetryPolicy,
                         config: Config, name: str = "policy", seed: int = 0,
                         attempts: int = RETRY_ATTEMPTS) -> pd.DataFrame:
    """``shared_at_1..m`` of a (possibly adaptive) policy: for each object and each trial index
    k, one ``GripSelect-v0`` episode pinned to k (``reset(options={"object_id", "trial"})``,
    ``max_attempts = m``); the policy sees each failure (the failed slot masked) and may pick
    the next grip by it. ``shared_at_j`` = mean over k of [held within j attempts]. A
    deterministic policy makes this exact; rows ``method, seed, object_id, shared_at_*``.

    Raises:
        ValueError: ``table`` does not record every trial's outcome.
    """
    from grip_env.envs.select import GripSelectEnv

    trials = recorded_trial_successes(table.columns)
    if not trials:
        raise ValueError("the retry task needs every trial's outcome (trial_success_0..T-1)")
    env = GripSelectEnv(data=table, config=config, max_attempts=attempts, replay="trial")
    rows = []
    for object_id in object_ids:
        held_at = np.full((trials, attempts), False)
        for k in range(trials):
            observation, _ = env.reset(seed=seed, options={"object_id": object_id, "trial": k})
            for attempt in range(attempts):
                slot = int(policy(observation, env.action_masks()))
                observation, _, terminated, _, info = env.step(slot)
                if info["success"]:
                    held_at[k, attempt:] = True
                if terminated:
                    break
        rows.append({"method": name, "seed": seed, "object_id": object_id,
                     **dict(zip(shared_columns(attempts), held_at.mean(axis=0), strict=True))})
    env.close()
    return pd.DataFrame(rows)


def standard_retry_board(data: str = "standard", trials: str | Path | None = None,
                         scores: str | Path | None = None, reps: int = 2000,
                         config: Config | None = None,
                         agents: Sequence[tuple[str, str | Path]] = ()) -> dict[str, Any]:
    """The retry task on the standard split (v4) on the held-out objects whose every trial is
    recorded: in ``data`` itself, or (``trials``) in a folder of re-simulated shards
    (:func:`grip_env.dataset.trial_outcomes.with_trial_outcomes`). Methods: the baselines'
    static orders (best-Q_C, best-Q_G, random, oracle), from a study's ``scores`` file
    (``classifiers/scores.parquet``) its rankers and classifiers, every seed, and ``agents``:
    ``(name, SB3 zip)`` pairs, a name given n times its runs 0..n-1 (a retry policy, whose
    observation says which slots failed, is scored by the slots it picks after each failure:
    :func:`~classifiers.experiments.benchmark.methods.sb3_scores`).

    Raises:
        ValueError: no held-out object has its trials recorded, or the scores file does not
            score the split's candidates.
    """
    from classifiers.experiments.benchmark.methods import (
        baseline_scores,
        drop_duplicates,
        sb3_scores,
    )
    from classifiers.experiments.benchmark.split import (
        candidate_sets,
        candidate_table,
        standard_split,
    )
    from grip_env.columns import trial_columns
    from grip_env.config import load_config
    from grip_env.dataset.loading import load
    from grip_env.dataset.trial_outcomes import with_trial_outcomes
    from grip_env.datasets import resolve_data

    config = config or load_config()
    table = load(resolve_data(data))
    recorded = with_trial_outcomes(table, trials) if trials is not None else table
    count = recorded_trial_successes(recorded.columns)
    split = standard_split()
    have = set(recorded["object_id"].astype(str)) if count else set()
    held = [oid for oid in split.test_objects if oid in have]
    if not held:
        raise ValueError("no held-out object of the standard split has its trials recorded")
    bare = table.copy(deep=False)
    bare.attrs = {}
    sets = [found for found in candidate_sets(bare, config, split) if found.object_id in held]
    candidates = candidate_table(sets)
    candidates = candidates.drop(columns=[c for c in trial_columns(count)
                                          if c in candidates.columns]).merge(
        recorded[["grip_id", *trial_columns(count)]], on="grip_id", how="left",
        validate="one_to_one")  # fmt: skip
    frames = [baseline_scores(candidates).query("method != 'epsilon'")]
    if scores is not None:
        learned = drop_duplicates(pd.read_parquet(scores))
        learned = learned[learned["object_id"].astype(str).isin(held)]
        frames.append(learned.assign(object_id=learned["object_id"].astype(str)))
    runs: dict[str, int] = {}
    for name, path in agents:
        runs[name] = runs.get(name, -1) + 1
        frames.append(sb3_scores(Path(path), sets, runs[name], name))
    metrics = retry_metrics(candidates, pd.concat(frames, ignore_index=True))
    board = retry_leaderboard(metrics, reps, config.learning.seed)
    board["split"] = {"name": split.name, "version": split.version,
                      "held_out_objects": len(split.test_objects), "scored_objects": len(held)}
    board["per_object"] = metrics.round(6).to_dict(orient="records")
    return board


def main(argv: list[str] | None = None) -> None:
    import argparse
    import json

    parser = argparse.ArgumentParser(prog="python -m classifiers.experiments.benchmark.retry",
                                     description=__doc__.splitlines()[0])  # type: ignore[union-attr]
    parser.add_argument("--data", default="standard", help="the dataset (default: standard)")
    parser.add_argument("--trials", type=Path, default=None,
                        help="re-simulated per-trial shards, for a dataset made before they "
                             "were kept (the standard dataset records them)")
    parser.add_argument("--scores", type=Path, default=None,
                        help="a study's classifiers/scores.parquet (rankers, classifiers)")
    parser.add_argument("--agent", action="append", default=[], metavar="NAME=ZIP",
                        help="an SB3 agent to score (repeat; one name n times: its n runs)")
    parser.add_argument("--methods", default="best_qc,ranker_lambdarank,oracle,random",
                        help="the methods to tabulate, comma-separated (agents added)")
    parser.add_argument("--reps", type=int, default=2000)
    parser.add_argument("--out", type=Path, default=None, help="write retry.json here")
    args = parser.parse_args(argv)
    trials = args.trials
    agents = [tuple(spec.split("=", 1)) for spec in args.agent]
    if any(len(agent) != 2 for agent in agents):
        parser.exit(2, f"error: --agent takes NAME=ZIP, got {args.agent!r}\n")
    try:
        board = standard_retry_board(args.data, trials, args.scores, args.reps, agents=agents)
    except ValueError as exc:
        parser.exit(2, f"error: {exc}\n")
    split = board["split"]
    print(f"{split['name']} v{split['version']}: {split['scored_objects']} of the "
          f"{split['held_out_objects']} held-out objects have every trial recorded\n")
    methods = [*args.methods.split(","), *dict.fromkeys(name for name, _ in agents)]
    for name in (m for m in methods if m in board["methods"]):
        row = board["methods"][name]
        print(f"{name:>20}: within 1, 2, 3 attempts " + ", ".join(
            f"{row[f'shared_at_{m}']['estimate']:.3f}" for m in (1, 2, 3))
            + "; independence overstates by " + ", ".join(
            f"{row[f'overstatement_at_{m}']['estimate']:+.3f}" for m in (1, 2, 3)))
    print(f"ceiling (some candidate holds at the episode's trial): {board['ceiling']:.3f}")
    if args.out is not None:  # classifiers.report.leaderboard.retry_table tabulates it
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "retry.json").write_text(json.dumps(board, indent=1))


if __name__ == "__main__":
    main()
