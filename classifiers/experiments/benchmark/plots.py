"""Leaderboard figures: performance profiles (rliable) and success against attempts allowed."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from classifiers.experiments.benchmark.selection import MAX_ATTEMPTS


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _lines(ax: Any, board: Mapping[str, Any], x: Any, values: Any, **options: Any) -> None:
    """One line per method, each with a look of its own and the references (random, oracle,
    best-Q_C) in greys; a method's line identical to another's says so in the legend
    (:func:`classifiers.experiments.plots.draw_lines`)."""
    from classifiers.experiments.plots import draw_lines

    series = {name: (x, values(row)) for name, row in board["methods"].items()}
    draw_lines(ax, series, ("random", "oracle", board["reference"]), **options)


def _finish(plt: Any, fig: Any, ax: Any, title: str, legend: str, path: str | Path) -> Path:
    """Grid, legend and title, then the figure saved to ``path`` and closed."""
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2, loc=legend)
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


def plot_profiles(board: Mapping[str, Any], path: str | Path) -> Path:
    """Fraction of (object, run) pairs whose normalised score exceeds tau, per method."""
    plt = _pyplot()
    taus = np.asarray(board["taus"], dtype=float)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    _lines(ax, board, taus, lambda row: row["profile"], drawstyle="steps-post")
    ax.set_xlabel("normalised score tau  (0 = random pick, 1 = oracle)")
    ax.set_ylabel("fraction of objects x runs with score > tau")
    ax.set_xlim(taus.min(), taus.max())
    ax.set_ylim(0, 1.02)
    return _finish(plt, fig, ax, "Performance profiles on the held-out objects", "lower left", path)


def plot_attempts(board: Mapping[str, Any], path: str | Path) -> Path:
    """Chance that one of the top-k picks holds, k = 1..5, per method."""
    plt = _pyplot()
    ks = np.arange(1, MAX_ATTEMPTS + 1)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    _lines(ax, board, ks, lambda row: [row[f"success_at_{k}"] for k in ks], every_point=True)
    ax.set_xticks(ks)
    ax.set_xlabel("attempts allowed")
    ax.set_ylabel("P(one of the top-k picks holds)")
    return _finish(plt, fig, ax, "Success against attempts allowed (independent trials)",
                   "lower right", path)
