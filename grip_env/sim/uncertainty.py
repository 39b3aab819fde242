"""Execution uncertainty of one trial: where the palm really goes and what the object really is.

Which draw a trial meets (``trial_noises``): with ``uncertainty.draws: common`` (the default),
trial k of every grip of an object draws from one generator keyed by (seed, object, k), so the
grips of one object are compared under the same friction, mass and palm error (common random
numbers); ``per_grip`` keys it by (seed, grip, k) instead. With ``uncertainty.stratified``,
friction and mass are spread over their ranges across each block of ``dataset.trials`` trials
(one stratum per trial, a Latin hypercube) instead of sampled independently; with
``uncertainty.stratified_palm``, so are the palm's two offsets and its yaw error.
"""

from __future__ import annotations

import zlib
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtri

from grip_env.config import Config
from grip_env.objects import PlanarObject

#: Tag the stratifications' permutations apart from the trials' own streams and each other.
_STRATA_TAG = 0x5354
_PALM_STRATA_TAG = 0x5350


@dataclass(frozen=True)
class TrialNoise:
    """One trial's draws: palm offset (mm, in the planned palm frame: x across the thumb's force,
    y along it), yaw error (rad), friction, mass factor. In the palm frame, every grip that meets
    the same draw meets the same error relative to its own plan.

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


def sample_noise(rng: np.random.Generator, config: Config | None = None,
                 quantiles: tuple[float, float] | None = None,
                 palm_quantiles: tuple[float, float, float] | None = None) -> TrialNoise:
    """Draw one trial's noise from ``rng``.

    Palm position: isotropic Gaussian with std ``uncertainty.position_std_mm`` per axis;
    yaw: Gaussian with std ``yaw_std_rad``; friction: uniform in ``friction_range``, never below
    the planner's assumed minimum ``grasp.mu``; mass: a log-normal factor of mean 1 and
    relative std ``mass_rel_std`` on the object's nominal mass (``object_mass_kg``).
    ``quantiles`` (friction, mass) and ``palm_quantiles`` (offset x, offset y, yaw), each in
    (0, 1), replace their draws (stratification); ``rng`` is consumed the same either way.
    """
    config = config if config is not None else Config()
    u = config.uncertainty
    low, high = sorted(u.friction_range)
    low = max(low, config.grasp.mu)
    high = max(high, low)
    offset = rng.normal(0.0, u.position_std_mm, size=2)
    yaw = rng.normal(0.0, u.yaw_std_rad)
    unit_friction = rng.uniform()
    standard_mass = rng.normal()
    if palm_quantiles is not None:
        x, y, z = (float(ndtri(q)) for q in palm_quantiles)
        offset = u.position_std_mm * np.array([x, y])
        yaw = u.yaw_std_rad * z
    if quantiles is not None:
        unit_friction, standard_mass = quantiles[0], float(ndtri(quantiles[1]))
    friction = low + (high - low) * unit_friction
    sigma = np.sqrt(np.log1p(u.mass_rel_std**2))
    mass = np.exp(-sigma**2 / 2 + sigma * standard_mass)
    offset_mm = (float(offset[0]), float(offset[1]))
    return TrialNoise(offset_mm, float(yaw), float(friction), float(mass))


def trial_rng(seed: int, key: int, trial: int) -> np.random.Generator:
    """The generator of trial ``trial`` under ``key`` (an object's under common draws, a grip's
    under per-grip draws): depends on (seed, key, trial) only."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), int(key), int(trial)]))


def stable_key(label: object) -> int:
    """A stable non-negative integer for seeding: the label itself when it is one, else the CRC-32
    of its text (the same on every machine and Python, unlike ``hash``)."""
    if isinstance(label, (int, np.integer)) and not isinstance(label, bool) and label >= 0:
        return int(label)
    return zlib.crc32(str(label).encode())


def trial_noises(
    config: Config, seed: int, object_key: int, grip_keys: Sequence[int], trials: Sequence[int],
) -> list[list[TrialNoise]]:
    """``noises[g][j]``: the draw of trial ``trials[j]`` of grip ``grip_keys[g]``.

    It depends on (seed, object key, grip key, trial number) only, never on which other grips
    or trials are asked for. Under common draws the grip key is not used.
    """
    common = config.uncertainty.draws == "common"
    cache: dict[tuple[int, int], TrialNoise] = {}

    u = config.uncertainty

    def draw(key: int, k: int) -> TrialNoise:
        if (key, k) not in cache:
            quantiles = _stratum(config, seed, key, k, 2, _STRATA_TAG) if u.stratified else None
            palm = (_stratum(config, seed, key, k, 3, _PALM_STRATA_TAG)
                    if u.stratified_palm else None)
            cache[key, k] = sample_noise(trial_rng(seed, key, k), config, quantiles, palm)
        return cache[key, k]

    return [[draw(object_key if common else grip, k) for k in trials] for grip in grip_keys]


def _stratum(config: Config, seed: int, key: int, trial: int, dims: int,
             tag: int) -> tuple[float, ...]:
    """The ``dims`` quantiles of ``trial`` (a Latin hypercube): block ``trial // n`` of n =
    ``dataset.trials`` trials gives each of its trials one of n equal strata of each dimension,
    in a seeded order keyed by ``tag``, and a uniform place inside it."""
    n = config.dataset.trials
    block, place = divmod(int(trial), n)
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), int(key), block, tag]))
    strata = np.stack([rng.permutation(n) for _ in range(dims)])
    jitter = rng.uniform(size=(dims, n))
    return tuple(float(q) for q in (strata[:, place] + jitter[:, place]) / n)


def zero_noise(config: Config | None = None) -> TrialNoise:
    """No execution error; friction at the planner's minimum and the nominal mass."""
    config = config if config is not None else Config()
    return TrialNoise((0.0, 0.0), 0.0, float(config.grasp.mu), 1.0)
