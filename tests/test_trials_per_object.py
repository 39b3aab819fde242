"""Trials chosen per object (tests.benchmarks.trials_per_object): its rules and its retest."""

import numpy as np
import pytest
from scipy import stats

from grip_env.dataset.retest_curve import retest_curve, split_order
from tests.benchmarks.trials_per_object import Splits, fixed, graded, held_out, judge, two_level
from tests.test_retest_curve import _objects


def test_a_fixed_count_is_the_spearman_of_the_two_halves_first_trials():
    """Each split's labels are the first n trials of its two halves; their Spearman averaged
    over splits, then over objects (scipy's Spearman, split by split)."""
    objects = _objects(3, 12, 10, 1.0, seed=1)
    order = split_order(8, 10, 4)
    splits = [Splits(m, order, seconds=0.1) for m in objects]
    for n in range(1, 6):
        expected = np.mean([np.mean([stats.spearmanr(m[:, p[:n]].mean(1),
                                                     m[:, p[5:5 + n]].mean(1)).statistic
                                     for p in order]) for m in objects])
        retest, trials, seconds = judge(splits, fixed(n))
        assert abs(retest - expected) < 1e-12
        assert trials == n and seconds == pytest.approx(n * 0.1)


def test_a_fixed_count_agrees_with_the_retest_curve_over_many_splits():
    objects = _objects(4, 40, 10, 1.0, seed=2)
    splits = [Splits(m, split_order(300, 10, 5), seconds=0.1) for m in objects]
    curve = retest_curve(objects, splits=300, seed=6)
    measured = [judge(splits, fixed(n))[0] for n in range(1, 6)]
    np.testing.assert_allclose(measured, curve, atol=0.01)


def test_two_level_stops_the_objects_whose_first_two_trials_agree():
    """Noise-free objects rank their grips alike from the first two trials and stop at two;
    pure-noise objects go on to K. Trials and CPU are averaged over grips."""
    rng = np.random.default_rng(2)
    perfect = [Splits(m, split_order(20, 10, 0), seconds=1.0) for m in _objects(2, 10, 10, 0.0, 3)]
    hopeless = [Splits(rng.normal(size=(30, 10)), split_order(20, 10, 0), seconds=2.0)]
    retest, trials, seconds = judge(perfect + hopeless, two_level(0.99, 5))
    assert trials == (2 * 10 * 2 + 5 * 30) / 50
    assert seconds == pytest.approx((2 * 10 * 2 * 1.0 + 5 * 30 * 2.0) / 50)
    assert judge(perfect, two_level(0.99, 5))[:2] == (1.0, 2.0)
    assert abs(retest - (1.0 + 1.0 + judge(hopeless, fixed(5))[0]) / 3) < 1e-12


def test_graded_takes_the_fewest_trials_spearman_brown_says_reach_the_target():
    """From a first-two Spearman r, Spearman-Brown at k trials is k r / (1 + (k - 1) r): at
    r = 1/2 that is k / (k + 1), 2/3 at two trials and 3/4 at three."""
    first_two = np.array([[0.5, 1.0], [np.nan, 0.2]])
    np.testing.assert_array_equal(graded(0.75, 5)(first_two), [[3, 2], [5, 5]])
    np.testing.assert_array_equal(graded(0.7, 5)(first_two), [[3, 2], [5, 5]])
    np.testing.assert_array_equal(graded(0.6, 5)(first_two), [[2, 2], [5, 5]])


def test_held_out_judges_each_fold_on_objects_its_setting_was_not_chosen_on():
    """Objects that need no second trial and objects no count rescues: a setting chosen on one
    half judged on the other half, as many folds as 2 x repeats."""
    perfect = [Splits(m, split_order(20, 10, 0), seconds=1.0) for m in _objects(4, 10, 10, 0.0, 5)]
    rules = {"all stop at two": fixed(2), "all take five": fixed(5)}
    folds = held_out(perfect, rules, repeats=3, seed=0)
    np.testing.assert_array_equal(folds, [[1.0, 2.0, 2.0]] * 6)
    rng = np.random.default_rng(6)
    noise = [Splits(rng.normal(size=(10, 10)), split_order(20, 10, 0), seconds=1.0)
             for _ in range(4)]
    assert len(held_out(noise, rules, repeats=3, seed=0)) == 0  # no setting reaches 0.8
