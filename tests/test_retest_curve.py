"""The within-object retest measured at each label size (grip_env.dataset.retest_curve)."""

import numpy as np
import pytest

from grip_env.dataset.retest_curve import retest_curve, trials_for, trials_measured


def _objects(count: int, grips: int, trials: int, noise: float, seed: int) -> list[np.ndarray]:
    """Objects whose grips' true means are standard normal, each trial adding independent
    normal noise of std ``noise``."""
    rng = np.random.default_rng(seed)
    return [rng.normal(size=(grips, 1)) + noise * rng.normal(size=(grips, trials))
            for _ in range(count)]


def test_noise_free_grips_repeat_perfectly_at_every_label_size():
    np.testing.assert_allclose(retest_curve(_objects(3, 8, 6, 0.0, seed=1), splits=20), 1.0)


def test_one_reliability_for_every_object_follows_spearman_brown():
    """Normal true means and noise of variance 1: a one-trial Pearson reliability of 1/2, so
    n trials reach n/(n+1), and Spearman is (6/pi) asin(r/2) for normal scores."""
    curve = retest_curve(_objects(30, 200, 10, 1.0, seed=2), splits=40)
    n = np.arange(1, 6)
    expected = 6 / np.pi * np.arcsin(n / (n + 1) / 2)
    np.testing.assert_allclose(curve, expected, atol=0.02)


def test_objects_of_different_reliability_rise_slower_than_their_mean_would():
    """Half the objects rank their grips perfectly after one trial, half never: every label
    size measures about 1/2, where Spearman-Brown from the one-trial mean promises 0.83 at
    five trials."""
    perfect = _objects(10, 30, 10, 0.0, seed=3)
    rng = np.random.default_rng(4)
    hopeless = [rng.normal(size=(30, 10)) for _ in range(10)]
    curve = retest_curve(perfect + hopeless, splits=100)
    np.testing.assert_allclose(curve, 0.5, atol=0.03)
    assert trials_measured(curve, 0.8) > 10


def test_grips_all_alike_leave_the_object_out():
    alike = np.ones((5, 4))
    varied = _objects(1, 5, 4, 0.0, seed=5)
    np.testing.assert_allclose(retest_curve([alike, *varied], splits=10), 1.0)
    assert np.isnan(retest_curve([alike], splits=10)).all()


def test_the_curve_is_seeded_and_stops_at_the_fewest_trials_of_any_object():
    objects = _objects(4, 12, 10, 1.0, seed=6) + _objects(1, 12, 6, 1.0, seed=7)
    first, again = (retest_curve(objects, splits=30, seed=9) for _ in range(2))
    np.testing.assert_array_equal(first, again)
    assert len(first) == 3
    assert not np.array_equal(first, retest_curve(objects, splits=30, seed=10))


def test_one_trial_a_grip_is_refused_by_its_count():
    with pytest.raises(ValueError, match="2 or more trials a grip, got 0"):
        retest_curve([np.ones((3, 1))])
    with pytest.raises(ValueError, match="1 or more splits, got 0"):
        retest_curve(_objects(2, 4, 4, 1.0, seed=8), splits=0)


def test_trials_measured_is_the_first_label_size_that_reaches_the_target():
    assert trials_measured([0.70, 0.78, 0.81, 0.84], 0.8) == 3.0
    assert trials_measured([0.81], 0.8) == 1.0
    beyond = trials_measured([0.5, 0.6], 0.8)
    assert beyond == pytest.approx(trials_for(0.6, 2)) and beyond > 2
    assert np.isnan(trials_measured([], 0.8)) and np.isnan(trials_measured([0.7, np.nan], 0.8))
