"""The figures that show the study's answers, drawn from its result files.

- :func:`forest_plot`: every method's paired top-1 success minus best-Q_C's, with its 95 %
  interval, sorted, the oracle's gap as a reference line (``benchmark/leaderboard.json``);
- :func:`ablation_plot`: the ablation's ROC-AUC difference of each feature set to all twelve
  (``ablation/ablation.json``);
- :func:`profile_plot`: the performance profiles, the methods the answers name drawn strongly and
  the rest faint (``leaderboard.json``);
- :func:`retest_plot`: the labels' within-object test-retest (``calibration/calibration.json``).

Colours are Okabe and Ito's colour-blind-safe palette, and every verdict has its own marker too,
so no reading rests on hue alone. The marker of an interval is its
:func:`~classifiers.evaluation.verdicts.relation` to zero, the rule of the leaderboard's verdicts.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from classifiers.evaluation.verdicts import RELATIONS, relation
from grip_env.drawing import save_figure

#: Okabe & Ito (2008), "Color Universal Design": distinct in every common colour-vision deficiency.
OKABE_ITO = {"black": "#000000", "orange": "#E69F00", "sky blue": "#56B4E9",
             "bluish green": "#009E73", "yellow": "#F0E442", "blue": "#0072B2",
             "vermillion": "#D55E00", "reddish purple": "#CC79A7"}  # fmt: skip
FAINT = "#BBBBBB"
#: Colour and marker of each verdict (beats, is worse than, is not distinguishable from).
VERDICT_STYLE: dict[str, tuple[str, str]] = dict(zip(RELATIONS, (
    (OKABE_ITO["blue"], "o"), (OKABE_ITO["vermillion"], "s"), ("#666666", "D")), strict=True))
#: Figure width (inches) and resolution: 1,050 px, the docs' content width at 1.5x.
WIDTH, DPI = 7.0, 150


def forest_plot(board: Mapping[str, Any], path: Path) -> Path:
    """Each method's top-1 success minus the reference's, paired over the held-out objects, with
    95 % intervals, sorted; the oracle's gap dashed (the reference and oracle are not rows)."""
    reference = board["reference"]
    rows = {name: row["success_difference_vs_reference"] for name, row in board["methods"].items()
            if name not in (reference, "oracle")}  # fmt: skip
    held_out = len(board["objects"]) + len(board["degenerate_objects"])
    fig, ax = _interval_rows(rows, f"top-1 success minus {reference}'s (paired, 95 % interval)")
    oracle = board["methods"].get("oracle", {}).get("success_difference_vs_reference")
    if oracle is not None:
        ax.axvline(oracle["estimate"], color=OKABE_ITO["black"], linestyle="--", linewidth=1.2)
        ax.annotate(f"oracle {oracle['estimate']:+.3f}", (oracle["estimate"], 1.0),
                    xycoords=("data", "axes fraction"), xytext=(-4, -4),
                    textcoords="offset points", ha="right", va="top", fontsize=9)
    ax.set_title(f"Each method's pick against {reference}'s, over {held_out} held-out objects",
                 fontsize=11)
    return _save(fig, path)


def ablation_plot(ablation: Mapping[str, Any], path: Path) -> Path:
    """Each feature set's paired ROC-AUC difference to the reference set, with 95 % intervals."""
    model, reference = ablation["model"], ablation["reference"]
    rows = {name: block["paired_difference"][model]["roc_auc"]
            for name, block in ablation["feature_sets"].items()
            if name != reference and block["paired_difference"][model]["roc_auc"]["mean"]
            is not None}  # fmt: skip
    fig, ax = _interval_rows(rows, f"ROC-AUC minus {reference}'s ({model}, paired over folds, "
                             "95 % interval)")
    ax.set_title(f"What each feature set scores against all twelve measures ({model})",
                 fontsize=11)
    return _save(fig, path)


def profile_plot(board: Mapping[str, Any], strong: Sequence[str], path: Path) -> Path:
    """Performance profiles: ``strong`` methods in colour, random and the oracle as black
    references, every other method a faint grey line."""
    taus = np.asarray(board["taus"], dtype=float)
    fig = Figure(figsize=(WIDTH, 4.4))
    ax = fig.subplots()
    colours = [OKABE_ITO[c] for c in ("blue", "orange", "bluish green", "reddish purple",
                                      "vermillion", "sky blue")]  # fmt: skip
    dashes = ("-", "--", "-.", ":", (0, (5, 1, 1, 1)), (0, (1, 1)))
    references = {"oracle": ":", "random": "--"}
    shown = [name for name in strong if name in board["methods"] and name not in references]
    for name, row in board["methods"].items():
        if name not in shown and name not in references:
            ax.step(taus, row["profile"], where="post", color=FAINT, linewidth=0.8, zorder=1)
    for k, name in enumerate(shown):
        ax.step(taus, board["methods"][name]["profile"], where="post", linewidth=2.2,
                color=colours[k % len(colours)], linestyle=dashes[k % len(dashes)], label=name,
                zorder=3)  # fmt: skip
    for name, style in references.items():
        if name in board["methods"]:
            ax.step(taus, board["methods"][name]["profile"], where="post", linewidth=1.2,
                    color=OKABE_ITO["black"], linestyle=style, label=name, zorder=2)  # fmt: skip
    handles, labels = ax.get_legend_handles_labels()
    handles.append(Line2D([], [], color=FAINT, linewidth=0.8))
    labels.append("every other method")
    ax.legend(handles, labels, fontsize=9, loc="lower left")
    ax.set(xlim=(taus.min(), taus.max()), ylim=(0, 1.02),
           xlabel="normalised score τ (0 = random pick, 1 = oracle)",
           ylabel="share of objects × runs scoring above τ")  # fmt: skip
    ax.grid(alpha=0.3)
    ax.set_title("Performance profiles on the held-out objects", fontsize=11)
    return _save(fig, path)


def retest_plot(check: Mapping[str, Any], target: float, path: Path) -> Path:
    """Each scored object's Spearman between two disjoint sets of its grips' trials, sorted, with
    the mean and its 95 % interval and the target."""
    rows = [r for r in check.get("per_object", []) if r.get("spearman") is not None]
    rows.sort(key=lambda r: r["spearman"])
    fig = Figure(figsize=(WIDTH, 0.28 * len(rows) + 1.9))
    ax = fig.subplots()
    y = np.arange(len(rows))
    ax.scatter([r["spearman"] for r in rows], y, color=OKABE_ITO["blue"], zorder=3, s=28)
    ax.set_yticks(y, [str(r["object_id"]) for r in rows], fontsize=9)
    if check.get("measured") is not None:
        low, high = check["ci"]
        ax.axvspan(low, high, color=OKABE_ITO["sky blue"], alpha=0.3, zorder=1,
                   label=f"mean {check['measured']:.2f} [{low:.2f}, {high:.2f}]")
        ax.axvline(check["measured"], color=OKABE_ITO["blue"], linewidth=1.5, zorder=2)
    ax.axvline(target, color=OKABE_ITO["vermillion"], linestyle="--", linewidth=1.5,
               label=f"target {target:g}")
    ax.set(xlim=(-1.05, 1.05), xlabel="Spearman of the grips' mean robustness, trial set A "
           "against set B")  # fmt: skip
    ax.legend(fontsize=9, loc="lower left")
    ax.grid(axis="x", alpha=0.3)
    ax.set_title(f"Do two sets of {check.get('trials_per_set')} trials rank an object's grips "
                 f"alike? ({len(rows)} objects)", fontsize=11)
    return _save(fig, path)


# ---------------------------------------------------------------------------------- helpers
def _interval_rows(rows: Mapping[str, Mapping[str, Any]], xlabel: str) -> tuple[Figure, Axes]:
    """A forest of ``{name: {"estimate" or "mean", "ci"}}`` sorted by the point value (largest
    on top), each marked by its verdict, a zero line and a verdict legend."""
    points = {name: float(row.get("estimate", row.get("mean"))) for name, row in rows.items()}
    order = sorted(points, key=points.get)  # type: ignore[arg-type]
    fig = Figure(figsize=(WIDTH, 0.36 * len(order) + 1.9))
    ax = fig.subplots()
    ax.axvline(0.0, color=OKABE_ITO["black"], linewidth=1.0)
    for y, name in enumerate(order):
        low, high = (float(v) for v in rows[name]["ci"])
        colour, marker = VERDICT_STYLE[relation((low, high))]
        ax.plot([low, high], [y, y], color=colour, linewidth=2.0, solid_capstyle="butt")
        ax.plot(points[name], y, marker=marker, color=colour, markersize=7, linestyle="none")
    ax.set_yticks(range(len(order)), order, fontsize=9)
    ax.set_xlabel(xlabel, fontsize=9)
    ax.grid(axis="x", alpha=0.3)
    used = {relation(tuple(float(v) for v in rows[n]["ci"])) for n in order}
    handles = [Line2D([], [], color=VERDICT_STYLE[r][0], marker=VERDICT_STYLE[r][1],
                      linewidth=2.0, label=_legend_label(r)) for r in RELATIONS if r in used]
    if handles:
        ax.legend(handles=handles, fontsize=8, loc="best")
    return fig, ax


def _legend_label(verdict: str) -> str:
    return {"beats": "interval above 0", "is worse than": "interval below 0"}.get(
        verdict, "interval contains 0")


def _save(fig: Figure, path: Path) -> Path:
    fig.tight_layout()
    return save_figure(fig, path, dpi=DPI)


#: Each answer figure's file (in the report's figures folder) and its alt text.
ALT_TEXT: dict[str, str] = {
    "forest.png": "Forest plot: every method's top-1 success minus best-Q_C's, paired over the "
                  "held-out objects, with 95 % intervals, sorted, the oracle's gap dashed",
    "ablation_auc.png": "Each feature set's ROC-AUC minus all twelve measures', with 95 % "
                        "intervals, sorted",
    "profile.png": "Performance profiles: share of held-out objects and runs scoring above each "
                   "normalised score, the methods the answers name in colour, the rest faint",
    "retest.png": "Within-object test-retest of the labels: each object's Spearman between two "
                  "disjoint sets of trials, with the mean, its interval and the target",
}


def draw_answer_figures(out: Path, strong: Sequence[str], fig_dir: Path) -> dict[str, Path]:
    """Draw the answer figures of the study in ``out`` whose results exist into ``fig_dir``
    (``strong``: the methods the profile draws in colour); ``{file name: path}``."""
    from grip_env.calibration import RETEST_TARGET

    board = _read(out / "benchmark" / "leaderboard.json")
    ablation = _read(out / "ablation" / "ablation.json")
    within = _read(out / "calibration" / "calibration.json").get("checks", {}).get("within_object")
    drawn = {}
    if board.get("methods"):
        drawn["forest.png"] = forest_plot(board, fig_dir / "forest.png")
        drawn["profile.png"] = profile_plot(board, strong, fig_dir / "profile.png")
    if ablation.get("feature_sets"):
        drawn["ablation_auc.png"] = ablation_plot(ablation, fig_dir / "ablation_auc.png")
    if within and any(r.get("spearman") is not None for r in within.get("per_object", [])):
        drawn["retest.png"] = retest_plot(within, RETEST_TARGET, fig_dir / "retest.png")
    return {name: drawn[name] for name in ALT_TEXT if name in drawn}


def _read(path: Path) -> dict[str, Any]:
    return json.loads(path.read_text()) if path.is_file() else {}
