"""PNG figures of classifier results (matplotlib, Agg backend)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from sklearn.calibration import calibration_curve
from sklearn.metrics import RocCurveDisplay


def plot_roc(
    labels: np.ndarray, probabilities: Mapping[str, np.ndarray], path: Path,
    title: str = "ROC (held out)",
) -> Path:
    """ROC curve of each model on the same grips (sklearn's ``RocCurveDisplay``)."""
    figure, axes = plt.subplots(figsize=(5.5, 5))
    for name, probability in probabilities.items():
        RocCurveDisplay.from_predictions(labels, probability, name=name, ax=axes,
                                         plot_chance_level=False)  # fmt: skip
    axes.plot([0, 1], [0, 1], color="grey", linestyle=":", linewidth=1, label="chance")
    axes.set(xlabel="false positive rate", ylabel="true positive rate")
    axes.set_title(title, fontsize=9)
    axes.legend(fontsize=7, loc="lower right")
    return _save(figure, path)


def plot_calibration(
    labels: np.ndarray, probabilities: Mapping[str, np.ndarray], path: Path, bins: int = 10,
    title: str = "Calibration, held-out objects",
) -> Path:
    """Reliability diagram of each model (top) and the grips per probability bin (bottom)."""
    figure, (top, bottom) = plt.subplots(2, 1, figsize=(5.5, 6.5), sharex=True,
                                         gridspec_kw={"height_ratios": [3, 1.4]})  # fmt: skip
    edges = np.linspace(0.0, 1.0, bins + 1)
    for name, probability in probabilities.items():
        observed, predicted = calibration_curve(labels, probability, n_bins=bins)
        (line,) = top.plot(predicted, observed, marker="o", markersize=3, label=name)
        counts, _ = np.histogram(probability, bins=edges)
        bottom.stairs(counts, edges, color=line.get_color(), linewidth=1)
    top.plot([0, 1], [0, 1], color="grey", linestyle=":", linewidth=1, label="perfect")
    top.set(ylabel="observed success rate")
    top.set_title(title, fontsize=9)
    top.legend(fontsize=7, loc="upper left")
    bottom.set(xlabel="predicted success probability", ylabel="grips per bin")
    return _save(figure, path)


def plot_ablation(result: Mapping[str, Any], metric: str, path: Path) -> Path:
    """Bars of ``metric`` per feature set and of its paired difference to the reference set."""
    sets = result["feature_sets"]
    names = list(sets)
    model = result["model"]
    summaries = [sets[name]["models"][model][metric] for name in names]
    differences = [sets[name]["paired_difference"][model][metric] for name in names]
    figure, (left, right) = plt.subplots(1, 2, figsize=(11, 0.35 * len(names) + 1.5), sharey=True)
    _bars(left, names, summaries, f"{metric} ({model})")
    _bars(right, names, differences, f"paired difference to '{result['reference']}'")
    right.axvline(0.0, color="black", linewidth=0.8)
    left.invert_yaxis()  # shared: the reference set on top
    return _save(figure, path)


def _bars(axes: plt.Axes, names: list[str], summaries: list[dict[str, Any]], title: str) -> None:
    means = np.array([np.nan if s["mean"] is None else s["mean"] for s in summaries], dtype=float)
    low = np.array([np.nan if s["ci"][0] is None else s["ci"][0] for s in summaries], dtype=float)
    high = np.array([np.nan if s["ci"][1] is None else s["ci"][1] for s in summaries], dtype=float)
    errors = np.vstack([means - low, high - means])
    positions = np.arange(len(names))
    axes.barh(positions, means, xerr=errors, capsize=3, color="tab:blue", alpha=0.75)
    axes.set_yticks(positions, names, fontsize=8)
    axes.set_title(title, fontsize=9)


def _save(figure: plt.Figure, path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path
