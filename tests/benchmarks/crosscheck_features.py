"""Which grips do the engines order differently? (run by hand)

    python -m tests.benchmarks.crosscheck_features --parts R.crosscheck

Reads a cross-check's kept outcomes (``grip-env validate standard --crosscheck N --report R.json``
keeps them in ``R.crosscheck/``). Within each object of at least ``MIN_GRIPS`` grips, every grip's
rank by mean robustness in PyBullet minus its rank in MuJoCo (each scaled to 0..1), and its
features standardised within the object; then, by family, the Spearman of each feature with that
difference (positive: PyBullet ranks the grips with more of it higher than MuJoCo does), the
features ordered by its size.
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

import argparse
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import rankdata, spearmanr

from grip_env.features import FEATURE_NAMES
from tests.benchmarks.crosscheck_contact_loads import kept_runs

SAMPLE = 80
MIN_GRIPS = 8
#: Besides the twelve measures: the indexes, the hand's configuration and the regions' curvature.
OTHERS = ("Q_G", "Q_C", "two_finger", "spread", "e1", "e2", "e3", "rho1", "rho2", "rho3")


def grip_rows(parts: Path) -> pd.DataFrame:
    """One row per grip: family, the rank difference, the features standardised in the object."""
    from grip_env.dataset.crosscheck import _means
    from grip_env.objects.family import object_family

    frames = []
    for check, runs in kept_runs(parts, SAMPLE, 0):
        grips = check.recorded.reset_index(drop=True)
        if len(grips) < MIN_GRIPS:
            continue
        draws = runs.draws
        scale = len(grips) - 1
        difference = (rankdata(_means(draws["pybullet"])) - rankdata(_means(draws["mujoco"])))
        features = grips[[*FEATURE_NAMES, *OTHERS]].astype(float)
        spread = features.std().replace(0.0, np.nan)
        frames.append(((features - features.mean()) / spread).assign(
            family=object_family(check.task.obj), object_id=check.task.object_id,
            difference=difference / scale))
    return pd.concat(frames, ignore_index=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--parts", type=Path, required=True)
    parser.add_argument("--top", type=int, default=6)
    args = parser.parse_args()
    table = grip_rows(args.parts)
    for family, rows in table.groupby("family"):
        found = {name: spearmanr(rows[name], rows.difference, nan_policy="omit").statistic
                 for name in (*FEATURE_NAMES, *OTHERS)}
        ordered = sorted(found.items(), key=lambda item: -abs(item[1]))[: args.top]
        listed = ", ".join(f"{name} {value:+.2f}" for name, value in ordered)
        print(f"| {family} | {rows.object_id.nunique()} | {len(rows)} | {listed} |")


if __name__ == "__main__":
    main()
