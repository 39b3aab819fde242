"""Inputs checked before a command writes anything: the dataset a learning command reads.

A command that would fail on its data (missing, unfinished, too few objects for the folds) says
so in one line before it creates ``--out``: bad input writes nothing.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from grip_env.config import Config


def learning_table(data: Path, config: Config) -> pd.DataFrame:
    """The grips of dataset ``data``, checked for grouped cross-validation under ``config``."""
    from classifiers.evaluation.cross_validation import check_dataset
    from grip_env.columns import FEATURES
    from grip_env.dataset import load

    if not Path(data).exists():
        raise ValueError(f"dataset not found: {data}")
    table = load(data)
    check_dataset(table, FEATURES, config.learning.folds)
    return table
