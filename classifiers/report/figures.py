"""The study report's figures, each written to a PNG (matplotlib Figures, no pyplot state)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib import colormaps
from matplotlib.figure import Figure

from grip_env.columns import FEATURES
from grip_env.drawing import add_grip_legend, draw_grip, draw_object, grip_legend, save_figure
from grip_env.objects import PlanarObject


def correlation_heatmap(correlations: pd.DataFrame, path: Path, label: str = "Spearman ρ") -> Path:
    """Heat map of a correlation matrix with the values printed in the cells (see
    :func:`correlation_figure`)."""
    return save_figure(correlation_figure(correlations, label), path)


def correlation_figure(correlations: pd.DataFrame, label: str = "Spearman ρ") -> Figure:
    """The heat map; an undefined correlation (a constant feature's row and column) is a grey
    cell marked "—", never "nan"."""
    fig = Figure(figsize=(7, 6))
    ax = fig.subplots()
    values = correlations.to_numpy(dtype=float)
    cmap = colormaps["RdBu_r"].with_extremes(bad="lightgrey")
    image = ax.imshow(np.ma.masked_invalid(values), vmin=-1, vmax=1, cmap=cmap)
    labels = list(correlations.columns)
    ax.set_xticks(range(len(labels)), labels)
    ax.set_yticks(range(len(labels)), labels)
    for (i, j), value in np.ndenumerate(values):
        ax.text(j, i, f"{value:.2f}" if np.isfinite(value) else "—", ha="center", va="center",
                fontsize=7)  # fmt: skip
    fig.colorbar(image, ax=ax, shrink=0.8, label=label)
    undefined = [name for k, name in enumerate(labels) if np.isnan(values[k]).all()]
    ax.set_title(f"Feature correlations, {label} (paper, section VI-B)"
                 + (f"\n— : {', '.join(undefined)} constant, no correlation defined"
                    if undefined else ""), fontsize=10)  # fmt: skip
    fig.tight_layout()
    return fig


def feature_distributions(table: pd.DataFrame, path: Path) -> Path:
    """Share of grips per bin of each feature, held against slipped, on symlog axes (see
    :func:`distribution_figure`)."""
    return save_figure(distribution_figure(table), path)


def distribution_figure(table: pd.DataFrame) -> Figure:
    """Share of grips per bin of each feature, held against slipped, on symlog axes.

    No value is cut: bins are even in ``asinh(x / s)`` (``s`` the feature's smallest nonzero
    magnitude, at least 1e-3), which is what a symlog axis with linear range ``s`` shows; each
    outcome's bars sum to 1, so the two groups compare whatever their sizes. A feature whose
    values span less than ``s`` gets an axis of ``s`` either side of them; a constant one says
    so in its title.
    """
    fig = Figure(figsize=(12, 8))
    axes = fig.subplots(3, 4).ravel()
    held = table["success"].astype(bool).to_numpy()
    for ax, name in zip(axes, FEATURES, strict=True):
        values = table[name].to_numpy(dtype=float)
        finite = np.isfinite(values)
        scale = _linear_range(values[finite])
        edges = _symlog_edges(values[finite], scale)
        for mask, label, colour in ((held, "held", "tab:green"), (~held, "slipped", "tab:red")):
            chosen = values[mask & finite]
            if chosen.size:
                ax.hist(chosen, bins=edges, weights=np.full(chosen.size, 1.0 / chosen.size),
                        alpha=0.55, label=label, color=colour)  # fmt: skip
        ax.set_xscale("symlog", linthresh=scale)
        ax.set_xlim(edges[0], edges[-1])
        unique = np.unique(values[finite])
        ax.set_title(f"{name} (constant {unique[0]:g})" if unique.size == 1 else name)
        ax.tick_params(labelsize=7)
    axes[0].legend()
    fig.supylabel("share of the outcome's grips")
    fig.suptitle("Feature distributions by simulated outcome (symlog x: every value shown)")
    fig.tight_layout()
    return fig


def _linear_range(values: np.ndarray) -> float:
    nonzero = np.abs(values[values != 0])
    return float(max(nonzero.min(), 1e-3)) if nonzero.size else 1.0


def _symlog_edges(values: np.ndarray, scale: float, bins: int = 30) -> np.ndarray:
    """Bin edges even in ``asinh(x / scale)`` over the values, widened to ``scale`` either side
    when the values span less (a constant feature's bar sits mid-axis on a readable scale)."""
    if values.size == 0:
        return np.linspace(0.0, 1.0, bins + 1)
    low, high = float(values.min()), float(values.max())
    if high - low < scale:
        low, high = low - scale, high + scale
    return np.sinh(np.linspace(np.arcsinh(low / scale), np.arcsinh(high / scale), bins + 1)) * scale


def success_by_bin(bins: pd.DataFrame, path: Path, column: str = "Q_C") -> Path:
    """Bar chart of the success rate per quantile bin, with 95% intervals and grip counts."""
    fig = Figure(figsize=(6.5, 3.8))
    ax = fig.subplots()
    index = bins.index.astype(int)
    errors = None
    if {"ci_low", "ci_high"} <= set(bins.columns):
        errors = np.vstack([bins["success_rate"] - bins["ci_low"],
                            bins["ci_high"] - bins["success_rate"]]).clip(min=0)  # fmt: skip
    ax.bar(index, bins["success_rate"], yerr=errors, capsize=3, color="tab:blue")
    for position, count in zip(index, bins["grips"], strict=True):
        ax.annotate(f"n={count}", (position, 0.01), ha="center", va="bottom", fontsize=6,
                    color="white")  # fmt: skip
    ax.set_xlabel(f"{column} decile (1 = best, lowest {column})")
    ax.set_ylabel("simulated success rate")
    ax.set_ylim(0, 1)
    ax.set_xticks(index)
    ax.set_title(f"Success rate per {column} decile (95% object-bootstrap intervals)")
    fig.tight_layout()
    return save_figure(fig, path)


def grip_gallery(
    objects: Sequence[PlanarObject], grips: pd.DataFrame, path: Path, columns: int = 4,
    kinds: Sequence[str] | None = None, title: str | None = None,
) -> Path:
    """Each object with its best (solid) and worst (faint) grip by Q_C and their outcomes; axes
    in mm, one legend for the figure. ``kinds`` (one per object, e.g. "mesh") head each panel's
    title; ``title`` is a line under the panels."""
    rows = int(np.ceil(len(objects) / columns))
    fig = Figure(figsize=(3.2 * columns, 3.2 * rows + (0.4 if title else 0.0)))
    axes = np.atleast_1d(fig.subplots(rows, columns)).ravel()
    for ax in axes[len(objects):]:
        ax.axis("off")
    for k, (ax, obj) in enumerate(zip(axes, objects, strict=False)):
        draw_object(ax, obj)
        name = obj.name if kinds is None else f"{kinds[k]}: {obj.name}"
        mine = grips[grips["object_id"] == obj.name].sort_values("Q_C")
        if not mine.empty:
            draw_grip(ax, mine.iloc[-1], highlight=False)
            draw_grip(ax, mine.iloc[0], highlight=True)
            best, worst = mine.iloc[0], mine.iloc[-1]
            ax.set_title(
                f"{name}\nbest Q_C {best['Q_C']:.2f}: {_rate(best)}\n"
                f"worst Q_C {worst['Q_C']:.2f}: {_rate(worst)}",
                fontsize=7,
            )
        else:
            ax.set_title(f"{name}\n(no feasible grip)", fontsize=8)
        ax.set_xlabel("")
        ax.set_ylabel("")
        ax.tick_params(labelsize=6)
    bottom = 0.4 / (3.2 * rows + 0.4) if title else 0.0
    fig.supxlabel("x (mm)", fontsize=9, y=bottom + 0.01, va="bottom")
    fig.supylabel("y (mm)", fontsize=9)
    if title:
        fig.text(0.5, 0.004, title, ha="center", va="bottom", fontsize=10, weight="bold")
    handles, labels = grip_legend(others="worst grip by Q_C (faint)")
    top = add_grip_legend(fig, handles, labels, ncol=4, fontsize=8)
    fig.tight_layout(rect=(0, bottom, 1, 1 - top))
    return save_figure(fig, path, dpi=100)


def gallery_choice(objects: pd.DataFrame, grips: pd.DataFrame, per_kind: int = 8) -> pd.DataFrame:
    """Which objects a gallery shows: up to ``per_kind`` drawn shapes (named first, then
    procedural) and as many meshes, each in the dataset's run order, among the objects with
    grips in ``grips``; ``objects`` is a dataset's objects table (``object_id``, ``family``,
    ``object_index``). Returns those rows, drawn shapes first, with a ``kind`` column."""
    present = objects[objects["object_id"].isin(set(grips["object_id"]))]
    present = present.assign(kind=np.where(present["family"] == "mesh", "mesh", "drawn"),
                             named=present["family"] != "named").sort_values(
        ["named", "object_index"])  # fmt: skip
    chosen = [present[present["kind"] == kind].head(per_kind) for kind in ("drawn", "mesh")]
    return pd.concat(chosen).drop(columns="named")


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
    rate = f"held {grip['success_rate']:.0%}"
    if "robustness_mean" in grip and pd.notna(grip["robustness_mean"]):
        rate += f", {grip['robustness_mean']:.1f} g"
    return rate
