"""Execution uncertainty of one trial: where the palm really goes and what the object really is."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from grip_env.config import Config


@dataclass(frozen=True)
class TrialNoise:
    """One trial's draws: palm offset (mm, plane frame), yaw error (rad), friction, mass (kg)."""

    offset_mm: tuple[float, float]
    yaw_error: float
    friction: float
    mass_kg: float


def sample_noise(rng: np.random.Generator, config: Config | None = None) -> TrialNoise:
    """Draw one trial's noise from ``rng``.

    Palm position: isotropic Gaussian with std ``uncertainty.position_std_mm`` per axis;
    yaw: Gaussian with std ``yaw_std_rad``; friction: uniform in ``friction_range``, never below
    the planner's assumed minimum ``grasp.mu``; mass: log-normal around
    ``sim.mass_per_weight_kg * grasp.weight`` with relative std ``mass_rel_std``.
    """
    config = config if config is not None else Config()
    u = config.uncertainty
    low, high = sorted(u.friction_range)
    low = max(low, config.grasp.mu)
    high = max(high, low)
    offset = rng.normal(0.0, u.position_std_mm, size=2)
    yaw = rng.normal(0.0, u.yaw_std_rad)
    friction = rng.uniform(low, high)
    nominal = config.sim.mass_per_weight_kg * config.grasp.weight
    sigma = np.sqrt(np.log1p(u.mass_rel_std**2))
    mass = nominal * np.exp(rng.normal(-sigma**2 / 2, sigma))
    offset_mm = (float(offset[0]), float(offset[1]))
    return TrialNoise(offset_mm, float(yaw), float(friction), float(mass))


def trial_rng(seed: int, grip_key: int, trial: int) -> np.random.Generator:
    """The generator of trial ``trial`` of grip ``grip_key``: depends on (seed, key, trial) only."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), int(grip_key), int(trial)]))


def zero_noise(config: Config | None = None) -> TrialNoise:
    """No execution error; friction at the planner's minimum and the nominal mass."""
    config = config if config is not None else Config()
    mass = config.sim.mass_per_weight_kg * config.grasp.weight
    return TrialNoise((0.0, 0.0), 0.0, float(config.grasp.mu), float(mass))
