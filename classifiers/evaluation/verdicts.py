"""How a paired difference stands against zero: the one rule behind the leaderboard's verdicts
and the study's answers."""

from __future__ import annotations

from collections.abc import Sequence

#: How a quantity stands against a reference, from the 95 % interval of their paired difference
#: (quantity minus reference): above zero, below zero, or containing it. The leaderboard's
#: verdicts and the study's answers both read it.
RELATIONS = ("beats", "is worse than", "is not distinguishable from")


def relation(ci: Sequence[float]) -> str:
    """``beats`` when the interval ``(low, high)`` of a paired difference lies above zero,
    ``is worse than`` when it lies below, ``is not distinguishable from`` otherwise."""
    low, high = float(ci[0]), float(ci[1])
    beats, worse, same = RELATIONS
    return beats if low > 0 else worse if high < 0 else same
