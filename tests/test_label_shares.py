"""The label's variance between grips split into grip, engine and draws (``label_shares``)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from grip_env.dataset.label_shares import grip_components, label_shares

tables = arrays(float, st.tuples(st.integers(2, 8), st.just(2), st.integers(2, 6)),
                elements=st.floats(0.0, 128.0))


def test_grips_that_differ_alike_in_both_engines_and_every_draw_are_all_grip():
    grips = np.array([8.0, 16.0, 64.0, 128.0])
    outcomes = np.broadcast_to(grips[:, None, None], (4, 2, 5))
    assert grip_components(outcomes) == pytest.approx([np.var(grips, ddof=1), 0.0, 0.0])
    assert label_shares(grip_components(outcomes), 5) == pytest.approx([1.0, 0.0, 0.0])


def test_an_engine_that_reverses_the_grips_is_all_engine():
    """Engine A ranks three grips 0, 10, 20 g and engine B 20, 10, 0 g, in each of 4 draws. By
    hand: every grip's mean is 10 (the grips' mean square is 0); the engine-by-grip deviations
    are -10, 10, 0, 0, 10, -10, whose squares sum to 400, a mean square of 4 x 400 / 2 = 800,
    so var GE = 800 / 4 = 200 and var G = (0 - 800) / 8 = -100, counted as 0."""
    outcomes = np.array([[0.0, 20.0], [10.0, 10.0], [20.0, 0.0]])[:, :, None].repeat(4, axis=2)
    assert grip_components(outcomes) == pytest.approx([-100.0, 200.0, 0.0])
    assert label_shares(grip_components(outcomes), 5) == pytest.approx([0.0, 1.0, 0.0])


def test_draws_that_move_each_grip_its_own_way_shrink_with_the_trials():
    """Two grips, alike in both engines, swap under the second draw (10, 30 g against 30, 10 g):
    all draws, whose share of the label falls as 1 / T. By hand: the grip-by-draw deviations
    are -10, 10, 10, -10 (squares 400), a mean square of 2 x 400 / 1 = 800 and no residual, so
    var GD = 800 / 2 = 400 and var G = (0 - 0 - 800 + 0) / 4 = -200, counted as 0."""
    outcomes = np.array([[[10.0, 30.0]] * 2, [[30.0, 10.0]] * 2])
    assert grip_components(outcomes) == pytest.approx([-200.0, 0.0, 400.0])
    assert label_shares(grip_components(outcomes), 5) == pytest.approx([0.0, 0.0, 1.0])
    assert label_shares([100.0, 0.0, 200.0], 1) == pytest.approx([1 / 3, 0.0, 2 / 3])
    assert label_shares([100.0, 0.0, 200.0], 4) == pytest.approx([2 / 3, 0.0, 1 / 3])


@given(tables, st.data())
def test_what_every_grip_shares_changes_no_component(outcomes, data):
    """An engine's offset, a draw's, an engine-by-draw term, or reordering the grips moves
    every grip alike: none can reorder them, so none is in a component."""
    _, engines, draws = outcomes.shape
    offsets = arrays(float, (engines, draws), elements=st.floats(-50.0, 50.0))
    shifted = outcomes + data.draw(offsets)[None]
    order = data.draw(st.permutations(range(len(outcomes))))
    expected = grip_components(outcomes)
    assert grip_components(shifted[list(order)]) == pytest.approx(expected, abs=1e-6)


def test_known_components_are_recovered_from_many_grips():
    """Outcomes drawn with var G 100, var GE 25 and var GD + GED 50 (g^2): 400 grips, 10
    draws, seed 0; each estimate within 15 % of its value (its sampling error is about 7 %)."""
    rng = np.random.default_rng(0)
    grips, draws = 400, 10
    grip = rng.normal(0, 10.0, (grips, 1, 1))
    engine = rng.normal(0, 5.0, (grips, 2, 1))
    noise = rng.normal(0, np.sqrt(50.0), (grips, 2, draws))
    found = grip_components(50.0 + grip + engine + noise)
    assert found == pytest.approx([100.0, 25.0, 50.0], rel=0.15)


@pytest.mark.parametrize("shape", [(1, 2, 5), (3, 1, 5), (3, 2, 1), (3, 2)])
def test_a_table_too_small_to_split_is_refused(shape):
    with pytest.raises(ValueError, match="grips, engines, draws"):
        grip_components(np.zeros(shape))


def test_bad_values_and_trial_counts_are_refused():
    with pytest.raises(ValueError, match="NaN"):
        grip_components(np.full((2, 2, 2), np.nan))
    with pytest.raises(ValueError, match="trials"):
        label_shares([1.0, 1.0, 1.0], 0)
    assert np.isnan(label_shares([-1.0, 0.0, 0.0], 5)).all()
