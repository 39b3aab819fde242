"""Learning-curve figure of the RL selector."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike


def plot_learning_curve(
    timesteps: ArrayLike, rewards: ArrayLike, path: str | Path, window: int = 50,
    baselines: Mapping[str, float] | None = None,
) -> Path:
    """Episode reward vs timesteps (dots) with a trailing mean over ``window`` episodes, and
    horizontal lines at the expected episode reward of each baseline; PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    steps, values = np.asarray(timesteps, dtype=float), np.asarray(rewards, dtype=float)
    fig, ax = plt.subplots(figsize=(6.0, 3.6), dpi=120)
    if values.size:
        ax.plot(steps, values, ".", ms=2, alpha=0.25, color="tab:blue", label="episode")
        width = max(1, min(window, values.size))
        trailing = np.convolve(values, np.ones(width) / width, mode="valid")
        ax.plot(steps[width - 1 :], trailing, color="tab:red", label=f"mean of last {width}")
    styles = ("--", "-.", ":", (0, (5, 1)))
    for k, (name, value) in enumerate((baselines or {}).items()):
        ax.axhline(value, color="black", linestyle=styles[k % len(styles)], linewidth=1,
                   label=f"{name} ({value:.2f})")  # fmt: skip
    if values.size or baselines:
        ax.legend(loc="lower right", fontsize=7)
    ax.set_xlabel("timesteps")
    ax.set_ylabel("episode reward")
    ax.set_title("RL selector: training episodes")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path)
    plt.close(fig)
    return path
