"""Agreement between engines: a dataset's grips simulated again in the other engine.

Every recorded grip of a seeded sample of objects (as ``retest`` samples them) runs its
``dataset.trials`` trials in the dataset's own engine and in the other one, with the same grips,
the same draws (trials 0..T-1 of the dataset's seed) and the same protocol. The own engine's run
is the recorded labels again (checked: ``reproduced`` counts the grips whose mean robustness is
the recorded one); the figures compare it with the other engine's:

* per-trial success agreement and Cohen's kappa;
* the pooled Spearman of the grips' mean robustness, and its mean within objects;
* top-1: how often the grip one engine ranks first (by mean robustness) succeeds in most of its
  trials in the other, both ways;
* the same by object family.

Intervals are 95 % bootstrap intervals over objects.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from grip_env.config import ENGINES
from grip_env.dataset.manifest import read_manifest
from grip_env.dataset.resimulation import BOOTSTRAP, _map, _ObjectCheck, _retest_sample
from grip_env.label_model import engine_of, label_model_for, label_model_of
from grip_env.objects.family import object_family


@dataclass
class CrossCheck:
    """How far a dataset's labels are the engine's: its engine against the other one."""

    engine: str
    other: str
    objects: int
    grips: int
    trials: int
    reproduced: int  # grips whose own-engine mean robustness is the recorded one, bit for bit
    agreement: float  # share of trials both engines judge alike (success)
    agreement_interval: tuple[float, float]
    kappa: float
    pooled: float  # Spearman of the grips' mean robustness, all objects together
    within: float  # mean over objects of the within-object Spearman
    within_interval: tuple[float, float]
    top1: float  # share of (object, direction) whose first-ranked grip mostly succeeds
    families: dict[str, dict[str, float]] = field(default_factory=dict)

    def summary(self) -> str:
        a, w = self.agreement_interval, self.within_interval
        return (f"{self.engine} against {self.other} on {self.grips} grips of {self.objects} "
                f"objects ({self.trials} trials; {self.reproduced} reproduced): success agree "
                f"{self.agreement:.1%} [{a[0]:.1%}, {a[1]:.1%}], kappa {self.kappa:.2f}, "
                f"within-object Spearman {self.within:.2f} [{w[0]:.2f}, {w[1]:.2f}], pooled "
                f"{self.pooled:.2f}, top-1 {self.top1:.1%}")


def other_engine(engine: str) -> str:
    """The engine a dataset made in ``engine`` is cross-checked against."""
    return next(e for e in ENGINES if e != engine)


def check_crosscheckable(directory: Path) -> str:
    """The engine of the dataset in ``directory``, once it is sure this code can cross-check it.

    Raises:
        ValueError: its label model is not one this code reproduces (its engine's), or the other
            engine is not installed.
    """
    from grip_env.sim.engine import require_engine

    manifest = read_manifest(directory)
    engine = engine_of(manifest)
    found, expected = label_model_of(manifest), label_model_for(engine)
    if found != expected:
        raise ValueError(f"dataset {directory} was labelled by label model {found!r}; this code "
                         f"makes {expected!r} in {engine}, so it cannot cross-check it "
                         f"(regenerate it first)")
    require_engine(engine)
    require_engine(other_engine(engine))
    return engine


def crosscheck(path: str | Path, objects: int, seed: int = 0, workers: int = 1) -> CrossCheck:
    """Simulate every grip of ``objects`` seeded objects in both engines and compare.

    Raises:
        ValueError: ``objects`` is not a positive integer, the dataset is unreadable, or its
            label model is not one this code reproduces (its engine's).
    """
    directory = Path(path)
    engine = check_crosscheckable(directory)
    checks = _retest_sample(directory, objects, seed)
    runs = _map(_both_engines, checks, workers, "crosscheck")
    return _figures(checks, runs, engine, seed)


def _both_engines(check: _ObjectCheck) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Per-trial outcomes of every recorded grip of one object in its engine and the other."""
    from grip_env.sim import run_trial_outcomes

    config = check.task.config
    grips = check.recorded.assign(object_id=check.task.object_id).reset_index(drop=True)
    other = config.override(sim={"engine": other_engine(config.sim.engine)})
    trials, seed = config.dataset.trials, config.dataset.seed
    return (run_trial_outcomes(check.task.obj, grips, config, trials, seed),
            run_trial_outcomes(check.task.obj, grips, other, trials, seed))


def _object_figures(own: pd.DataFrame, other: pd.DataFrame) -> dict[str, float]:
    """One object's sums and scores (trials alike, both successes, the grips' means...)."""
    from scipy import stats

    a, b = own["success"].to_numpy(bool), other["success"].to_numpy(bool)
    mean_a = own.groupby("grip", sort=True)["robustness"].mean().to_numpy()
    mean_b = other.groupby("grip", sort=True)["robustness"].mean().to_numpy()
    rate_a = own.groupby("grip", sort=True)["success"].mean().to_numpy()
    rate_b = other.groupby("grip", sort=True)["success"].mean().to_numpy()
    spearman = (float(stats.spearmanr(mean_a, mean_b).statistic)
                if np.ptp(mean_a) > 0 and np.ptp(mean_b) > 0 else float("nan"))
    top = (float(rate_b[int(np.argmax(mean_a))] > 0.5)
           + float(rate_a[int(np.argmax(mean_b))] > 0.5))
    return {"trials": len(a), "alike": int((a == b).sum()), "a": int(a.sum()), "b": int(b.sum()),
            "both": int((a & b).sum()), "spearman": spearman, "top": top / 2}


def _reproduced(own: pd.DataFrame, check: _ObjectCheck) -> int:
    """Grips whose mean robustness in the own engine is the recorded one, bit for bit (summed
    as the dataset sums it: ``trial_summary``)."""
    from grip_env.sim.execution import trial_summary

    n = len(check.recorded)
    ordered = own.sort_values(["grip", "trial"], kind="stable")
    mean = trial_summary(ordered["robustness"].to_numpy(float).reshape(n, -1),
                         ordered["success"].to_numpy(bool).reshape(n, -1))["robustness_mean"]
    return int((mean == check.recorded["robustness_mean"].to_numpy()).sum())


def _kappa(rows: list[dict[str, float]]) -> tuple[float, float]:
    """Per-trial agreement and Cohen's kappa over the objects ``rows``."""
    n = sum(r["trials"] for r in rows)
    if n == 0:
        return float("nan"), float("nan")
    observed = sum(r["alike"] for r in rows) / n
    pa, pb = sum(r["a"] for r in rows) / n, sum(r["b"] for r in rows) / n
    chance = pa * pb + (1 - pa) * (1 - pb)
    return observed, (observed - chance) / (1 - chance) if chance < 1 else float("nan")


def _interval(values: np.ndarray, rng: np.random.Generator) -> tuple[float, float]:
    values = values[np.isfinite(values)]
    if not len(values):
        return float("nan"), float("nan")
    boot = rng.choice(values, (BOOTSTRAP, len(values))).mean(axis=1)
    return float(np.quantile(boot, 0.025)), float(np.quantile(boot, 0.975))


def _figures(checks: list[_ObjectCheck], runs: list[tuple[pd.DataFrame, pd.DataFrame]],
             engine: str, seed: int) -> CrossCheck:
    from scipy import stats

    rng = np.random.default_rng(seed)
    rows = [_object_figures(own, other) for own, other in runs]
    agreement, kappa = _kappa(rows)
    alike = np.array([r["alike"] / r["trials"] for r in rows]) if rows else np.zeros(0)
    boot = rng.choice(len(rows), (BOOTSTRAP, len(rows))) if rows else np.zeros((0, 0), int)
    trials = np.array([r["trials"] for r in rows])
    shares = ((alike * trials)[boot].sum(axis=1) / trials[boot].sum(axis=1)) if rows else alike
    agreement_interval = ((float(np.quantile(shares, 0.025)), float(np.quantile(shares, 0.975)))
                          if rows else (float("nan"), float("nan")))
    within = np.array([r["spearman"] for r in rows])
    means = [(own.groupby("grip")["robustness"].mean(),
              other.groupby("grip")["robustness"].mean()) for own, other in runs]
    own_means = np.concatenate([a for a, _ in means]) if means else np.zeros(0)
    other_means = np.concatenate([b for _, b in means]) if means else np.zeros(0)
    pooled = (float(stats.spearmanr(own_means, other_means).statistic)
              if len(own_means) and np.ptp(own_means) > 0 and np.ptp(other_means) > 0
              else float("nan"))
    reproduced = sum(_reproduced(own, check) for (own, _), check in zip(runs, checks, strict=True))
    families: dict[str, list[dict[str, float]]] = {}
    for check, row in zip(checks, rows, strict=True):
        families.setdefault(object_family(check.task.obj), []).append(row)
    by_family = {name: {"objects": len(group), "agreement": _kappa(group)[0],
                        "kappa": _kappa(group)[1],
                        "within": float(np.nanmean([r["spearman"] for r in group]))
                        if any(np.isfinite(r["spearman"]) for r in group) else float("nan")}
                 for name, group in sorted(families.items())}
    return CrossCheck(
        engine, other_engine(engine), len(checks), int(sum(len(c.recorded) for c in checks)),
        int(trials.sum()) if rows else 0, reproduced, agreement, agreement_interval, kappa,
        pooled, float(np.nanmean(within)) if np.isfinite(within).any() else float("nan"),
        _interval(within, rng), float(np.mean([r["top"] for r in rows])) if rows else float("nan"),
        by_family)
