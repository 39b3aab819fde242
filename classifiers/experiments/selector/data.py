"""The grip table the selector learns from: a dataset folder, a bare Parquet table or a
DataFrame, with simulated outcomes."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd

from grip_env.dataset import load
from grip_env.datasets import resolve_data

_OUTCOME_COLUMNS = ("success_rate", "successes")


def check_grip_table(data: Any) -> pd.DataFrame:
    """Load a dataset (directory or ``.parquet`` table) or take a DataFrame with outcomes."""
    if isinstance(data, str | Path):
        data = _read_table(Path(data))
    if not isinstance(data, pd.DataFrame):
        raise ValueError(f"data must be a dataset path or DataFrame, got {type(data).__name__}")
    if not any(column in data.columns for column in _OUTCOME_COLUMNS):
        raise ValueError(
            "dataset has no outcome columns ('success_rate' or 'trials'/'successes'): "
            "the selector learns from simulated outcomes (run grip-env generate first)"
        )
    if data.empty:
        raise ValueError("dataset holds no grip")
    return data


def _read_table(path: Path) -> pd.DataFrame:
    """A dataset directory (``grip_env.dataset.load``) or a bare Parquet grip table."""
    path = resolve_data(path)
    if not path.exists():
        raise ValueError(f"dataset not found: {path}")
    if path.is_file() and path.suffix == ".parquet":
        return pd.read_parquet(path)
    return load(path)
