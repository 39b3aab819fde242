"""Statistical power of the study: how its three intervals narrow with objects and with trials.

A larger dataset is subsampled (:func:`subsample`): whole objects drawn without replacement, at
most ``grips`` grips kept per object, and ``trials`` of each grip's recorded trials kept. The
dataset stores per grip only the number of trials and of successes, and the kept trials are a
uniformly random subset of them, so the kept successes are drawn exactly from the hypergeometric
law; ``success_rate`` and ``success`` are recomputed from them. The graded outcome
(``robustness_mean``/``std``) cannot be recomputed from the counts and is dropped when trials are
subsampled.

On each subsample three half-widths are measured (:data:`QUANTITIES`), each exactly as the study
computes its interval:

- ``roc_auc``: the model's (default ``learning.ablation_model``, the ablation's) ROC-AUC,
  corrected resampled t over folds x repeats
  (:func:`classifiers.evaluation.cross_validation.half_width`);
- ``hand_difference``: the ablation's paired ROC-AUC difference ``without_hand − all_twelve``,
  same folds and seeds, same interval;
- ``rl_minus_best_qc``: first-pick success of the RL selector minus the best-Q_C pick on the
  held-out objects, per object, 95% percentile bootstrap over those objects (the selector's own
  resampling). The policy is retrained per subsample (about half a minute each), so it is measured
  at a few sizes only.

The fitted law (:func:`fit_law`) is ``h^2 = (a + b / t) / n`` for ``n`` objects and ``t`` trials
per grip: between-object spread ``a`` plus label noise ``b / t``, both shrinking as ``1/sqrt(n)``.
At fixed trials it is the ``1/sqrt(n)`` law; :func:`objects_needed` inverts it for a target.
Every subsample is drawn from ``numpy.random.default_rng([seed, objects, trials, grips,
replicate])``, so a curve is reproducible point by point.
"""

from __future__ import annotations

import math
import tempfile
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pandas as pd

from classifiers.evaluation.half_widths import (
    POWER_FILE,
    TARGETS,
    Law,
    exponent,
    fit_law,
    objects_needed,
    paired_bootstrap,
)
from grip_env.columns import FEATURES, ROBUSTNESS
from grip_env.config import Config
from grip_env.dataset.jobs import SUCCESS_THRESHOLD

QUANTITIES: tuple[str, ...] = tuple(TARGETS)
CLASSIFIER_QUANTITIES: tuple[str, ...] = ("roc_auc", "hand_difference")
GROUP = "object_id"


# ------------------------------------------------------------------------------- subsampling
def subsample(
    table: pd.DataFrame, objects: int | None = None, trials: int | None = None,
    grips: int | None = None, seed: int = 0, replicate: int = 0,
) -> pd.DataFrame:
    """A seeded subsample of a grip table: ``objects`` whole objects, at most ``grips`` grips per
    object, ``trials`` trials per grip (None keeps all). Row order and index follow ``table``.

    Raises:
        ValueError: a size below 1, more objects than the table holds, more trials than its
            grips recorded, or a table without the outcome columns.
    """
    for name, value in (("objects", objects), ("trials", trials), ("grips", grips)):
        if value is not None and (int(value) != value or value < 1):
            raise ValueError(f"{name} must be a positive integer or None, got {value!r}")
    missing = [c for c in (GROUP, "trials", "successes") if c not in table.columns]
    if missing:
        raise ValueError(f"the table lacks the columns {missing} (a generated dataset has them)")
    rng = np.random.default_rng([seed, objects or 0, trials or 0, grips or 0, replicate])
    ids = np.sort(table[GROUP].astype(str).unique())
    if objects is not None and objects > ids.size:
        raise ValueError(f"objects={objects} but the table holds {ids.size} objects")
    kept = ids if objects is None else np.sort(rng.choice(ids, size=objects, replace=False))
    rows = table[table[GROUP].astype(str).isin(kept).to_numpy()]
    if grips is not None:
        rows = _keep_grips(rows, grips, rng)
    if trials is not None:
        rows = _keep_trials(rows, trials, rng)
    return rows


def _keep_grips(rows: pd.DataFrame, grips: int, rng: np.random.Generator) -> pd.DataFrame:
    """At most ``grips`` uniformly drawn rows of each object (vectorised: rank of a random key)."""
    key = pd.Series(rng.random(len(rows)), index=rows.index)
    rank = key.groupby(rows[GROUP].to_numpy()).rank(method="first")
    return rows[(rank <= grips).to_numpy()]


def _keep_trials(rows: pd.DataFrame, trials: int, rng: np.random.Generator) -> pd.DataFrame:
    """``trials`` of each grip's trials: successes drawn from the hypergeometric law."""
    recorded = rows["trials"].to_numpy(int)
    if trials > recorded.min(initial=trials):
        raise ValueError(f"trials={trials} but some grips recorded only {recorded.min()} trials")
    good = rows["successes"].to_numpy(int)
    kept = rng.hypergeometric(good, recorded - good, np.full(len(rows), trials))
    out = rows.drop(columns=[c for c in ROBUSTNESS if c in rows.columns])
    out = out.assign(trials=trials, successes=kept, success_rate=kept / trials)
    return out.assign(success=out["success_rate"].to_numpy() >= SUCCESS_THRESHOLD)


# ------------------------------------------------------------------------------- measurement
def classifier_half_widths(
    table: pd.DataFrame, config: Config, model: str | None = None
) -> dict[str, tuple[float, float]]:
    """``{quantity: (estimate, half-width)}`` of ``roc_auc`` and ``hand_difference``."""
    from classifiers.evaluation.cross_validation import cross_validate_models, half_width
    from classifiers.experiments.ablation import GRASP, SHARED

    learning = config.learning
    model = model or learning.ablation_model
    full = cross_validate_models(table, [model], FEATURES, learning)
    without = cross_validate_models(table, [model], SHARED + GRASP, learning)  # without_hand
    paired = without.merge(full, on=["repeat", "fold"], suffixes=("", "_ref"), validate="1:1")
    difference = (paired["roc_auc"] - paired["roc_auc_ref"]).to_numpy(float)
    auc = full["roc_auc"].to_numpy(float)
    return {
        "roc_auc": (float(np.nanmean(auc)), half_width(auc, learning.folds)),
        "hand_difference": (float(np.nanmean(difference)), half_width(difference, learning.folds)),
    }


def selector_half_width(table: pd.DataFrame, config: Config) -> tuple[float, float]:
    """(mean, half-width) of RL minus best-Q_C first-pick success on the held-out objects, the
    policy trained afresh on ``table``'s training objects (files go to a temporary folder)."""
    from classifiers.experiments.selector.evaluation import evaluate_selectors
    from classifiers.experiments.selector.training import train_selector

    with tempfile.TemporaryDirectory(prefix="grip-power-") as folder:
        trained = train_selector(table, config, folder, progress=False)
        report = evaluate_selectors(trained.model, table, config, classifiers=())
    policies = report["policies"]
    return paired_bootstrap(np.asarray(policies["rl"]["per_object"]),
                            np.asarray(policies["best_qc"]["per_object"]), config.learning.seed)


Measure = Callable[[pd.DataFrame, Config], dict[str, tuple[float, float]]]


def power_curve(
    table: pd.DataFrame, config: Config, objects: Sequence[int], trials: Sequence[int],
    replicates: int = 2, seed: int = 0, model: str | None = None,
    selector_objects: Sequence[int] = (), selector_trials: Sequence[int] = (),
    log: Callable[[str], None] = lambda _: None, trials_table: pd.DataFrame | None = None,
) -> pd.DataFrame:
    """Half-widths along two axes: ``objects`` (subsamples of ``table``, all its trials) and
    ``trials`` (subsamples of ``trials_table``, default ``table``, all its objects). The
    classifier quantities are measured ``replicates`` times per size (see :func:`_measure`); the
    selector, costlier, once per size in ``selector_objects`` / ``selector_trials``.

    Returns one row per measurement: ``quantity, axis, objects, trials, replicate, estimate,
    half_width, seconds`` (the wall time of the measurement the row comes from).
    """
    by_trials = table if trials_table is None else trials_table
    model = model or config.learning.ablation_model
    classify: Measure = lambda part, cfg: classifier_half_widths(part, cfg, model)  # noqa: E731
    select: Measure = lambda part, cfg: {"rl_minus_best_qc": selector_half_width(part, cfg)}  # noqa: E731
    rows = []
    for measure, n_reps, sizes, kind in ((classify, replicates, objects, "objects"),
                                         (classify, replicates, trials, "trials"),
                                         (select, 1, selector_objects, "objects"),
                                         (select, 1, selector_trials, "trials")):  # fmt: skip
        source = table if kind == "objects" else by_trials
        rows += _measure(source, kind, sizes, n_reps, seed, measure, config, log)
    return pd.DataFrame.from_records(rows, columns=[
        "quantity", "axis", "objects", "trials", "replicate", "estimate", "half_width",
        "seconds"])


def _measure(
    table: pd.DataFrame, axis: str, sizes: Sequence[int], replicates: int, seed: int,
    measure: Measure, config: Config, log: Callable[[str], None],
) -> list[dict[str, Any]]:
    """Measurements at each size along ``axis`` ("objects" or "trials") of ``table``; replicate
    ``r`` draws its own subsample and runs with ``learning.seed + r`` (its own folds, split and
    bootstrap), so the whole table too has replicates."""
    most = int(table[GROUP].nunique()) if axis == "objects" else int(table["trials"].min())
    rows = []
    for size in sizes:
        drawn = None if size >= most else int(size)
        n_use, t_use = (drawn, None) if axis == "objects" else (None, drawn)
        for replicate in range(replicates):
            part = subsample(table, n_use, t_use, seed=seed, replicate=replicate)
            seeded = config.override(learning={"seed": config.learning.seed + replicate})
            start = time.perf_counter()
            found = measure(part, seeded)
            seconds = time.perf_counter() - start
            n, t = int(part[GROUP].nunique()), int(part["trials"].min())
            rows += [{"quantity": quantity, "axis": axis, "objects": n, "trials": t,
                      "replicate": replicate, "estimate": estimate, "half_width": half,
                      "seconds": seconds}
                     for quantity, (estimate, half) in found.items()]  # fmt: skip
            log(f"[power] {axis} axis: {n} objects, {t} trials, replicate {replicate}: "
                + ", ".join(f"{q} ±{h:.3f}" for q, (_, h) in found.items())
                + f" ({seconds:.0f} s)")
    return rows


def fit_curve(curve: pd.DataFrame) -> dict[str, Law]:
    """One :class:`Law` per quantity from :func:`power_curve`'s rows (mean over replicates); a
    quantity no subsample gives a finite positive half-width for (too few objects to resample)
    has none.

    Raises:
        ValueError: no quantity has one: the dataset is too small to measure power on.
    """
    means = curve.groupby(["quantity", "objects", "trials"], as_index=False)["half_width"].mean()
    measurable = means[np.isfinite(means["half_width"]) & (means["half_width"] > 0)]
    laws = {str(q): fit_law(g["objects"], g["trials"], g["half_width"])
            for q, g in measurable.groupby("quantity", sort=False)}  # fmt: skip
    if not laws:
        raise ValueError(f"power: no subsample of this dataset ({int(curve['objects'].max())} "
                         "objects at most) gives a positive interval half-width to fit; use a "
                         "dataset of more objects (--data standard, the shipped one)")
    return laws


def pool(tables: Sequence[pd.DataFrame], trials: int | None = None, seed: int = 0) -> pd.DataFrame:
    """Several datasets of the same simulator as one table: every grip cut to ``trials`` trials
    (default: the fewest any grip recorded) by :func:`subsample`, and an object (by
    ``object_id``, e.g. a named shape in two runs) kept only from the first table holding it.

    Raises:
        ValueError: no table, or ``trials`` above what a table recorded.
    """
    if not tables:
        raise ValueError("pool needs at least one table")
    common = trials or min(int(t["trials"].min()) for t in tables)
    parts, seen = [], set()
    for index, table in enumerate(tables):
        ids = table[GROUP].astype(str)
        fresh = table[~ids.isin(seen).to_numpy()]
        seen.update(ids)
        cut = None if int(fresh["trials"].min()) == common else common
        parts.append(subsample(fresh, trials=cut, seed=seed, replicate=index))
    if len(parts) > 1:  # robustness may be over other trials in each table: not comparable
        parts = [p.drop(columns=[c for c in ROBUSTNESS if c in p.columns]) for p in parts]
    return pd.concat(parts, ignore_index=True)


#: Trials per grip the projections are given at (``inf``: noiseless labels).
PROJECTED_TRIALS: tuple[float, ...] = (1, 2, 4, 8, math.inf)


def summarise_curve(
    curve: pd.DataFrame, targets: dict[str, float] | None = None,
) -> dict[str, Any]:
    """``power.json``'s content: the rows, each quantity's law, its fitted exponent along the
    objects axis, and the objects needed for its target at :data:`PROJECTED_TRIALS`."""
    targets = dict(targets or TARGETS)
    laws = fit_curve(curve)
    summary: dict[str, Any] = {"targets": targets, "laws": {}, "projection": {},
                               "unmeasured": sorted(set(curve["quantity"]) - set(laws)),
                               "curve": curve.to_dict(orient="records")}  # fmt: skip
    for quantity, law in laws.items():
        along = curve[(curve["quantity"] == quantity) & (curve["axis"] == "objects")]
        means = along.groupby("objects")["half_width"].mean()
        summary["laws"][quantity] = {**law.as_dict(), "exponent": exponent(means.index, means)}
        if quantity in targets:
            summary["projection"][quantity] = {
                _trials_key(t): objects_needed(law, targets[quantity], t) for t in PROJECTED_TRIALS
            }
    return summary


def _trials_key(trials: float) -> str:
    return "inf" if math.isinf(trials) else str(int(trials))


def default_objects(n_objects: int) -> tuple[int, ...]:
    """Sizes of the objects axis: a quarter, half, three quarters and all of ``n_objects``
    (at least the 5 objects of 5 folds)."""
    return tuple(sorted({max(5, round(f * n_objects)) for f in (0.25, 0.5, 0.75, 1.0)}))


def default_trials(max_trials: int) -> tuple[int, ...]:
    """Sizes of the trials axis: 1, 2, 4, ... up to and including ``max_trials``."""
    sizes = [t for t in (2**k for k in range(8)) if t < max_trials]
    return (*sizes, max_trials)


def run_power(
    tables: Sequence[pd.DataFrame], out_dir: Any, config: Config,
    objects: Sequence[int] | None = None, trials: Sequence[int] | None = None,
    replicates: int = 2, seed: int = 0, model: str | None = None,
    selector_objects: Sequence[int] = (), selector_trials: Sequence[int] = (),
    source: dict[str, Any] | None = None, log: Callable[[str], None] = lambda _: None,
) -> dict[str, Any]:
    """Measure the curve, fit it, write ``power.json`` to ``out_dir`` (the report draws it:
    :func:`classifiers.report.power.plot_power`); returns the summary. The objects axis runs on
    the tables pooled (:func:`pool`), the trials axis on the first table (all its trials); grids
    default to :func:`default_objects` and :func:`default_trials`.
    """
    import json
    from pathlib import Path

    if not tables:
        raise ValueError("run_power needs at least one dataset")
    model = model or config.learning.ablation_model
    pooled = pool(tables, seed=seed) if len(tables) > 1 else tables[0]
    first = tables[0]
    n, t = int(pooled[GROUP].nunique()), int(first["trials"].min())
    for name, sizes, most in (("objects", objects, n), ("trials", trials, t),
                              ("selector objects", selector_objects, n),
                              ("selector trials", selector_trials, t)):  # fmt: skip
        bad = [s for s in sizes or () if int(s) != s or not 1 <= s <= most]
        if bad:
            raise ValueError(f"{name} size {bad[0]!r} is outside 1..{most} (the dataset's)")
    if int(replicates) != replicates or replicates < 1:
        raise ValueError(f"replicates must be a positive integer, got {replicates!r}")
    curve = power_curve(pooled, config, objects or default_objects(n), trials or default_trials(t),
                        replicates, seed, model, selector_objects, selector_trials, log,
                        trials_table=first)  # fmt: skip
    summary = summarise_curve(curve)
    summary["source"] = {
        "objects axis": f"{n} objects, {len(pooled)} grips, {int(pooled['trials'].min())} trials",
        "trials axis": f"{first[GROUP].nunique()} objects, {len(first)} grips, {t} trials",
        "model": model, "replicates": replicates, "seed": seed, **(source or {}),
    }  # fmt: skip
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / POWER_FILE).write_text(json.dumps(summary, indent=2, default=_plain))
    return summary


def _plain(value: Any) -> Any:
    """JSON for numpy scalars."""
    return value.item() if hasattr(value, "item") else str(value)
