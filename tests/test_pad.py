"""The fingertip's rubber pad: Hertz stiffness, rubber's loss, the defaults derived from them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from grip_env.config import Config
from grip_env.hand_geometry import DISTAL_PAD_MM
from grip_env.objects import load_object_set
from grip_env.sim.pad import (
    RUBBER_LOSS_FACTOR,
    RUBBER_MODULUS_PA,
    hertz_stiffness,
    loss_damping,
)
from grip_env.sim.uncertainty import object_mass_kg


def _hertz_force(depth_m: float, modulus_pa: float, radius_m: float) -> float:
    """Hertz's law written out: F = 4/3 E / (1 - 0.25) sqrt(R) d^1.5 (rubber, nu = 0.5)."""
    return 4.0 / 3.0 * (modulus_pa / 0.75) * math.sqrt(radius_m) * depth_m**1.5


def test_the_stiffness_is_the_slope_of_hertzs_law_at_the_force():
    k = hertz_stiffness(3e6, 8e-3, 15.0)
    # the depth at which Hertz's law gives 15 N, by bisection on the law itself
    low, high = 0.0, 0.01
    for _ in range(80):
        mid = (low + high) / 2
        low, high = (mid, high) if _hertz_force(mid, 3e6, 8e-3) < 15.0 else (low, mid)
    step = 1e-9
    slope = (_hertz_force(low + step, 3e6, 8e-3) - _hertz_force(low - step, 3e6, 8e-3)) / (2 * step)
    assert low == pytest.approx(0.996e-3, rel=1e-3)  # a millimetre of rubber at 15 N
    assert k == pytest.approx(slope, rel=1e-6)


@given(st.floats(1.0, 100.0), st.floats(1e5, 1e8), st.floats(1e-3, 0.05))
def test_the_stiffness_scales_as_hertz_says(force, modulus, radius):
    """k = 3/2 F / d with d ~ (F / (E sqrt R))^(2/3): k ~ F^(1/3) E^(2/3) R^(1/3)."""
    k = hertz_stiffness(modulus, radius, force)
    assert hertz_stiffness(modulus, radius, 8 * force) == pytest.approx(2 * k, rel=1e-9)
    assert hertz_stiffness(8 * modulus, radius, force) == pytest.approx(4 * k, rel=1e-9)
    assert hertz_stiffness(modulus, 64 * radius, force) == pytest.approx(4 * k, rel=1e-9)


def test_the_damping_is_the_loss_factor_at_the_natural_frequency():
    k, m = 2.0e4, 0.08
    omega = math.sqrt(k / m)
    assert loss_damping(k, m, 0.2) == pytest.approx(0.2 * k / omega)
    assert loss_damping(k, m, 0.0) == 0.0


def test_the_default_pad_is_the_rubber_fingertip_it_is_derived_from():
    """sim.pad_stiffness_n_per_m: 3 MPa rubber on the distal link's 8 mm rounding at the
    fingertip force; sim.pad_damping_n_s_per_m: loss factor 0.2 with the default objects'
    median mass (rounded to the config's figures)."""
    sim = Config().sim
    k = hertz_stiffness(RUBBER_MODULUS_PA, DISTAL_PAD_MM * 1e-3, sim.finger_force_n)
    assert sim.pad_stiffness_n_per_m == pytest.approx(k, rel=0.005)
    median = float(np.median([object_mass_kg(o) for o in load_object_set("default")]))
    damping = loss_damping(sim.pad_stiffness_n_per_m, median, RUBBER_LOSS_FACTOR)
    assert sim.pad_damping_n_s_per_m == pytest.approx(damping, rel=0.01)


@pytest.mark.parametrize(("args", "name"), [
    ((0.0, 8e-3, 15.0), "modulus_pa"), ((3e6, -1.0, 15.0), "radius_m"),
    ((3e6, 8e-3, float("nan")), "force_n"),
])
def test_bad_pad_figures_are_refused_by_name(args, name):
    with pytest.raises(ValueError, match=name):
        hertz_stiffness(*args)
    with pytest.raises(ValueError, match="poisson"):
        hertz_stiffness(3e6, 8e-3, 15.0, poisson=0.7)
    with pytest.raises(ValueError, match="positive"):
        loss_damping(-1.0, 0.1)
    with pytest.raises(ValueError, match="loss_factor"):
        loss_damping(1e4, 0.1, -0.1)
