"""The RL selector's learning curve: held-out top-1 success at log-spaced checkpoints.

>>> from classifiers.experiments.selector.curve import run_curve
>>> run_curve(table, "curve.csv", config, "success", seed=0, timesteps=1_000_000)

Each run trains one selector (:func:`~classifiers.experiments.selector.training.make_selector_model`
on ``GripSelect-v0``'s training objects, as ``grip-env select`` does) and, whenever the step count
passes a checkpoint of :func:`checkpoints`, scores the deterministic first pick on the held-out
objects (the ones ``selector.json`` and the benchmark score: the recorded success rate of the
picked grip, averaged over objects). Every checkpoint is appended to the CSV at once
(:data:`CURVE_COLUMNS`), so an interrupted run still leaves its curve. :func:`plot_curves` draws
the file: the mean over seeds of each variant, each seed faint, and horizontal reference lines
(e.g. lambdarank's and best-Q_C's held-out top-1 success).
"""

from __future__ import annotations

import csv
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from stable_baselines3.common.callbacks import BaseCallback

from grip_env.config import Config

CURVE_COLUMNS = ("variant", "seed", "timesteps", "held_out_success", "train_reward",
                 "seconds")  # fmt: skip


def checkpoints(total: int, first: int = 1000, per_decade: int = 4) -> tuple[int, ...]:
    """Log-spaced step counts from ``first`` to ``total`` (both included), ``per_decade`` a
    decade; ``total < first`` gives ``(total,)``."""
    if total < 1 or first < 1 or per_decade < 1:
        raise ValueError(f"checkpoints need total, first, per_decade >= 1, got {total}, {first}, "
                         f"{per_decade}")  # fmt: skip
    if total <= first:
        return (int(total),)
    count = int(np.ceil(np.log10(total / first) * per_decade)) + 1
    points = np.unique(np.round(np.geomspace(first, total, count)).astype(int))
    return tuple(int(p) for p in points)


class CheckpointEvaluation(BaseCallback):
    """At each checkpoint, the held-out first-pick success (and the mean training reward since
    the last checkpoint), appended to ``path`` as a :data:`CURVE_COLUMNS` row."""

    def __init__(self, table: pd.DataFrame, config: Config, path: Path, variant: str, seed: int,
                 points: tuple[int, ...]) -> None:  # fmt: skip
        super().__init__()
        from classifiers.experiments.selector.evaluation import held_out_candidate_sets

        self.sets = held_out_candidate_sets(table, config)
        self.rates = [found.success_rate for found in self.sets]
        self.path, self.variant, self.seed = path, variant, seed
        self.pending = list(points)
        self.rewards: list[float] = []
        self.start = time.perf_counter()

    def held_out_success(self) -> float:
        """Mean recorded success rate of the policy's first pick on the held-out objects."""
        from classifiers.experiments.selector.evaluation import policy_orders

        picks = policy_orders(self.model, self.sets, 1)
        return float(np.mean([rate[order[0]] for rate, order in zip(self.rates, picks,
                                                                    strict=True)]))

    def _on_step(self) -> bool:
        self.rewards.extend(float(r) for r in self.locals.get("rewards", ()))
        while self.pending and self.num_timesteps >= self.pending[0]:
            self.pending.pop(0)
            self._write()
        return True

    def _write(self) -> None:
        seconds = time.perf_counter() - self.start
        row = (self.variant, self.seed, self.num_timesteps, round(self.held_out_success(), 6),
               round(float(np.mean(self.rewards)), 6) if self.rewards else "", round(seconds, 2))
        self.rewards = []
        new = not self.path.exists()
        with self.path.open("a", newline="") as handle:
            writer = csv.writer(handle)
            if new:
                writer.writerow(CURVE_COLUMNS)
            writer.writerow(row)


def run_curve(table: pd.DataFrame, path: str | Path, config: Config, variant: str, seed: int,
              timesteps: int, policy: str = "set", first: int = 1000,
              per_decade: int = 4) -> Path:  # fmt: skip
    """Train one selector for ``timesteps`` with ``config`` (its ``selector`` section, seed
    ``seed``), appending its checkpoints to ``path`` under ``variant``; returns ``path``."""
    from classifiers.experiments.selector.training import (
        make_selector_env,
        make_selector_model,
        torch_threads,
    )

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    settings = config.selector.model_copy(update={"seed": seed})
    seeded = config.override(selector={"seed": seed})
    env = make_selector_env(table, seeded, "train", settings.n_envs, seed)
    callback = CheckpointEvaluation(table, seeded, path, variant, seed,
                                    checkpoints(timesteps, first, per_decade))  # fmt: skip
    with torch_threads(1):
        model = make_selector_model(env, policy, seed, None, settings=settings)
        model.learn(int(timesteps), callback=callback)
    env.close()
    return path


def read_curves(path: str | Path) -> pd.DataFrame:
    """The curve file as a DataFrame of :data:`CURVE_COLUMNS`."""
    frame = pd.read_csv(path)
    missing = [c for c in CURVE_COLUMNS if c not in frame.columns]
    if missing:
        raise ValueError(f"{path} is not a learning-curve file: it lacks {missing}")
    return frame


def plot_curves(curves: pd.DataFrame | str | Path, path: str | Path,
                references: Mapping[str, float] | None = None,
                title: str = "RL selector: held-out top-1 success") -> Path:  # fmt: skip
    """Held-out top-1 success against training steps (log axis): each variant's mean over its
    seeds (solid, with the seed count) and each seed (faint), and a dashed horizontal line per
    ``references`` entry; PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    frame = curves if isinstance(curves, pd.DataFrame) else read_curves(curves)
    fig, ax = plt.subplots(figsize=(7.0, 4.2), dpi=120)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, (variant, runs) in enumerate(frame.groupby("variant", sort=False)):
        colour = colours[k % len(colours)]
        for _, run in runs.groupby("seed"):
            ax.plot(run["timesteps"], run["held_out_success"], color=colour, alpha=0.25, lw=0.8)
        mean = _seed_mean(runs)
        seeds = runs["seed"].nunique()
        ax.plot(mean.index, mean.to_numpy(), color=colour, lw=2,
                label=f"{variant} ({seeds} seed{'s' if seeds > 1 else ''})")  # fmt: skip
    styles = ("--", "-.", ":", (0, (5, 1)))
    for k, (name, value) in enumerate((references or {}).items()):
        ax.axhline(value, color="black", linestyle=styles[k % len(styles)], lw=1,
                   label=f"{name} ({value:.3f})")  # fmt: skip
    ax.set_xscale("log")
    ax.set_xlabel("environment steps")
    ax.set_ylabel("held-out top-1 success")
    ax.set_title(title)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out)
    plt.close(fig)
    return out


def _seed_mean(runs: pd.DataFrame) -> pd.Series:
    """Mean over seeds at the checkpoints every seed reached."""
    table = runs.pivot_table(index="timesteps", columns="seed", values="held_out_success")
    return table.dropna().mean(axis=1)


def curve_summary(frame: pd.DataFrame) -> dict[str, Any]:
    """Per variant: seeds, last common checkpoint and the mean (min, max) success there."""
    found: dict[str, Any] = {}
    for variant, runs in frame.groupby("variant", sort=False):
        mean = _seed_mean(runs)
        if mean.empty:
            continue
        last = int(mean.index.max())
        at = runs[runs["timesteps"] == last]["held_out_success"]
        found[str(variant)] = {"seeds": int(runs["seed"].nunique()), "timesteps": last,
                               "mean": float(at.mean()), "min": float(at.min()),
                               "max": float(at.max())}  # fmt: skip
    return found


def full_information_curve(table: pd.DataFrame, config: Config, iterations: int = 400,
                           entropy: float = 0.0, seed: int = 0, every: int = 100,
                           learning_rate: float = 3e-3,
                           ) -> list[tuple[int, float, float]]:  # fmt: skip
    """The set policy's scorer trained with full information: what RL tends to without noise.

    The actor of :class:`~classifiers.experiments.selector.policy.CandidateSetNetwork` (the
    config's ``selector.context``, hidden sizes ``[64, 64]`` as the policy's) is fitted by
    full-batch Adam to the exact expected reward of its softmax policy on every training object,
    ``sum_i pi_i p_i`` with ``p`` the recorded success rates, plus ``entropy`` times the
    policy's entropy: the objective MaskablePPO estimates from one sampled pick an episode, here
    with every candidate's outcome and no sampling. Returns ``(iteration, training top-1,
    held-out top-1)`` every ``every`` iterations: if the held-out figure stays below a ranker's,
    more experience cannot close the gap; the objective and model must.
    """
    import torch as th

    from classifiers.experiments.selector.evaluation import held_out_candidate_sets
    from classifiers.experiments.selector.policy import CandidateSetNetwork
    from grip_env.envs.select import GripSelectEnv

    env = GripSelectEnv(data=table, config=config, split="train")
    train = [found for found in (env._candidate_set(i) for i in range(len(env.object_ids)))
             if found.count]  # fmt: skip
    env.close()
    parts = [_tensors(train), _tensors(held_out_candidate_sets(table, config))]
    k, width = train[0].features.shape
    found: list[tuple[int, float, float]] = []
    with th.random.fork_rng():  # seeded without touching the caller's generator
        th.manual_seed(seed)
        network = CandidateSetNetwork(k, width, [64, 64], [64], th.nn.Tanh,
                                      config.selector.context)  # fmt: skip
        optimiser = th.optim.Adam(network.parameters(), lr=learning_rate)
        for iteration in range(iterations + 1):
            logits, _, rates = _logits(network, *parts[0])
            policy = th.softmax(logits, dim=1)
            spread = -(policy * th.log(policy.clamp_min(1e-12))).sum(dim=1)
            loss = -((policy * rates).sum(dim=1) + entropy * spread).mean()
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            if iteration and iteration % every == 0:
                with th.no_grad():
                    found.append((iteration, *(_top1(network, *part) for part in parts)))
    return found


def _tensors(sets: list[Any]) -> tuple[Any, Any, Any]:
    import torch as th

    features = th.tensor(np.stack([found.features for found in sets]))
    mask = th.tensor(np.stack([found.mask for found in sets])).float()
    rates = th.tensor(np.nan_to_num(np.stack([found.success_rate for found in sets]))).float()
    return features, mask, rates


def _logits(network: Any, features: Any, mask: Any, rates: Any) -> tuple[Any, Any, Any]:
    import torch as th

    packed = th.cat([features, mask[..., None]], dim=-1).flatten(start_dim=1)
    return network.forward_actor(packed).masked_fill(mask < 0.5, -1e9), mask, rates


def _top1(network: Any, features: Any, mask: Any, rates: Any) -> float:
    logits, _, _ = _logits(network, features, mask, rates)
    return round(float(rates.gather(1, logits.argmax(dim=1, keepdim=True)).mean()), 6)
