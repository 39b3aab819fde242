"""The study report's power section: how wide the three intervals are, and how many objects
(and trials per grip) it takes to narrow each one to its target.

Two sources: the study's own intervals (always; one size, projected by the ``1/sqrt(n)`` law)
and, when ``grip-env power`` wrote ``<study>/power/power.json``, a measured power curve (its
figure, the half-widths per size and the fitted laws' projections).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import matplotlib.ticker as ticker
import numpy as np
import pandas as pd

from classifiers.evaluation.half_widths import (
    FIGURE_FILE,
    POWER_FILE,
    TARGETS,
    Law,
    paired_bootstrap,
)
from classifiers.report.document import Report
from classifiers.report.judge import FEW_OBJECTS

LABELS = {"roc_auc": "best model's ROC-AUC", "hand_difference": "hand features (paired ΔAUC)",
          "rl_minus_best_qc": "RL − best Q_C (held out)"}  # fmt: skip


def study_half_widths(out: Path) -> dict[str, dict[str, float]]:
    """The three half-widths of a study folder's results: ``{quantity: {"objects", "trials",
    "estimate", "half_width"}}`` (a quantity is missing when its stage did not run)."""
    found: dict[str, dict[str, float]] = {}
    metrics, ablation = _json(out / "classifiers" / "metrics.json"), _json(
        out / "ablation" / "ablation.json")
    selector = _json(out / "selector" / "selector.json")
    if metrics:
        scores = {k: v["roc_auc"] for k, v in metrics["models"].items() if "roc_auc" in v}
        best = max(scores, key=lambda k: scores[k]["mean"] or -1.0)
        found["roc_auc"] = _from_interval(scores[best], metrics["cv"]["n_objects"])
    if ablation:
        block = ablation["feature_sets"].get("without_hand", {}).get("paired_difference", {})
        value = block.get(ablation["model"], {}).get("roc_auc")
        if value and value["mean"] is not None:
            found["hand_difference"] = _from_interval(value, ablation["cv"]["n_objects"])
    board = _json(out / "benchmark" / "leaderboard.json")
    paired = _rl_difference(board) if board else None
    if selector and paired:
        n = len(selector["split"]["train"]) + len(selector["split"]["test"])
        found["rl_minus_best_qc"] = {"objects": n, **paired}
    elif selector and {"rl", "best_qc"} <= set(selector["policies"]):
        policies = selector["policies"]
        mean, half = paired_bootstrap(np.asarray(policies["rl"]["per_object"]),
                                      np.asarray(policies["best_qc"]["per_object"]),
                                      selector["split"]["seed"])  # fmt: skip
        n = len(selector["split"]["train"]) + len(selector["split"]["test"])
        found["rl_minus_best_qc"] = {"objects": n, "estimate": mean, "half_width": half}
    return found


def _rl_difference(board: dict[str, Any]) -> dict[str, float] | None:
    """The leaderboard's paired RL − best-Q_C difference in top-1 success over every held-out
    object and every selector seed (``success_difference_vs_reference``), if it has one."""
    rl = board.get("methods", {}).get("rl", {})
    paired = rl.get("success_difference_vs_reference")
    if board.get("reference") != "best_qc" or not paired or paired.get("ci") is None:
        return None
    low, high = paired["ci"]
    return {"estimate": paired["estimate"], "half_width": (high - low) / 2.0}


def _from_interval(value: dict[str, Any], objects: int) -> dict[str, float]:
    """Half of an interval's width (intervals of the study are symmetric unless clipped)."""
    low, high = value["ci"]
    return {"objects": objects, "estimate": value["mean"], "half_width": (high - low) / 2.0}


def plot_power(summary: dict[str, Any], path: Path) -> Path:
    """Half-width against objects (left, log-log) and against trials per grip (right), with the
    fitted laws (lines) and the targets (dotted)."""
    curve = pd.DataFrame(summary["curve"])
    figure, (left, right) = plt.subplots(1, 2, figsize=(10, 4.2))
    fitted = summary["laws"]
    for k, quantity in enumerate(q for q in LABELS if q in set(curve["quantity"]) & set(fitted)):
        color = f"C{k}"
        rows = curve[curve["quantity"] == quantity]
        law = Law(**{f: summary["laws"][quantity][f] for f in ("a", "b", "points")})
        target = summary["targets"].get(quantity)
        _axis(left, rows[rows["axis"] == "objects"], "objects", color, LABELS[quantity], law)
        _axis(right, rows[rows["axis"] == "trials"], "trials", color, LABELS[quantity], law)
        if target:
            for axes in (left, right):
                axes.axhline(target, color=color, linestyle=":", linewidth=1)
    left.set(xscale="log", yscale="log", xlabel="objects", ylabel="95% interval half-width")
    right.set(yscale="log", xlabel="trials per grip", ylabel="95% interval half-width")
    for axes in (left, right):  # plain numbers on the log axes
        axes.set_yticks([0.01, 0.02, 0.05, 0.1, 0.2, 0.5])
        axes.set_ylim(*_limits(curve["half_width"], summary["targets"].values()))
    left.set_xticks([5, 10, 20, 50, 100, 200, 500])
    for axis in (left.xaxis, left.yaxis, right.yaxis):
        axis.set_major_formatter(ticker.ScalarFormatter())
        axis.set_minor_formatter(ticker.NullFormatter())
    left.set_title("vs objects (trials fixed); lines: fitted law", fontsize=9)
    right.set_title("vs trials per grip (objects fixed); dotted: targets", fontsize=9)
    left.legend(fontsize=7)
    figure.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path


def _limits(half: pd.Series, targets: Any) -> tuple[float, float]:
    """Y range covering the positive half-widths and the targets."""
    values = [*half[half > 0], *targets]
    return min(values) / 1.3, max(values) * 1.3


def _axis(axes: Any, rows: pd.DataFrame, axis: str, color: str, label: str, law: Any) -> None:
    """Subsamples (small dots), their means (large) and the law at each size held fixed."""
    if rows.empty:
        return
    other = "trials" if axis == "objects" else "objects"
    axes.scatter(rows[axis], rows["half_width"], color=color, s=12, alpha=0.6)
    means = rows.groupby([other, axis])["half_width"].mean()
    for k, (held, found) in enumerate(means.groupby(level=0)):
        found = found.droplevel(0)
        axes.plot(found.index, found.to_numpy(), "os"[k % 2], color=color, markersize=5,
                  label=label if k == 0 else None)
        stretch = 3 if axis == "objects" else 1
        grid = np.geomspace(found.index.min(), found.index.max() * stretch, 50)
        fitted = [law.half_width(x, held) if axis == "objects" else law.half_width(held, x)
                  for x in grid]  # fmt: skip
        axes.plot(grid, fitted, color=color, linewidth=1, linestyle="-" if k == 0 else "--")


def power_section(report: Report, out: Path) -> None:
    """The study report's "Statistical power" section (see the module docstring)."""
    report.heading("Statistical power: how many objects and trials")
    measured = study_half_widths(out)
    trials = _study_trials(out)
    rows, unjudged = {}, []
    for quantity, value in measured.items():
        target, half, n = TARGETS[quantity], value["half_width"], value["objects"]
        met, why = target_met(half, target, n)
        rows[LABELS[quantity]] = {
            "estimate": value["estimate"], "half-width": half, "objects": n, "target": target,
            "met": met,
            "objects needed (1/sqrt(n))": (math.ceil(n * (half / target) ** 2)
                                           if half and math.isfinite(half) else "–"),
        }
        if why:
            unjudged.append(f"{LABELS[quantity]}: {why}")
    if rows:
        report.table(pd.DataFrame(rows).T.rename_axis("question"), float_format="{:.3f}",
                     caption=f"This study's 95% interval half-widths at {trials} trials per grip "
                     "against the targets; the objects needed scale this study's size by "
                     "(half-width / target)^2, the 1/sqrt(n) law from a single size.")
    if unjudged:
        report.text("Not judged against its target: " + "; ".join(unjudged) + ".")
    summary = _json(out / "power" / POWER_FILE)
    if summary is None:
        report.text("No measured power curve: `grip-env power --data DIR --out "
                    f"{out}/power` subsamples a dataset by objects and trials, and the next "
                    "`grip-env study` into this folder (every stage reused) shows it here.")
        return
    _curve_tables(report, summary)
    if (out / "power" / FIGURE_FILE).exists():
        report.figure(f"power/{FIGURE_FILE}", "Interval half-width of each question against "
                      "the number of objects (left) and of trials per grip (right): dots are "
                      "seeded subsamples, lines the fitted law h² = (a + b/t)/n, dotted the "
                      "targets.")


def target_met(half: float | None, target: float, objects: int) -> tuple[str, str | None]:
    """Whether a half-width meets its target ("yes", "no" or "not judged") and, when not judged,
    why: a zero (or undefined) width comes from constant scores or too few objects to vary,
    not from precision, and a width within target on few objects is itself too uncertain."""
    if half is None or not math.isfinite(half) or half <= 0:
        return "not judged", ("its interval has zero width (constant scores, or too few objects "
                              "for a resample to differ): it measures no precision")
    if half > target:
        return "no", None
    if objects < FEW_OBJECTS:
        return "not judged", (f"a half-width within target on {objects} objects (fewer than "
                              f"{FEW_OBJECTS}) is itself too uncertain")
    return "yes", None


def _curve_tables(report: Report, summary: dict[str, Any]) -> None:
    curve = pd.DataFrame(summary["curve"])
    for axis in ("objects", "trials"):
        rows = curve[curve["axis"] == axis]
        if rows.empty:
            continue
        table = rows.groupby(["quantity", axis])["half_width"].mean().unstack(axis)
        table.index = [LABELS.get(q, q) for q in table.index]
        table = table.astype(object).where(table.notna(), "–")  # a size not measured
        report.table(table.rename_axis("half-width"), float_format="{:.3f}",
                     caption=f"Measured half-width against {axis} (mean over seeded subsamples; "
                     f"{_held(rows, axis)}).")
    if summary.get("unmeasured"):
        report.text("Not measurable on this dataset (no subsample gives a positive half-width, "
                    "too few objects to resample): "
                    + ", ".join(LABELS.get(q, q) for q in summary["unmeasured"]) + ".")
    projection = {
        LABELS.get(q, q): {f"t = {t}": str(n) for t, n in found.items()}
        | {"target": f"{summary['targets'][q]:g}",
           "exponent": f"{summary['laws'][q]['exponent']:.2f}"}
        for q, found in summary["projection"].items()
    }
    report.table(pd.DataFrame(projection).T.rename_axis("objects needed"), float_format="{:.2f}",
                 caption="Objects needed for each target at t trials per grip, from the fitted "
                 "law (t = inf: noiseless labels, the floor set by the objects alone); exponent: "
                 "fitted slope of log half-width against log objects (1/sqrt(n): -0.5).")
    selector = curve[curve["quantity"] == "rl_minus_best_qc"]
    if (selector["half_width"] == 0).any():
        report.text("A selector half-width of 0 means the trained policy picked the best-Q_C "
                    "grip on every held-out object; such fits carry no spread and are left out "
                    "of the law.")
    source = summary.get("source", {})
    if source:
        report.text("Power curve measured on " + "; ".join(f"{k}: {v}" for k, v in source.items())
                    + ".")


def _held(rows: pd.DataFrame, axis: str) -> str:
    other = "trials" if axis == "objects" else "objects"
    values = sorted(set(rows[other].astype(int)))
    return f"{other} {values[0]}" if len(values) == 1 else f"{other} {values[0]}–{values[-1]}"


def _study_trials(out: Path) -> str:
    """Trials per grip of the dataset the study learnt on: its own ``dataset/`` or the one
    ``data.json`` names (the standard dataset)."""
    manifest = _json(out / "dataset" / "manifest.json")
    if manifest is None:
        data = _json(out / "data.json") or {}
        manifest = _json(Path(data.get("dataset", out / "dataset")) / "manifest.json") or {}
    return str(manifest.get("trials", "?"))


def _json(path: Path) -> dict[str, Any] | None:
    return json.loads(path.read_text()) if path.exists() else None
