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


def _colors(plt: Any, board: Mapping[str, Any]) -> list[Any]:
    """One distinct colour per method (tab20: up to 20 methods before a colour repeats)."""
    cmap = plt.get_cmap("tab20")
    return [cmap(i % 20) for i in range(len(board["methods"]))]


def _style(name: str, board: Mapping[str, Any]) -> str:
    """Dashed for the references (oracle, random, best-Q_C), solid for the rest."""
    return "--" if name in ("random", "oracle", board["reference"]) else "-"


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
    for (name, row), color in zip(board["methods"].items(), _colors(plt, board), strict=True):
        ax.step(taus, np.asarray(row["profile"], dtype=float), where="post", color=color,
                ls=_style(name, board), label=name)  # fmt: skip
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
    for (name, row), color in zip(board["methods"].items(), _colors(plt, board), strict=True):
        values = [row[f"success_at_{k}"] for k in ks]
        ax.plot(ks, values, marker="o", color=color, ls=_style(name, board), label=name)
    ax.set_xticks(ks)
    ax.set_xlabel("attempts allowed")
    ax.set_ylabel("P(one of the top-k picks holds)")
    return _finish(plt, fig, ax, "Success against attempts allowed (independent trials)",
                   "lower right", path)
