"""``run_trials`` and ``run_trial_outcomes``: simulated outcome labels for a table of grips."""

from __future__ import annotations

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from grip_env.config import Config
from grip_env.objects import PlanarObject
from grip_env.portable_process import portable
from grip_env.sim.trial import TrialScene, grip_plans
from grip_env.sim.uncertainty import stable_key, trial_noises

OUTCOME_COLUMNS = ("grip", "trial", "robustness", "success", "held", "friction", "mass_kg",
                   "drift_mm", "rotation_deg", "steps")


def grip_keys(grips: pd.DataFrame) -> list[int]:
    """A stable integer per grip for seeding: from ``grip_id`` when present, else the index."""
    labels = grips["grip_id"] if "grip_id" in grips.columns else grips.index.to_series()
    return [stable_key(label) for label in labels]


def object_key(obj: PlanarObject, grips: pd.DataFrame) -> int:
    """A stable integer for the object's common draws: from the grips' ``object_id`` when they
    carry one, else the object's name (never its position in a run)."""
    if "object_id" in grips.columns and len(grips):
        ids = grips["object_id"].astype(str).unique()
        if len(ids) > 1:
            raise ValueError(f"grips of one object expected, got object_id {sorted(ids)[:3]}")
        return stable_key(ids[0])
    return stable_key(obj.name)


def _count(name: str, value: object, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        kind = "a positive" if minimum > 0 else "a non-negative"
        raise ValueError(f"{name} must be {kind} integer, got {value!r}")
    return int(value)


@portable
def run_trial_outcomes(
    obj: PlanarObject,
    grips: pd.DataFrame,
    config: Config | None = None,
    trials: int | None = None,
    seed: int = 0,
    trial_offset: int = 0,
) -> pd.DataFrame:
    """Execute every grip ``trials`` times (``dataset.trials`` when None) in PyBullet; one row
    per (grip, trial).

    Trial k (``trial_offset + k``) of every grip of the object meets one draw, from
    ``SeedSequence([seed, object key, k])`` with the key from the grips' ``object_id`` (else the
    object's name): common random numbers (``uncertainty.draws: per_grip`` keys it by the grip's
    ``grip_id`` instead). Every trial runs in a world built fresh for it. So an outcome depends on
    (seed, object, grip, trial) only: never on the order, chunking or number of workers the grips
    are run in, nor on which other grips or trials are run (tested on the graded outcome, the
    step count, drift and rotation). Two disjoint seed sets are ``trial_offset=0`` and
    ``trial_offset=trials``.

    Returns:
        Columns ``grip`` (the grips' index label), ``trial``, ``robustness`` (g: the highest
        disturbance level held; 0 when the object was not held after the lift), ``success``
        (held the reference level ``sim.reference_level_g``), ``held``, ``friction``,
        ``mass_kg``, ``drift_mm``, ``rotation_deg``, ``steps``.

    Raises:
        ValueError: bad arguments, or a grip the hand cannot reach (never clipped).
    """
    if not isinstance(obj, PlanarObject):
        raise ValueError(f"obj must be a PlanarObject, got {type(obj).__name__}")
    if not isinstance(grips, pd.DataFrame):
        raise ValueError(f"grips must be a pandas DataFrame, got {type(grips).__name__}")
    config = config if config is not None else Config()
    trials = _count("trials", config.dataset.trials if trials is None else trials, 1)
    seed = _count("seed", seed, 0)
    trial_offset = _count("trial_offset", trial_offset, 0)
    plans = grip_plans(grips)
    numbers = range(trial_offset, trial_offset + trials)
    noises = trial_noises(config, seed, object_key(obj, grips), grip_keys(grips), numbers)
    rows: list[tuple] = []
    if plans:
        with TrialScene(obj, config) as scene:
            for label, plan, draws in zip(grips.index, plans, noises, strict=True):
                for k, noise in zip(numbers, draws, strict=True):
                    r = scene.run(plan, noise)
                    rows.append((label, k, r.robustness_g, r.success, r.held, noise.friction,
                                 scene.mass_kg * noise.mass_scale, r.drift_mm, r.rotation_deg,
                                 r.steps))
    return pd.DataFrame(rows, columns=list(OUTCOME_COLUMNS))


@portable
def run_trials(
    obj: PlanarObject,
    grips: pd.DataFrame,
    config: Config | None = None,
    trials: int | None = None,
    seed: int = 0,
) -> pd.DataFrame:
    """Per-grip labels from ``run_trial_outcomes`` (``dataset.trials`` trials when None):
    trial k of every grip of an object shares one draw, keyed by (seed, object_id, k), and an
    outcome depends on (seed, object, grip, trial) only, never on order, chunking, workers,
    machine or the order of imports (:mod:`grip_env.portable_process`).

    Returns:
        DataFrame indexed like ``grips`` with ``trials``, ``successes`` (trials that held the
        reference level), ``robustness_mean`` and ``robustness_std`` (g, over the trials;
        the std is the population std, 0 for one trial).
    """
    config = config if config is not None else Config()
    trials = config.dataset.trials if trials is None else trials
    outcomes = run_trial_outcomes(obj, grips, config, trials, seed)
    n, trials = len(grips), int(trials)
    robust = outcomes["robustness"].to_numpy(float).reshape(n, trials)
    success = outcomes["success"].to_numpy(bool).reshape(n, trials)
    return pd.DataFrame(trial_summary(robust, success), index=grips.index)


def trial_summary(
    robustness: NDArray[np.float64], success: NDArray[np.bool_]
) -> dict[str, NDArray]:
    """Per-grip ``trials``, ``successes``, ``robustness_mean`` and ``robustness_std`` (population)
    from per-trial arrays of shape (grips, trials).

    The sums run over each grip's levels in ascending order, one column at a time, so the bits
    depend on the set of trial outcomes only: not on the trials' order, nor on how many grips
    share the array (a numpy reduction along a row may pair its terms differently). That is what
    lets trials be added to a dataset (:mod:`grip_env.dataset.trial_extension`) with the bits a
    fresh run would give."""
    n, trials = robustness.shape
    levels = np.sort(robustness, axis=1)
    total = np.zeros(n)
    for column in levels.T:
        total = total + column
    mean = total / trials
    squares = np.zeros(n)
    for column in levels.T:
        squares = squares + (column - mean) ** 2
    return {"trials": np.full(n, trials, dtype=np.int64),
            "successes": success.sum(axis=1).astype(np.int64),
            "robustness_mean": mean,
            "robustness_std": np.sqrt(squares / trials)}
