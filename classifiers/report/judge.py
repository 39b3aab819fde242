"""When an interval may carry a verdict.

A verdict ("met", "beats", a bold winner, "excludes zero") needs an interval that says
something: one that exists, has a width (a zero width comes from constant scores, or from too
few objects for a resample to differ), does not span every value the metric can take, and rests
on enough objects. :func:`unjudgeable` names what is missing; the report's sections ask it
before they declare anything, and print the numbers either way.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

#: Below this many objects a result is shown but nothing is declared from it (the leaderboard's
#: own caution uses the same count).
FEW_OBJECTS = 10
#: The range of values each metric can take: an interval covering it says nothing.
SPANS: dict[str, tuple[float, float]] = {
    "roc_auc": (0.0, 1.0), "balanced_accuracy": (0.0, 1.0), "accuracy": (0.0, 1.0),
    "top1_success": (0.0, 1.0), "success_rate": (0.0, 1.0), "spearman": (-1.0, 1.0),
    "spearman_object": (-1.0, 1.0),
}  # fmt: skip
_TOLERANCE = 1e-9


def unjudgeable(value: dict[str, Any] | None, objects: int | None = None,
                span: Sequence[float] | None = None) -> str | None:
    """Why ``value`` (a ``{"mean", "ci"}`` block) cannot carry a verdict, or None when it can.

    ``objects``: how many objects the interval rests on (None: not known, not checked);
    ``span``: the lowest and highest value the quantity can take (None: unbounded).
    """
    ci = (value or {}).get("ci")
    if (value or {}).get("mean") is None or not ci or ci[0] is None or ci[1] is None:
        return "there is no interval"
    low, high = float(ci[0]), float(ci[1])
    if high - low <= _TOLERANCE * max(1.0, abs(low), abs(high)):
        return ("its interval has zero width (constant scores, or too few objects for a "
                "resample to differ)")
    if span is not None and low <= span[0] + _TOLERANCE and high >= span[1] - _TOLERANCE:
        return f"its interval spans every possible value [{span[0]:g}, {span[1]:g}]"
    if objects is not None and objects < FEW_OBJECTS:
        return f"it rests on {objects} objects (fewer than {FEW_OBJECTS})"
    return None


def difference_verdict(value: dict[str, Any], objects: int | None = None,
                       span: Sequence[float] | None = None) -> str:
    """A paired difference in words: whether its interval excludes zero, or why it cannot say."""
    problem = unjudgeable(value, objects, span)
    if problem:
        return f"no verdict: {problem}"
    low, high = value["ci"]
    if low > 0 or high < 0:
        return "the interval excludes zero"
    return "the interval includes zero: no significant effect on this dataset"


def leaderboard_caution(board: dict[str, Any]) -> str | None:
    """Why the leaderboard declares no method better or worse than best-Q_C (too few held-out
    objects ranked), or None when it may."""
    ranked = len(board.get("objects", []))
    if ranked >= FEW_OBJECTS:
        return None
    return (f"No method is declared to beat or to lose to best-Q_C: only {ranked} held-out "
            f"object(s) could be ranked (fewer than {FEW_OBJECTS}), so the intervals say "
            "nothing either way.")


def small_data_caution(objects: int) -> str | None:
    """The console's one-line caution when a run rests on fewer than :data:`FEW_OBJECTS`
    objects (the rule the report's toy-study banner and the leaderboard apply), else None."""
    if objects >= FEW_OBJECTS:
        return None
    return (f"caution: only {objects} object(s) (fewer than {FEW_OBJECTS}): too few to judge; "
            f"read these numbers and their intervals as indicative only")


def constant_scores(blocks: dict[str, dict[str, Any] | None], chance: float = 0.5) -> list[str]:
    """The names whose ROC-AUC block is exactly ``chance`` with a zero-width interval: every
    fold scored every grip alike (a learner that predicts a constant)."""
    found = []
    for name, block in blocks.items():
        problem = unjudgeable(block)
        if problem and "zero width" in problem and abs(float(block["mean"]) - chance) < _TOLERANCE:
            found.append(name)
    return found
