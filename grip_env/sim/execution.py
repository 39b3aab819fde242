"""``run_trials``: simulated outcome labels (trials, successes) for a table of grips."""

from __future__ import annotations

import zlib

import numpy as np
import pandas as pd

from grip_env.config import Config
from grip_env.objects import PlanarObject
from grip_env.sim.trial import TrialScene, grip_plans
from grip_env.sim.uncertainty import sample_noise, trial_rng


def grip_keys(grips: pd.DataFrame) -> list[int]:
    """A stable integer per grip for seeding: from ``grip_id`` when present, else the index."""
    labels = grips["grip_id"] if "grip_id" in grips.columns else grips.index.to_series()
    return [_stable_int(label) for label in labels]


def _stable_int(label: object) -> int:
    if isinstance(label, (int, np.integer)) and label >= 0:
        return int(label)
    return zlib.crc32(str(label).encode())


def run_trials(
    obj: PlanarObject,
    grips: pd.DataFrame,
    config: Config | None = None,
    trials: int = 5,
    seed: int = 0,
) -> pd.DataFrame:
    """Execute every grip ``trials`` times in PyBullet under sampled execution noise.

    The noise of trial k of a grip is drawn from ``SeedSequence([seed, key, k])`` where ``key``
    comes from the grip's ``grip_id`` (or its index label), so results do not depend on how the
    grips are chunked or ordered. Each call owns one headless PyBullet client.

    Returns:
        DataFrame indexed like ``grips`` with integer columns ``trials`` and ``successes``.
    """
    if not isinstance(obj, PlanarObject):
        raise ValueError(f"obj must be a PlanarObject, got {type(obj).__name__}")
    if not isinstance(grips, pd.DataFrame):
        raise ValueError(f"grips must be a pandas DataFrame, got {type(grips).__name__}")
    if isinstance(trials, bool) or not isinstance(trials, (int, np.integer)) or trials < 1:
        raise ValueError(f"trials must be a positive integer, got {trials!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    config = config if config is not None else Config()
    plans = grip_plans(grips)
    successes = np.zeros(len(plans), dtype=np.int64)
    if plans:
        with TrialScene(obj, config) as scene:
            for j, (plan, key) in enumerate(zip(plans, grip_keys(grips), strict=True)):
                for k in range(trials):
                    noise = sample_noise(trial_rng(seed, key, k), config)
                    successes[j] += scene.run(plan, noise).success
    return pd.DataFrame(
        {"trials": np.full(len(plans), int(trials), dtype=np.int64), "successes": successes},
        index=grips.index,
    )
