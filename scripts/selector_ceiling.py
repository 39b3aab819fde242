"""Full-information ceilings of the RL selector's scorer beside lambdarank (issue 47).

Every training object's candidates and recorded outcomes at once, no sampling: a per-candidate
scorer (the set policy's actor with ``context="none"``: one MLP from a candidate's inputs to its
logit) is fitted by full-batch Adam under one of three objectives, and its deterministic first
pick is scored on the 128 held-out objects of split v4, as the study scores the selector:

- ``policy``: the expected reward of the softmax policy, ``sum_i pi_i r_i`` (what MaskablePPO
  estimates from one sampled pick an episode);
- ``pairwise``: RankNet's logistic loss over every pair of an object's candidates, each pair
  weighted by its difference in reward (a neural counterpart of lambdarank's pairwise lambdas);
- ``listnet``: cross-entropy to the softmax of the rewards at temperature 0.1 (ListNet).

Inputs (``--encodings``): ``log`` (the environment's observation), ``relative`` (plus each
feature minus its mean over the object's candidates), ``relative_z`` (and that difference
over the feature's standard deviation among them), ``rank`` (plus each feature's percentile
among the object's candidates), ``ple`` (piecewise-linear encoding on 8 quantile bins of the
training candidates, Gorishniy et al. 2022). ``--target robustness`` fits the recorded
robustness over the reference level instead of the success rate (the top-1 is always scored on
success). LightGBM lambdarank (:class:`~classifiers.learners.ranking.GroupedRanker`, the success
count 0-5 as grade) is fitted to the same candidates for the reference row. One CSV row per
(configuration, seed, checkpoint)::

    nice -n 10 python scripts/selector_ceiling.py --out ceiling.csv --encodings log relative \\
        --objectives policy pairwise --seeds 0 1
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

import numpy as np
import pandas as pd
import torch as th

from classifiers.experiments.selector.evaluation import held_out_candidate_sets
from classifiers.learners.ranking import GroupedRanker
from grip_env.config import load_config
from grip_env.datasets import load_standard
from grip_env.envs.select import GripSelectEnv

COLUMNS = ("encoding", "objective", "target", "activation", "hidden", "seed", "iteration",
           "train_top1", "held_out_top1", "seconds")  # fmt: skip
ENCODINGS = ("log", "relative", "relative_z", "rank", "ple")
OBJECTIVES = ("policy", "pairwise", "listnet")
PLE_BINS = 8
LISTNET_TEMPERATURE = 0.1


def tensors(sets, target, reference_g):
    """(features, mask, success rate, fitted reward) of candidate sets, padded to K slots."""
    k = sets[0].features.shape[0]
    features = th.tensor(np.stack([s.features for s in sets]))
    mask = th.tensor(np.stack([s.mask for s in sets])).float()
    rate = th.tensor(np.nan_to_num(np.stack([s.success_rate for s in sets]))).float()
    if target == "success":
        return features, mask, rate, rate
    robust = [np.nan_to_num(s.rows["robustness_mean"].to_numpy(float)) / reference_g for s in sets]
    reward = th.tensor(np.stack([np.pad(r, (0, k - r.size)) for r in robust])).float()
    return features, mask, rate, reward


def encode(features, mask, encoding, edges):
    """The scorer's per-candidate inputs; every encoding is permutation-equivariant."""
    if encoding == "log":
        return features
    valid = mask[..., None]
    count = valid.sum(1, keepdim=True).clamp(min=1)
    if encoding in ("relative", "relative_z"):
        mean = (features * valid).sum(1, keepdim=True) / count
        centred = (features - mean) * valid
        if encoding == "relative":
            return th.cat([features, centred], -1)
        spread = ((centred**2).sum(1, keepdim=True) / count).sqrt()
        return th.cat([features, centred, centred / (spread + 1e-3) * valid], -1)
    if encoding == "rank":
        big = features.masked_fill(valid < 0.5, 1e9)
        above = (big[:, :, None, :] > big[:, None, :, :]).float() * valid[:, None, :, :]
        return th.cat([features, above.sum(2) / (count - 1).clamp(min=1) * valid], -1)
    low, high = edges[:, :-1], edges[:, 1:]
    part = ((features[..., None] - low) / (high - low).clamp(min=1e-6)).clamp(0, 1)
    return (part * mask[..., None, None]).flatten(-2)


def loss(objective, scores, mask, reward):
    """The objective to minimise over a batch of objects (masked slots excluded)."""
    scores = scores.masked_fill(mask < 0.5, -1e9)
    if objective == "policy":
        return -(th.softmax(scores, 1) * reward).sum(1).mean()
    if objective == "listnet":
        target = th.softmax((reward / LISTNET_TEMPERATURE).masked_fill(mask < 0.5, -1e9), 1)
        return -(target * th.log_softmax(scores, 1)).sum(1).mean()
    gap = reward[:, :, None] - reward[:, None, :]
    weight = gap.clamp(min=0) * mask[:, :, None] * mask[:, None, :]
    margin = scores[:, :, None] - scores[:, None, :]
    return (th.nn.functional.softplus(-margin) * weight).sum() / weight.sum()


def top1(scores, mask, rate):
    """Mean success rate of each object's highest-scored valid candidate."""
    pick = scores.masked_fill(mask < 0.5, -1e9).argmax(1, keepdim=True)
    return round(float(rate.gather(1, pick).mean()), 6)


def scorer(width, hidden, activation):
    layers, size = [], width
    for units in hidden:
        layers += [th.nn.Linear(size, units), activation()]
        size = units
    return th.nn.Sequential(*layers, th.nn.Linear(size, 1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--encodings", nargs="+", default=["log"], choices=ENCODINGS)
    parser.add_argument("--objectives", nargs="+", default=["policy"], choices=OBJECTIVES)
    parser.add_argument("--target", default="success", choices=("success", "robustness"))
    parser.add_argument("--activation", default="tanh", choices=("tanh", "relu"))
    parser.add_argument("--hidden", type=int, nargs="*", default=[64, 64])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--iterations", type=int, nargs="+", default=[100, 200, 400, 800])
    parser.add_argument("--config", default="configs/default.yaml")
    args = parser.parse_args()
    th.set_num_threads(1)
    table, config = load_standard(), load_config(args.config)
    env = GripSelectEnv(data=table, config=config, split="train")
    train = [s for s in (env._candidate_set(i) for i in range(len(env.object_ids))) if s.count]
    env.close()
    test = held_out_candidate_sets(table, config)
    reference_g = config.sim.reference_level_g
    (x_train, m_train, p_train, r_train) = tensors(train, args.target, reference_g)
    (x_test, m_test, p_test, _) = tensors(test, args.target, reference_g)
    valid = x_train[m_train > 0.5]
    edges = th.quantile(valid, th.linspace(0, 1, PLE_BINS + 1), dim=0).T
    activation = {"tanh": th.nn.Tanh, "relu": th.nn.ReLU}[args.activation]
    out = Path(args.out)
    new = not out.exists()
    with out.open("a", newline="") as handle:
        writer = csv.writer(handle)
        if new:
            writer.writerow(COLUMNS)
        frame = pd.concat([s.rows for s in train])
        grades = np.rint(frame["success_rate"].to_numpy() * config.dataset.trials).astype(int)
        for seed in args.seeds:
            start = time.perf_counter()
            ranker = GroupedRanker(random_state=seed).fit(frame, grades)
            found = [float(np.mean([s.success_rate[np.argmax(ranker.predict(s.rows))]
                                    for s in sets])) for sets in (train, test)]  # fmt: skip
            _write(writer, handle, ("trees", "lambdarank", "success_count", "", "", seed, "",
                                    round(found[0], 6), round(found[1], 6),
                                    round(time.perf_counter() - start, 1)))  # fmt: skip
        for encoding in args.encodings:
            i_train = encode(x_train, m_train, encoding, edges)
            i_test = encode(x_test, m_test, encoding, edges)
            fitted, held_out = (i_train, m_train, p_train, r_train), (i_test, m_test, p_test)
            for objective in args.objectives:
                for seed in args.seeds:
                    _fit(writer, handle, args, encoding, objective, seed, activation, fitted,
                         held_out)  # fmt: skip


def _fit(writer, handle, args, encoding, objective, seed, activation, train, test) -> None:
    inputs, mask, rate, reward = train
    th.manual_seed(seed)
    network = scorer(inputs.shape[-1], args.hidden, activation)
    optimiser = th.optim.Adam(network.parameters(), lr=3e-3)
    start = time.perf_counter()
    for iteration in range(1, max(args.iterations) + 1):
        value = loss(objective, network(inputs).squeeze(-1), mask, reward)
        optimiser.zero_grad()
        value.backward()
        optimiser.step()
        if iteration in args.iterations:
            with th.no_grad():
                found = (top1(network(inputs).squeeze(-1), mask, rate),
                         top1(network(test[0]).squeeze(-1), test[1], test[2]))  # fmt: skip
            _write(writer, handle, (encoding, objective, args.target, args.activation,
                                    "-".join(map(str, args.hidden)), seed, iteration, *found,
                                    round(time.perf_counter() - start, 1)))  # fmt: skip


def _write(writer, handle, row) -> None:
    writer.writerow(row)
    handle.flush()
    print(*row, sep=",", flush=True)


if __name__ == "__main__":
    main()
