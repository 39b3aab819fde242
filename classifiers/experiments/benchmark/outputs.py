"""What a method returns for one object, read as one score per candidate row.

A method sees one object's candidate table (rows ``0..n-1`` in slot order) and returns either

- one row index (an integer: the choice), scored 1 for that row and 0 for the rest;
- a score per row (higher = pick first): a sequence or array in row order, or a
  :class:`pandas.Series` whose index is the table's index, aligned on it (so
  ``-table.sort_values("Q_G")["Q_G"]`` scores each row by its own Q_G, whatever the order).

Anything else is refused with a ``ValueError`` naming what came back: ``None``, a string (even
``"0"``), a non-integer choice, the wrong number of scores, a Series on another index, NaN.
"""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np
import pandas as pd


def choice_scores(choice: Any, count: int, where: str) -> np.ndarray:
    """``choice`` (one object's output, ``count`` candidate rows) as ``count`` finite scores."""
    if choice is None:
        raise ValueError(f"{where}: returned None; return one score per candidate row or one "
                         f"row index")  # fmt: skip
    if isinstance(choice, pd.Series):
        choice = _aligned(choice, count, where)
    _check_numbers(choice, where)
    if np.ndim(choice) == 0:
        return _one_hot(choice, count, where)
    try:
        scores = np.asarray(choice, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"{where}: scores must be numbers, got {type(choice).__name__}") from None
    if np.ndim(choice) != 1 or scores.size != count:
        raise ValueError(f"{where}: {scores.size} scores (shape {np.shape(choice)}) for "
                         f"{count} candidates")  # fmt: skip
    if not np.all(np.isfinite(scores)):
        raise ValueError(f"{where}: scores hold NaN or infinite values")
    return scores


def _aligned(scores: pd.Series, count: int, where: str) -> np.ndarray:
    """A Series' values in the order of the candidate rows ``0..count-1`` (its index must be
    exactly those rows, in any order)."""
    rows = pd.RangeIndex(count)
    index = scores.index
    if index.has_duplicates or len(index) != count or not index.isin(rows).all():
        shown = list(index[:5]) + (["..."] if len(index) > 5 else [])
        raise ValueError(f"{where}: returned a pandas Series whose index {shown} is not the "
                         f"candidate table's index (its rows 0..{count - 1}, each once); return "
                         f"the scores in row order, or a Series on the table's index")  # fmt: skip
    return scores.reindex(rows).to_numpy()


def _check_numbers(choice: Any, where: str) -> None:
    """Refuse text: numpy would read ``"0"`` as the number 0."""
    values = np.asarray(choice, dtype=object).reshape(-1)
    text = [v for v in values if isinstance(v, str | bytes)]
    if text:
        raise ValueError(f"{where}: a method returns numbers (scores or one row index), got the "
                         f"text {text[0]!r}")  # fmt: skip


def _one_hot(choice: Any, count: int, where: str) -> np.ndarray:
    if isinstance(choice, np.ndarray):
        choice = choice.item()
    if (isinstance(choice, bool | np.bool_) or not isinstance(choice, numbers.Real)
            or not float(choice).is_integer()):  # fmt: skip
        raise ValueError(f"{where}: a choice must be an integer index, got {choice!r}")
    index = int(choice)
    if not 0 <= index < count:
        raise ValueError(f"{where}: invalid index {index} for {count} candidates")
    scores = np.zeros(count)
    scores[index] = 1.0
    return scores
