"""Execution uncertainty of one trial: where the palm really goes and what the object really is."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from grip_env.config import Config
from grip_env.objects import PlanarObject


@dataclass(frozen=True)
class TrialNoise:
    """One trial's draws: palm offset (mm, plane frame), yaw error (rad), friction, mass factor.

    ``friction`` is the pad-object coefficient (the object's side; the pads' is 1, and PyBullet
    multiplies the two); ``mass_scale`` multiplies the object's nominal mass.
    """

    offset_mm: tuple[float, float]
    yaw_error: float
    friction: float
    mass_scale: float


def object_mass_kg(obj: PlanarObject, config: Config | None = None) -> float:
    """Nominal mass: area x thickness x density x the weight class W (``grasp.weight``)."""
    config = config if config is not None else Config()
    volume_m3 = obj.area * config.objects.thickness_mm * 1e-9
    return float(volume_m3 * config.objects.density_kg_m3 * config.grasp.weight)


def sample_noise(rng: np.random.Generator, config: Config | None = None) -> TrialNoise:
    """Draw one trial's noise from ``rng``.

    Palm position: isotropic Gaussian with std ``uncertainty.position_std_mm`` per axis;
    yaw: Gaussian with std ``yaw_std_rad``; friction: uniform in ``friction_range``, never below
    the planner's assumed minimum ``grasp.mu``; mass: a log-normal factor of mean 1 and
    relative std ``mass_rel_std`` on the object's nominal mass (``object_mass_kg``).
    """
    config = config if config is not None else Config()
    u = config.uncertainty
    low, high = sorted(u.friction_range)
    low = max(low, config.grasp.mu)
    high = max(high, low)
    offset = rng.normal(0.0, u.position_std_mm, size=2)
    yaw = rng.normal(0.0, u.yaw_std_rad)
    friction = rng.uniform(low, high)
    sigma = np.sqrt(np.log1p(u.mass_rel_std**2))
    mass = np.exp(rng.normal(-sigma**2 / 2, sigma))
    offset_mm = (float(offset[0]), float(offset[1]))
    return TrialNoise(offset_mm, float(yaw), float(friction), float(mass))


def trial_rng(seed: int, grip_key: int, trial: int) -> np.random.Generator:
    """The generator of trial ``trial`` of grip ``grip_key``: depends on (seed, key, trial) only."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), int(grip_key), int(trial)]))


def zero_noise(config: Config | None = None) -> TrialNoise:
    """No execution error; friction at the planner's minimum and the nominal mass."""
    config = config if config is not None else Config()
    return TrialNoise((0.0, 0.0), 0.0, float(config.grasp.mu), 1.0)
