"""Interval half-widths: the study's targets, the paired bootstrap, and the law by which a
half-width narrows with objects and trials (fitted by :mod:`classifiers.experiments.power`, drawn by
:mod:`classifiers.report.power`, which both import it from here)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import nnls

#: The three questions' half-width targets (issue 31: the standard dataset's study answers them;
#: issue 13's were 0.05, 0.02 and 0.08).
TARGETS: dict[str, float] = {"roc_auc": 0.03, "hand_difference": 0.03, "rl_minus_best_qc": 0.06}
#: The power experiment's result file and its figure (in its output folder).
POWER_FILE = "power.json"
FIGURE_FILE = "power.png"


def paired_bootstrap(
    a: np.ndarray, b: np.ndarray, seed: int, n_boot: int = 2000
) -> tuple[float, float]:
    """(mean, half-width) of the 95% percentile bootstrap of ``mean(a - b)`` over objects, with
    the resamples :func:`classifiers.experiments.selector.evaluation.evaluate_selectors` draws."""
    difference = np.asarray(a, float) - np.asarray(b, float)
    if difference.size == 0:
        raise ValueError("paired_bootstrap needs at least one object")
    resamples = np.random.default_rng(seed).integers(difference.size,
                                                     size=(n_boot, difference.size))
    low, high = np.percentile(difference[resamples].mean(axis=1), [2.5, 97.5])
    return float(difference.mean()), float((high - low) / 2.0)


@dataclass(frozen=True)
class Law:
    """``h^2 = (a + b / t) / n``: half-width ``h`` at ``n`` objects and ``t`` trials per grip."""

    a: float
    b: float
    points: int

    def half_width(self, objects: float, trials: float = math.inf) -> float:
        """The law's half-width at ``objects`` objects and ``trials`` trials per grip."""
        return math.sqrt((self.a + self.b / trials) / objects)

    def as_dict(self) -> dict[str, float]:
        return asdict(self)


def fit_law(objects: Sequence[float], trials: Sequence[float], half: Sequence[float]) -> Law:
    """Least-squares fit of :class:`Law` on relative error (``h^2`` residuals divided by
    ``h^2``), with ``a, b >= 0``. With a single trials value ``b`` is not identified and is 0
    (the ``1/sqrt(n)`` law, ``a`` carrying the label noise at that trial count).

    Raises:
        ValueError: no finite positive half-width, or inputs of unequal length or non-positive.
    """
    n, t, h = (np.asarray(v, dtype=float) for v in (objects, trials, half))
    if not n.shape == t.shape == h.shape:
        raise ValueError(f"objects, trials, half have lengths {n.size}, {t.size}, {h.size}")
    keep = np.isfinite(h) & (h > 0)
    n, t, h = n[keep], t[keep], h[keep]
    if h.size == 0:
        raise ValueError("fit_law needs at least one finite positive half-width")
    if (n <= 0).any() or (t <= 0).any():
        raise ValueError("objects and trials must be positive")
    design = np.column_stack([1.0 / n, 1.0 / (n * t)]) / (h**2)[:, None]
    if np.unique(t).size == 1:
        (a,), _ = nnls(design[:, :1], np.ones(h.size))
        return Law(a=float(a), b=0.0, points=int(h.size))
    (a, b), _ = nnls(design, np.ones(h.size))
    return Law(a=float(a), b=float(b), points=int(h.size))


def exponent(objects: Sequence[float], half: Sequence[float]) -> float:
    """Fitted slope of ``log h`` against ``log n`` (the ``1/sqrt(n)`` law predicts −0.5)."""
    n, h = np.asarray(objects, float), np.asarray(half, float)
    keep = np.isfinite(h) & (h > 0)
    if np.unique(n[keep]).size < 2:
        return float("nan")
    return float(np.polyfit(np.log(n[keep]), np.log(h[keep]), 1)[0])


def objects_needed(law: Law, target: float, trials: float = math.inf) -> int:
    """Fewest objects whose half-width :class:`Law` puts at or below ``target``."""
    if not target > 0:
        raise ValueError(f"target must be positive, got {target!r}")
    return max(1, math.ceil((law.a + law.b / trials) / target**2 - 1e-9))
