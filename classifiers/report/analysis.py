"""The paper's analyses on candidate tables: feature correlations, grasp versus configuration ranks.

Section VI-B correlates every feature with Q_C; section VII-A compares the rank of each grasp (by
Q_G) with the ranks of the configurations it generates (by Q_C).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.stats import spearmanr

from grip_env.columns import FEATURES, HAND_FEATURES, SHARED_FEATURES

CORRELATION_COLUMNS = (*HAND_FEATURES, *SHARED_FEATURES, "Q_C")


def feature_correlations(table: pd.DataFrame, method: str = "spearman") -> pd.DataFrame:
    """Correlations among C1..C6, S1..S4 and Q_C (the paper's correlation table).

    Spearman by default: the paper's question is about rank order, and capped features make
    Pearson follow a few outliers; ``method="pearson"`` gives the paper's own statistic.
    """
    _require(table, CORRELATION_COLUMNS)
    correlations = table.loc[:, list(CORRELATION_COLUMNS)].corr(method=method)
    return correlations.rename_axis("feature")


def constant_columns(table: pd.DataFrame, columns: tuple[str, ...]) -> dict[str, float]:
    """The columns of ``columns`` that take one value over the whole table, with that value
    (a correlation with them is undefined)."""
    _require(table, columns)
    found = {}
    for name in columns:
        values = table[name].dropna()
        if len(values) and values.nunique() == 1:
            found[name] = float(values.iloc[0])
    return found


@dataclass(frozen=True)
class RankComparison:
    """Grasp rank (by Q_G) against configuration ranks (by Q_C) for one object."""

    object_id: str
    table: pd.DataFrame  # one row per grasp: grasp_rank, Q_G, config ranks (best first), mean rank
    best_config_correlation: float  # Spearman: grasp rank vs its best configuration's rank
    mean_config_correlation: float  # Spearman: grasp rank vs the mean rank of its configurations
    best_config_grasp_rank: int  # rank of the grasp that generated the best configuration
    best_grasp_best_config_rank: int  # rank of the best configuration of the best grasp


def compare_ranks(candidates: pd.DataFrame) -> RankComparison:
    """Rank the grasps of one object's candidate table by Q_G and its configurations by Q_C."""
    _require(candidates, ("object_id", "grasp_id", "Q_G", "Q_C"))
    objects = candidates["object_id"].unique()
    if len(objects) != 1:
        raise ValueError(f"compare_ranks needs the candidates of one object, got {len(objects)}")
    if candidates.empty:
        raise ValueError("compare_ranks needs at least one candidate")
    config_rank = candidates["Q_C"].rank(method="first").astype(int)
    ranked = candidates.assign(config_rank=config_rank)
    per_grasp = ranked.groupby("grasp_id").agg(
        Q_G=("Q_G", "first"),
        best_config_rank=("config_rank", "min"),
        mean_config_rank=("config_rank", "mean"),
        config_ranks=("config_rank", lambda r: tuple(sorted(r))),
    )
    per_grasp["grasp_rank"] = per_grasp["Q_G"].rank(method="first").astype(int)
    per_grasp = per_grasp.sort_values("grasp_rank").reset_index()
    best_config_grasp = per_grasp.loc[per_grasp["best_config_rank"].idxmin(), "grasp_rank"]
    return RankComparison(
        object_id=str(objects[0]),
        table=per_grasp,
        best_config_correlation=_spearman(per_grasp["grasp_rank"], per_grasp["best_config_rank"]),
        mean_config_correlation=_spearman(per_grasp["grasp_rank"], per_grasp["mean_config_rank"]),
        best_config_grasp_rank=int(best_config_grasp),
        best_grasp_best_config_rank=int(per_grasp.loc[0, "best_config_rank"]),
    )


def rank_summary(comparisons: list[RankComparison]) -> pd.DataFrame:
    """One row per object: the two rank correlations and where the best configuration comes from."""
    return pd.DataFrame(
        {
            "object_id": [c.object_id for c in comparisons],
            "grasps": [len(c.table) for c in comparisons],
            "configurations": [int(c.table["config_ranks"].map(len).sum()) for c in comparisons],
            "rho_best_config": [c.best_config_correlation for c in comparisons],
            "rho_mean_config": [c.mean_config_correlation for c in comparisons],
            "best_config_from_top3_grasp": [c.best_config_grasp_rank <= 3 for c in comparisons],
            "best_grasp_config_in_top6": [c.best_grasp_best_config_rank <= 6 for c in comparisons],
        }
    )


def success_by_decile(
    table: pd.DataFrame, column: str = "Q_C", bins: int = 10, resamples: int = 1000,
    seed: int = 0,
) -> pd.DataFrame:
    """Mean simulated success rate per quantile bin of ``column`` (bin 1 = lowest, i.e. best).

    ``ci_low``/``ci_high``: 95% percentile interval of each bin's mean from a bootstrap over
    objects (grips of one object are not independent); over grips when there is no
    ``object_id``.
    """
    _require(table, (column, "success_rate"))
    ranks = table[column].rank(method="first")
    decile = pd.qcut(ranks, q=min(bins, len(table)), labels=False) + 1
    grouped = table.assign(bin=decile).groupby("bin")
    frame = pd.DataFrame(
        {
            f"{column}_min": grouped[column].min(),
            f"{column}_max": grouped[column].max(),
            "grips": grouped.size(),
            "success_rate": grouped["success_rate"].mean(),
        }
    )
    groups = table["object_id"] if "object_id" in table.columns else pd.Series(range(len(table)))
    low, high = cluster_bootstrap_means(table["success_rate"].to_numpy(float),
                                        decile.to_numpy() - 1, groups.to_numpy(), resamples,
                                        seed)  # fmt: skip
    frame["ci_low"], frame["ci_high"] = low, high
    return frame


def cluster_bootstrap_means(
    values: np.ndarray, bins: np.ndarray, groups: np.ndarray, resamples: int = 1000,
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """Per-bin 95% percentile interval of the mean, resampling whole groups with replacement."""
    _, group_of = np.unique(groups.astype(str), return_inverse=True)
    n_groups, n_bins = int(group_of.max()) + 1, int(bins.max()) + 1
    sums, counts = np.zeros((n_groups, n_bins)), np.zeros((n_groups, n_bins))
    np.add.at(sums, (group_of, bins), values)
    np.add.at(counts, (group_of, bins), 1.0)
    rng = np.random.default_rng(seed)
    weights = rng.multinomial(n_groups, np.full(n_groups, 1.0 / n_groups), resamples)
    with np.errstate(invalid="ignore", divide="ignore"):
        means = (weights @ sums) / (weights @ counts)
    return np.nanpercentile(means, 2.5, axis=0), np.nanpercentile(means, 97.5, axis=0)


def feature_summary(table: pd.DataFrame) -> pd.DataFrame:
    """Median and quartiles of each feature, split by the simulated outcome."""
    _require(table, (*FEATURES, "success"))
    rows = {}
    for outcome, group in table.groupby("success"):
        label = "held" if outcome else "slipped"
        quantiles = group.loc[:, list(FEATURES)].quantile([0.25, 0.5, 0.75])
        for q, name in zip((0.25, 0.5, 0.75), ("q25", "median", "q75"), strict=True):
            rows[(label, name)] = quantiles.loc[q]
    return pd.DataFrame(rows).T


def _spearman(a: pd.Series, b: pd.Series) -> float:
    if len(a) < 3 or a.nunique() < 2 or b.nunique() < 2:
        return float("nan")
    return float(spearmanr(a, b).statistic)


def _require(table: pd.DataFrame, columns: tuple[str, ...]) -> None:
    missing = [c for c in columns if c not in table.columns]
    if missing:
        raise ValueError(f"table lacks column(s) {', '.join(missing)}")
