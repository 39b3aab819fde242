"""PNG figures of classifier results (matplotlib, Agg backend)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from sklearn.calibration import calibration_curve
from sklearn.metrics import RocCurveDisplay

#: Colours of the compared lines: tab10 without its grey, which the references use.
_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
            "tab:pink", "tab:olive", "tab:cyan")
_DASHES = ("-", "--", "-.", ":")
_MARKERS = ("o", "s", "^", "v", "D", "P", "X", "*", "h", "<", ">", "p")
#: Reference lines (chance levels, oracles, the paper's index): shades of grey.
_REFERENCE_COLOURS = ("black", "dimgray", "darkgray", "silver")
_REFERENCE_MARKERS = ("x", "+", "1", "2")


def line_styles(names: Sequence[str], references: Sequence[str] = ()) -> dict[str, dict[str, Any]]:
    """Keyword arguments of ``plot``/``step`` for each named line, so that no two look alike
    and none hides another.

    The k-th compared line gets colour k of :data:`_COLOURS` (nine, one hue each), dash k of
    :data:`_DASHES` and marker k of :data:`_MARKERS`, so no two of the first 36 share colour and
    dash, and lines next to each other differ in both; ``references`` are grey. Widths decrease
    in drawing order, so a line drawn over an identical one leaves it showing on both sides and
    through its dashes; markers sit every ``len(names)`` points, each line's offset by its
    position, so the markers of coinciding lines do not cover each other.
    """
    lines = [n for n in names if n not in references]
    refs = [n for n in names if n in references]
    styles = {}
    for k, name in enumerate(lines):
        styles[name] = {"color": _COLOURS[k % len(_COLOURS)], "linestyle": _DASHES[k % 4],
                        "marker": _MARKERS[k % len(_MARKERS)]}
    for k, name in enumerate(refs):
        styles[name] = {"color": _REFERENCE_COLOURS[k % len(_REFERENCE_COLOURS)],
                        "linestyle": _DASHES[1 + k % 3],
                        "marker": _REFERENCE_MARKERS[k % len(_REFERENCE_MARKERS)]}
    count = len(names)
    for order, name in enumerate(names):
        styles[name] |= {"linewidth": 1.0 + 1.5 * (count - 1 - order) / max(count - 1, 1),
                         "markersize": 4, "markevery": (order, count), "zorder": 2 + order}
    return styles


def draw_lines(
    axes: plt.Axes, series: Mapping[str, tuple[Any, Any]], references: Sequence[str] = (),
    drawstyle: str = "default", every_point: bool = False,
) -> list[Any]:
    """Each named ``(x, y)`` series as a line with a look of its own (:func:`line_styles`),
    in order. A series identical to one drawn before it lies under it whatever its style, so
    its legend label says so: ``"b (= a)"``. ``every_point``: a marker on every point (short
    series) instead of staggered ones."""
    styles = line_styles(list(series), references)
    seen: list[tuple[str, np.ndarray, np.ndarray]] = []
    drawn = []
    for name, (x, y) in series.items():
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        twin = next((other for other, ox, oy in seen if ox.shape == x.shape and oy.shape == y.shape
                     and np.allclose(ox, x, equal_nan=True)
                     and np.allclose(oy, y, equal_nan=True)), None)  # fmt: skip
        style = styles[name] | ({"markevery": None} if every_point else {})
        (line,) = axes.plot(x, y, drawstyle=drawstyle, **style,
                            label=name if twin is None else f"{name} (= {twin})")
        drawn.append(line)
        seen.append((name, x, y))
    return drawn


def plot_roc(
    labels: np.ndarray, probabilities: Mapping[str, np.ndarray], path: Path,
    title: str = "ROC (held out)",
) -> Path:
    """ROC curve of each model on the same grips (sklearn's ``RocCurveDisplay``)."""
    figure, axes = plt.subplots(figsize=(5.5, 5))
    styles = line_styles(list(probabilities), references=("random",))
    for name, probability in probabilities.items():
        RocCurveDisplay.from_predictions(labels, probability, name=name, ax=axes,
                                         plot_chance_level=False)  # fmt: skip
        axes.lines[-1].set(**styles[name])
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
    styles = line_styles(list(probabilities), references=("random",))
    for name, probability in probabilities.items():
        observed, predicted = calibration_curve(labels, probability, n_bins=bins)
        style = styles[name] | {"markevery": None}  # few points: a marker on each
        top.plot(predicted, observed, label=name, **style)
        counts, _ = np.histogram(probability, bins=edges)
        bottom.stairs(counts, edges, color=style["color"], linestyle=style["linestyle"],
                      linewidth=style["linewidth"], zorder=style["zorder"])
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
    objects = result.get("cv", {}).get("n_objects")
    _bars(left, names, summaries, f"{metric} ({model})"
          + (f", {objects} objects" if objects is not None else ""), mark_flat=True)  # fmt: skip
    _bars(right, names, differences, f"paired difference to '{result['reference']}'")
    right.axvline(0.0, color="black", linewidth=0.8)
    left.invert_yaxis()  # shared: the reference set on top
    return _save(figure, path)


def _bars(axes: plt.Axes, names: list[str], summaries: list[dict[str, Any]], title: str,
          mark_flat: bool = False) -> None:  # fmt: skip
    """Horizontal bars with their intervals; ``mark_flat``: grey the zero-width ones (a model
    that scored every grip alike in every fold), and say how many in the title."""
    means = np.array([np.nan if s["mean"] is None else s["mean"] for s in summaries], dtype=float)
    low = np.array([np.nan if s["ci"][0] is None else s["ci"][0] for s in summaries], dtype=float)
    high = np.array([np.nan if s["ci"][1] is None else s["ci"][1] for s in summaries], dtype=float)
    errors = np.vstack([means - low, high - means])
    positions = np.arange(len(names))
    flat = np.isclose(low, high) & mark_flat  # zero width: constant scores in every fold
    colours = np.where(flat, "tab:gray", "tab:blue")
    axes.barh(positions, means, xerr=errors, capsize=3, color=list(colours), alpha=0.75)
    axes.set_yticks(positions, names, fontsize=8)
    if flat.any():
        title += f"\ngrey: zero-width interval ({int(flat.sum())} of {len(names)}: constant scores)"
    axes.set_title(title, fontsize=9)


def _save(figure: plt.Figure, path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path
