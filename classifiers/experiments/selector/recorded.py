"""The objects a retry selector trains on: those whose every trial is recorded by index.

With ``selector.max_attempts > 1`` (the retry task) an episode's attempts replay one trial index
k, so training needs every training object's ``trial_success_0..T-1``. A dataset made before
they were kept (the shipped standard dataset) gets them from its re-simulated shards
(:func:`with_recorded_trials`, the objects done so far); the training objects without them are
refused, or, when asked (``recorded_only``), left out and counted, never replayed as
independent draws.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from grip_env.columns import trial_columns, trial_success_columns
from grip_env.config import Config
from grip_env.dataset.shards import recorded_trial_successes
from grip_env.dataset.split import held_out_objects


@dataclass(frozen=True)
class RecordedTrainingObjects:
    """The training objects of the split whose every trial is recorded (``objects``), of
    ``total`` training objects; ``missing`` lack some trial's outcome."""

    objects: tuple[str, ...]
    total: int
    missing: tuple[str, ...]

    def summary(self) -> str:
        """One line: how many training objects were used, and why not the rest."""
        text = f"trained on {len(self.objects)} of the {self.total} training objects"
        if self.missing:
            text += f" ({len(self.missing)} left out: their trials are not recorded yet)"
        return text


def with_recorded_trials(table: pd.DataFrame, folder: str | Path) -> pd.DataFrame:
    """``table`` with the per-trial columns of the objects ``folder`` holds re-simulated
    (checked against their summaries), every other grip kept with those columns missing (NaN):
    the object-level split, which depends on the whole set of objects, stays the dataset's."""
    from grip_env.dataset.trial_outcomes import with_trial_outcomes

    recorded = with_trial_outcomes(table, folder)
    if recorded is table:  # the table records every trial already
        return table
    count = recorded_trial_successes(recorded.columns)
    merged = table.merge(recorded[["grip_id", *trial_columns(count)]], on="grip_id", how="left",
                         validate="one_to_one")  # fmt: skip
    merged.attrs = table.attrs
    return merged


def retry_training_objects(table: pd.DataFrame, config: Config,
                           recorded_only: bool = False) -> RecordedTrainingObjects | None:
    """The training objects a selector of ``config`` replays: None with one attempt an episode
    (any grip table will do), else those whose every trial is recorded by index.

    Raises:
        ValueError: the retry task on a table that records no trial by index, on training
            objects that lack some trial (unless ``recorded_only``), or on none that has them.
    """
    attempts = config.selector.max_attempts
    if attempts == 1:
        return None
    trials = recorded_trial_successes(table.columns)
    if not trials:
        raise ValueError(f"selector.max_attempts {attempts} (the retry task) replays every "
                         "trial's outcome by index (trial_success_0..T-1), which this dataset "
                         "does not record: give its re-simulated trials (--trials DIR) or "
                         "generate it again; independent draws would overstate a retry")
    ids = table["object_id"].astype(str)
    train, _ = held_out_objects(ids, config.learning)
    complete = table[list(trial_success_columns(trials))].notna().all(axis=1)
    recorded = set(complete.groupby(ids).all().loc[lambda c: c].index)
    objects = tuple(o for o in train if o in recorded)
    missing = tuple(o for o in train if o not in recorded)
    if missing and not recorded_only:
        raise ValueError(f"{len(missing)} of the {len(train)} training objects lack their "
                         f"trials' outcomes (e.g. {', '.join(missing[:3])}): record them, or "
                         f"train on the {len(objects)} that have them (--recorded-only)")
    if not objects:
        raise ValueError(f"none of the {len(train)} training objects has its trials recorded")
    return RecordedTrainingObjects(objects, len(train), missing)
