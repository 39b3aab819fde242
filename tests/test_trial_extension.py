"""``add_trials``: a dataset at more trials a grip, from one at fewer, is the dataset a fresh run at
that count makes, bit for bit; and the per-grip summary does not depend on the trials' order."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from grip_env.config import Config
from grip_env.dataset import generate, load
from grip_env.dataset.manifest import earlier_runs, read_manifest
from grip_env.dataset.trial_extension import (
    add_trials,
    main,
    reaches_reference,
    recorded_levels,
)
from grip_env.objects import load_object_set
from grip_env.sim.disturbance import ramp_levels
from grip_env.sim.execution import trial_summary

#: Two named objects, few grips: the real job (perception on the render included).
ONE = Config().override(dataset={"trials": 1, "max_grips_per_object": 4, "workers": 1})
TWO = ONE.override(dataset={"trials": 2})
LEVELS = np.concatenate([[0.0], ramp_levels(Config().sim)])


def _objects():  # type: ignore[no-untyped-def]
    return [o for o in load_object_set("default") if o.name in ("pentagon", "trapezoid")]


@pytest.fixture(scope="module")
def at_one(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return generate(ONE, tmp_path_factory.mktemp("one") / "data", objects=_objects(),
                    progress=False)


@pytest.mark.slow
def test_adding_a_trial_gives_the_fresh_runs_dataset_bit_for_bit(at_one, tmp_path):
    fresh = load(generate(TWO, tmp_path / "fresh", objects=_objects(), progress=False))
    added_dir = add_trials(at_one, TWO, tmp_path / "added", _objects(), progress=False)
    added = load(added_dir)
    pd.testing.assert_frame_equal(added, fresh, check_exact=True)
    manifest = read_manifest(added_dir)
    assert manifest["trials"] == 2 and [r["trials"] for r in earlier_runs(manifest)] == [1]
    assert earlier_runs(manifest)[0]["sessions"] == read_manifest(at_one)["sessions"]


@given(st.lists(st.lists(st.sampled_from(LEVELS.tolist()), min_size=3, max_size=3),
                min_size=1, max_size=20), st.randoms(use_true_random=False))
@settings(max_examples=60, deadline=None)
def test_recorded_levels_are_recovered_from_a_summary(rows, random):
    """Three trials' levels come back (as a multiset) from their mean, spread and successes."""
    robust = np.array(rows)
    summary = pd.DataFrame(trial_summary(robust, reaches_reference(robust, Config())))
    found = recorded_levels(summary, 3, Config())
    known = ~np.isnan(found).any(axis=1)
    np.testing.assert_array_equal(found[known], np.sort(robust, axis=1)[known])
    shuffled = np.array([random.sample(row, 3) for row in rows])
    again = trial_summary(shuffled, reaches_reference(shuffled, Config()))
    for name, values in again.items():
        np.testing.assert_array_equal(values, summary[name].to_numpy())


def test_almost_every_set_of_three_levels_is_unique_given_its_summary():
    every = np.array(list(itertools.combinations_with_replacement(LEVELS.tolist(), 3)))
    summary = pd.DataFrame(trial_summary(every, reaches_reference(every, Config())))
    found = recorded_levels(summary, 3, Config())
    known = ~np.isnan(found).any(axis=1)
    np.testing.assert_array_equal(found[known], every[known])
    assert known.mean() > 0.99, f"{(~known).sum()} of {len(every)} sets are ambiguous"


def test_the_summary_does_not_depend_on_how_many_grips_share_the_array():
    rng = np.random.default_rng(3)
    robust = rng.choice(LEVELS, size=(500, 4))
    together = trial_summary(robust, robust >= 64.0)
    for row in (0, 17, 499):
        alone = trial_summary(robust[row:row + 1], robust[row:row + 1] >= 64.0)
        for name, values in alone.items():
            assert values[0] == together[name][row]


def test_a_source_with_as_many_trials_is_refused(at_one, tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main([str(at_one), "--config", str(_recipe(tmp_path, 1)), "--out", str(tmp_path / "x")])
    assert stop.value.code == 2
    assert "trials must exceed the source's 1, got 1" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_a_source_made_with_another_config_is_refused(at_one, tmp_path):
    other = TWO.override(grasp={"mu": 0.5})
    with pytest.raises(ValueError, match=r"another config \(sections \['grasp'\]"):
        add_trials(at_one, other, tmp_path / "x", _objects(), progress=False)


def _recipe(folder: Path, trials: int) -> Path:
    path = folder / "recipe.yaml"
    path.write_text(f"dataset:\n  trials: {trials}\n  max_grips_per_object: 4\n")
    return path
