"""``add_trials``: a dataset at more trials a grip from one at fewer, running only the new trials.

Trial k of every grip of an object draws from (seed, object, k) whatever the trial count, and
the kept grips do not depend on it, so a dataset at T trials holds the first T0 trials of the
same run at T > T0. Its grips are planned again (and must equal the recorded ones, bit for bit),
trials T0..T-1 are simulated, and the recorded trials are recovered from the labels: every trial's
robustness is a ramp level (or 0), and the levels whose mean, spread and successes are the
recorded ones are unique for almost every grip. A grip whose levels are not unique has all its
trials simulated. The sums of :func:`~grip_env.sim.execution.trial_summary` depend on the set of
levels only, so the result has the bits a fresh ``generate`` at T trials gives; ``grip-env
validate --resimulate`` checks that on any sample. A source that records every trial's outcome
(:func:`~grip_env.columns.trial_columns`) gives them in order, and the result records all T;
recovered levels have no order, so from an older source the result records none (re-simulate
them with :mod:`grip_env.dataset.trial_outcomes`).

    python -m grip_env.dataset.trial_extension SOURCE --config RECIPE --out DIR [--workers N]

The output is an ordinary resumable dataset (interrupt it and run again to finish), with the
recipe's identity: ``grip-env generate`` with the same recipe sees it as its own run.
"""

from __future__ import annotations

import argparse
import itertools
from functools import lru_cache, partial
from pathlib import Path

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from grip_env.columns import trial_robustness_columns
from grip_env.config import Config, load_config
from grip_env.dataset.catalog import ObjectsSpec
from grip_env.dataset.generation import generate
from grip_env.dataset.jobs import ObjectTask, kept_grips, with_outcomes
from grip_env.dataset.loading import load
from grip_env.dataset.manifest import (
    earlier_runs,
    read_manifest,
    run_identity,
    without_learning,
    write_manifest,
)
from grip_env.dataset.resimulation import same_candidates
from grip_env.dataset.shards import recorded_trials
from grip_env.label_model import label_model_for
from grip_env.sim import run_trial_outcomes
from grip_env.sim.disturbance import ramp_levels, reached
from grip_env.sim.execution import trial_summary

#: Recorded and recovered mean and spread agree within this (g): the recorded ones were summed
#: in another order, a few units in the last place apart.
LEVEL_TOLERANCE_G = 1e-9


def add_trials(
    source: str | Path, config: Config, out_dir: str | Path, objects: ObjectsSpec = None,
    workers: int | None = None, progress: bool = True,
) -> Path:
    """Make ``out_dir`` the dataset ``config`` (and ``objects``, as :func:`generate` takes them)
    describe, from ``source``, the same run at fewer trials a grip (see the module docstring).
    Resumable; returns ``out_dir``.

    Raises:
        ValueError: ``source`` is another run (config, seed, label model), or has as many trials.
    """
    source = Path(source)
    recorded = read_manifest(source)
    earlier = int(recorded["trials"])
    _check_same_run(recorded, config, earlier)
    job = partial(extended_object, source=str(source), earlier=earlier)
    directory = generate(config, out_dir, objects, workers=workers, progress=progress, job=job)
    manifest = read_manifest(directory)
    manifest["trials_added_to"] = [*earlier_runs(recorded), {
        "git_commit": recorded.get("git_commit"), "trials": earlier,
        "sessions": recorded.get("sessions", [])}]  # what each step cost
    write_manifest(directory, manifest)
    return directory


def _check_same_run(recorded: dict, config: Config, earlier: int) -> None:
    expected = label_model_for(config.sim.engine)
    if recorded.get("label_model") != expected:
        raise ValueError(f"the source's label model {recorded.get('label_model')!r} is not the "
                         f"code's {expected!r}: its trials are not this simulator's")
    if config.dataset.trials <= earlier:
        raise ValueError(f"trials must exceed the source's {earlier}, got {config.dataset.trials}")
    wanted = _settings(run_identity(config, []))
    source = _settings(recorded["identity"])
    changed = sorted(k for k in wanted.keys() | source.keys() if wanted.get(k) != source.get(k))
    if changed:
        raise ValueError(f"the source was made with another config (sections {changed} differ)")


def _settings(identity: dict) -> dict:
    """A run identity's config sections, the trial count aside."""
    settings = without_learning(identity)["config"]
    dataset = {k: v for k, v in settings["dataset"].items() if k != "trials"}
    return {**settings, "dataset": dataset}


def extended_object(task: ObjectTask, source: str, earlier: int) -> pd.DataFrame:
    """The job: the object's grips planned again, their recorded trials recovered, the rest run."""
    config = task.config
    kept = kept_grips(task)
    rows = _source_rows(source, task.object_id)
    if not same_candidates(kept, rows):
        raise ValueError(f"{task.object_id}: the grips planned again differ from {source}'s")
    robust = np.empty((len(kept), config.dataset.trials))
    by_index = recorded_trials(rows.columns) == earlier > 0
    if by_index:  # the source kept every trial's outcome: take them, in order
        robust[:, :earlier] = rows[list(trial_robustness_columns(earlier))].to_numpy(float)
    else:
        robust[:, :earlier] = recorded_levels(rows, earlier, config)
    planned = kept.assign(object_id=task.object_id)  # the common draws' key, as generate runs
    robust[:, earlier:] = _levels(task, planned, earlier, config.dataset.trials - earlier)
    unknown = np.isnan(robust[:, :earlier]).any(axis=1)
    if unknown.any():
        robust[unknown, :earlier] = _levels(task, planned[unknown], 0, earlier)
    success = reaches_reference(robust, config)
    per_trial = (robust, success) if by_index else None  # recovered levels have no order
    return with_outcomes(kept, trial_summary(robust, success), task.object_id, per_trial)


def _levels(task: ObjectTask, grips: pd.DataFrame, first: int, count: int) -> NDArray:
    outcome = run_trial_outcomes(task.obj, grips, task.config, count, task.config.dataset.seed,
                                 trial_offset=first)
    return outcome["robustness"].to_numpy(float).reshape(len(grips), count)


def reaches_reference(robust: NDArray, config: Config) -> NDArray[np.bool_]:
    """Per-trial success from the levels held (a held level of 0 never reaches the reference)."""
    return reached(robust, config.sim.reference_level_g)


def recorded_levels(rows: pd.DataFrame, trials: int, config: Config) -> NDArray:
    """Each recorded grip's ``trials`` levels, ascending (NaN where not unique): the multisets of
    ramp levels whose mean, spread and successes are the recorded ones."""
    sets = _level_sets(tuple(ramp_levels(config.sim)), trials)
    summary = trial_summary(sets, reaches_reference(sets, config))
    mean = rows["robustness_mean"].to_numpy(float)[:, None]
    std = rows["robustness_std"].to_numpy(float)[:, None]
    match = ((np.abs(summary["robustness_mean"][None, :] - mean) <= LEVEL_TOLERANCE_G)
             & (np.abs(summary["robustness_std"][None, :] - std) <= LEVEL_TOLERANCE_G)
             & (summary["successes"][None, :] == rows["successes"].to_numpy()[:, None]))
    levels = np.full((len(rows), trials), np.nan)
    unique = match.sum(axis=1) == 1
    levels[unique] = sets[match[unique].argmax(axis=1)]
    return levels


@lru_cache(maxsize=4)
def _level_sets(levels: tuple[float, ...], trials: int) -> NDArray:
    """Every multiset of ``trials`` values from 0 and the ramp levels, ascending, one a row."""
    values = (0.0, *levels)
    return np.array(list(itertools.combinations_with_replacement(values, trials)), dtype=float)


@lru_cache(maxsize=1)
def _source_table(source: str) -> pd.DataFrame:
    return load(source)  # once a worker process


def _source_rows(source: str, object_id: str) -> pd.DataFrame:
    table = _source_table(source)
    return table[table["object_id"] == object_id].reset_index(drop=True)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m grip_env.dataset.trial_extension",
                                     description=__doc__.splitlines()[0])  # type: ignore[union-attr]
    parser.add_argument("source", type=Path, help="the dataset at fewer trials")
    parser.add_argument("--config", type=Path, required=True, help="the recipe at more trials")
    parser.add_argument("--out", type=Path, required=True, help="the dataset to make or finish")
    parser.add_argument("--workers", type=int, default=None)
    args = parser.parse_args(argv)
    try:
        directory = add_trials(args.source, load_config(args.config), args.out,
                               workers=args.workers)
    except ValueError as exc:
        parser.exit(2, f"error: {exc}\n")
    print(f"{directory}: {read_manifest(directory)['trials']} trials a grip")


if __name__ == "__main__":
    main()
