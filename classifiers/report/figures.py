"""The study report's figures, each written to a PNG (matplotlib Figures, no pyplot state)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from grip_env.columns import FEATURES
from grip_env.drawing import draw_grip, draw_object, save_figure
from grip_env.objects import PlanarObject


def correlation_heatmap(correlations: pd.DataFrame, path: Path) -> Path:
    """Heat map of a correlation matrix with the values printed in the cells."""
    fig = Figure(figsize=(7, 6))
    ax = fig.subplots()
    image = ax.imshow(correlations.to_numpy(), vmin=-1, vmax=1, cmap="RdBu_r")
    labels = list(correlations.columns)
    ax.set_xticks(range(len(labels)), labels)
    ax.set_yticks(range(len(labels)), labels)
    for (i, j), value in np.ndenumerate(correlations.to_numpy()):
        ax.text(j, i, f"{value:.2f}", ha="center", va="center", fontsize=7)
    fig.colorbar(image, ax=ax, shrink=0.8, label="Pearson r")
    ax.set_title("Feature correlations (paper, section VI-B)")
    fig.tight_layout()
    return save_figure(fig, path)


def feature_distributions(table: pd.DataFrame, path: Path) -> Path:
    """One histogram per feature, grips that held against grips that slipped."""
    fig = Figure(figsize=(12, 8))
    axes = fig.subplots(3, 4).ravel()
    held = table["success"].astype(bool)
    for ax, name in zip(axes, FEATURES, strict=True):
        values = table[name].to_numpy(dtype=float)
        upper = np.nanpercentile(values, 98) if len(values) else 1.0
        bins = np.linspace(np.nanmin(values), max(upper, np.nanmin(values) + 1e-9), 30)
        ax.hist(values[held], bins=bins, alpha=0.6, label="held", color="tab:green")
        ax.hist(values[~held], bins=bins, alpha=0.6, label="slipped", color="tab:red")
        ax.set_title(name)
    axes[0].legend()
    fig.suptitle("Feature distributions by simulated outcome (values above the 98th pct. cut)")
    fig.tight_layout()
    return save_figure(fig, path)


def success_by_bin(bins: pd.DataFrame, path: Path, column: str = "Q_C") -> Path:
    """Bar chart of the success rate per quantile bin of a quality index."""
    fig = Figure(figsize=(6.5, 3.8))
    ax = fig.subplots()
    ax.bar(bins.index.astype(int), bins["success_rate"], color="tab:blue")
    ax.set_xlabel(f"{column} decile (1 = best, lowest {column})")
    ax.set_ylabel("simulated success rate")
    ax.set_ylim(0, 1)
    ax.set_xticks(bins.index.astype(int))
    ax.set_title(f"Success rate per {column} decile")
    fig.tight_layout()
    return save_figure(fig, path)


def grip_gallery(
    objects: Sequence[PlanarObject], grips: pd.DataFrame, path: Path, columns: int = 4
) -> Path:
    """Each object with its best (solid) and worst (faint) grip by Q_C, and their outcomes."""
    rows = int(np.ceil(len(objects) / columns))
    fig = Figure(figsize=(3.2 * columns, 3.2 * rows))
    axes = np.atleast_1d(fig.subplots(rows, columns)).ravel()
    for ax in axes[len(objects):]:
        ax.axis("off")
    for ax, obj in zip(axes, objects, strict=False):
        draw_object(ax, obj)
        mine = grips[grips["object_id"] == obj.name].sort_values("Q_C")
        if not mine.empty:
            draw_grip(ax, mine.iloc[-1], highlight=False)
            draw_grip(ax, mine.iloc[0], highlight=True)
            best, worst = mine.iloc[0], mine.iloc[-1]
            ax.set_title(
                f"{obj.name}\nbest Q_C {best['Q_C']:.2f} ({_rate(best)}), "
                f"worst {worst['Q_C']:.2f} ({_rate(worst)})",
                fontsize=8,
            )
        else:
            ax.set_title(f"{obj.name}\n(no feasible grip)", fontsize=8)
        ax.set_xlabel("")
        ax.set_ylabel("")
        ax.tick_params(labelsize=6)
    fig.tight_layout()
    return save_figure(fig, path, dpi=100)


def interval_bars(
    results: dict[str, dict[str, float | list[float]]], path: Path, title: str, ylabel: str
) -> Path:
    """Horizontal bars of means with 95% intervals, from ``{name: {"mean": m, "ci": [lo, hi]}}``."""
    names = list(results)
    means = np.array([float(results[n]["mean"]) for n in names])
    lows = np.array([float(results[n]["ci"][0]) for n in names])  # type: ignore[index]
    highs = np.array([float(results[n]["ci"][1]) for n in names])  # type: ignore[index]
    fig = Figure(figsize=(7, 0.45 * len(names) + 1.5))
    ax = fig.subplots()
    errors = np.vstack([np.clip(means - lows, 0, None), np.clip(highs - means, 0, None)])
    ax.barh(range(len(names)), means, xerr=errors, color="tab:blue", capsize=3)
    ax.set_yticks(range(len(names)), names)
    ax.invert_yaxis()
    ax.set_xlabel(ylabel)
    ax.set_title(title)
    fig.tight_layout()
    return save_figure(fig, path)


def _rate(grip: pd.Series) -> str:
    if "success_rate" not in grip or pd.isna(grip["success_rate"]):
        return "not simulated"
    return f"held {grip['success_rate']:.0%}"
