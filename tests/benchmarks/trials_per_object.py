"""Trials chosen per object, judged on objects the rule was not chosen on (run by hand; issue 45).

    python -m tests.benchmarks.trials_per_object --parts R.crosscheck --engine mujoco

A label of n trials a grip reaches a mean within-object retest of 0.8 at n = 3 in both engines.
Objects differ, so a dataset could stop an object's grips at two trials when their first two
already rank alike and go on otherwise. This reads a cross-check's kept outcomes (2T = 10 trials
a grip), splits each object's trials into two disjoint labels of T many times (seeded, the same
splits for every object), and lets each label decide from its own first two trials:

- *two-level*: stop at 2 when the Spearman of the grips' first two trials is at least ``tau``,
  else take K;
- *graded*: the fewest n in 2..T whose Spearman-Brown from that Spearman reaches ``c``.

A rule's retest is the Spearman between the two labels' grip means, averaged over splits and
then objects; its trials are the mean over labels, weighted by the object's grips (what a
dataset pays). Each rule's setting is chosen as the cheapest reaching 0.8 on half the objects
and judged on the other half (2-fold, repeated over seeded object splits), so its figure is not
chosen on the data it is judged on.
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from grip_env.dataset.crosscheck import _every_trial
from grip_env.dataset.retest_curve import TRUSTWORTHY, _column_spearman, split_order
from tests.benchmarks.crosscheck_contact_loads import kept_runs

Rule = Callable[[NDArray[np.float64]], NDArray[np.int64]]


def outcomes(parts: Path, objects: int, seed: int,
             engine: str) -> list[tuple[NDArray[np.float64], float]]:
    """Each kept object's robustness in ``engine``, (grips, 2T), and its CPU s a trial there."""
    found = [(_every_trial(runs, engine), runs.seconds[engine])
             for _, runs in kept_runs(parts, objects, seed)]
    return [(m, seconds / m.size) for m, seconds in found if m is not None and m.shape[0] >= 2]


class Splits:
    """One object's labels under every split: each label's first-two Spearman ``first_two``
    (splits, 2) and the retest between labels of ``na`` and ``nb`` trials ``retest[:, na, nb]``."""

    def __init__(self, matrix: NDArray[np.float64], order: NDArray[np.int64],
                 seconds: float) -> None:
        self.grips, self.seconds = matrix.shape[0], seconds  # seconds: CPU a trial
        size = order.shape[1] // 2
        halves = order[:, :size], order[:, size:]
        self.first_two = np.stack([_column_spearman(matrix[:, h[:, 0]], matrix[:, h[:, 1]])
                                   for h in halves], axis=1)
        means = [[matrix[:, h[:, :n]].mean(axis=2) for n in range(1, size + 1)] for h in halves]
        self.retest = np.full((len(order), size + 1, size + 1), np.nan)
        for na in range(1, size + 1):
            for nb in range(1, size + 1):
                self.retest[:, na, nb] = _column_spearman(means[0][na - 1], means[1][nb - 1])

    def judge(self, rule: Rule) -> tuple[float, float]:
        """(retest, mean trials) of this object's labels under ``rule``."""
        n = rule(self.first_two)
        values = self.retest[np.arange(len(n)), n[:, 0], n[:, 1]]
        retest = float(np.nanmean(values)) if np.isfinite(values).any() else float("nan")
        return retest, float(n.mean())


def judge(objects: list[Splits], rule: Rule) -> tuple[float, float, float]:
    """``rule``'s mean retest over objects, and its trials and CPU s a label (a grip), each
    averaged over grips."""
    judged = np.array([s.judge(rule) for s in objects])
    grips = np.array([s.grips for s in objects])
    seconds = np.array([s.seconds for s in objects])
    return (float(np.nanmean(judged[:, 0])), float(np.average(judged[:, 1], weights=grips)),
            float(np.average(judged[:, 1] * seconds, weights=grips)))


def fixed(n: int) -> Rule:
    """``n`` trials for every object (the datasets' rule)."""
    return lambda first_two: np.full(first_two.shape, n)


def two_level(tau: float, most: int) -> Rule:
    """2 trials when the first two rank alike (Spearman >= ``tau``; undefined counts as not),
    else ``most``."""
    return lambda first_two: np.where(np.nan_to_num(first_two, nan=-1.0) >= tau, 2, most)


def graded(target: float, most: int) -> Rule:
    """The fewest n in 2..``most`` whose Spearman-Brown from the first-two Spearman reaches
    ``target`` (``most`` when none does)."""
    def rule(first_two: NDArray[np.float64]) -> NDArray[np.int64]:
        r = np.clip(np.nan_to_num(first_two, nan=0.0), 0.0, 0.999)
        n = np.full(first_two.shape, most)
        for k in range(most - 1, 1, -1):
            n = np.where(k * r / (1 + (k - 1) * r) >= target, k, n)
        return n
    return rule


def families(size: int) -> dict[str, dict[str, Rule]]:
    """Each rule family's candidate settings, by name."""
    taus = np.round(np.arange(-0.2, 1.001, 0.05), 2)
    targets = np.round(np.arange(0.5, 0.991, 0.01), 2)
    return {
        "two-level": {f"tau {t:.2f}, K {k}": two_level(t, k)
                      for k in range(3, size + 1) for t in taus},
        "graded": {f"c {c:.2f}": graded(c, size) for c in targets},
    }


def cheapest(objects: list[Splits], rules: dict[str, Rule]) -> str | None:
    """The setting with the fewest trials whose retest reaches 0.8 on ``objects``."""
    best: tuple[float, str] | None = None
    for name, rule in rules.items():
        retest, trials, _ = judge(objects, rule)
        if retest >= TRUSTWORTHY and (best is None or trials < best[0]):
            best = (trials, name)
    return None if best is None else best[1]


def held_out(objects: list[Splits], rules: dict[str, Rule], repeats: int,
             seed: int) -> NDArray[np.float64]:
    """(retest, trials, CPU s a label) on the test half of each fold whose training half had
    a setting."""
    rng = np.random.default_rng(seed)
    judged = []
    for _ in range(repeats):
        order = rng.permutation(len(objects))
        halves = order[: len(order) // 2], order[len(order) // 2:]
        for train, test in (halves, halves[::-1]):
            name = cheapest([objects[i] for i in train], rules)
            if name is not None:
                judged.append(judge([objects[i] for i in test], rules[name]))
    return np.array(judged)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", type=Path, required=True)
    parser.add_argument("--engine", choices=("pybullet", "mujoco"), default="mujoco")
    parser.add_argument("--objects", type=int, default=80)
    parser.add_argument("--splits", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    found = outcomes(args.parts, args.objects, args.seed, args.engine)
    if not found:
        raise SystemExit(f"{args.parts} keeps no retested object in {args.engine}")
    trials = min(m.shape[1] for m, _ in found)
    order = split_order(args.splits, trials, args.seed)
    objects = [Splits(m[:, :trials], order, seconds) for m, seconds in found]
    grips = sum(s.grips for s in objects)
    print(f"{args.engine}: {len(objects)} objects, {grips} grips, {trials} trials a grip, "
          f"{args.splits} splits; CPU a label at the cross-check's own CPU a trial\n")
    print("| rule | retest | trials a grip | core-s a label |\n| --- | --- | --- | --- |")
    for n in range(1, trials // 2 + 1):
        retest, _, seconds = judge(objects, fixed(n))
        print(f"| {n} for every object | {retest:.3f} | {n} | {seconds:.3f} |")
    for family, rules in families(trials // 2).items():
        name = cheapest(objects, rules)
        if name is not None:
            retest, mean, seconds = judge(objects, rules[name])
            print(f"| {family}, chosen on every object ({name}) | {retest:.3f} | {mean:.2f} | "
                  f"{seconds:.3f} |")
        folds = held_out(objects, rules, args.repeats, args.seed)
        if len(folds):
            low = int((folds[:, 0] < TRUSTWORTHY).sum())
            print(f"| {family}, held out ({len(folds)} folds; {low} below 0.8) | "
                  f"{interval(folds[:, 0], 3)} | {interval(folds[:, 1], 2)} | "
                  f"{interval(folds[:, 2], 3)} |")


def interval(values: NDArray[np.float64], digits: int) -> str:
    """Mean [5th, 95th percentile] over folds."""
    low, high = np.percentile(values, [5, 95])
    return f"{values.mean():.{digits}f} [{low:.{digits}f}, {high:.{digits}f}]"


if __name__ == "__main__":
    main()
