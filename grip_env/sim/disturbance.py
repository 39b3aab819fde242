"""The graded outcome: how large a disturbance a lifted grip resists, in g.

After the lift and hold, the world is saved. For each disturbance (by default the six in the
grip's plane: along the palm frame's +-x and +-y, and a twist either way about the palm normal;
``sim.ramp_directions: spatial`` adds pulling the object out of the hand along gravity and
pushing it in) the saved moment is restored and the disturbance is raised level by level,
doubling from ``sim.ramp_levels_g[0]`` up to ``sim.ramp_fine_from_g`` (where grips' limits begin:
nine in ten standard trials hold 16 g), then by ``sim.ramp_ratio``. Each level is held until the
object is at rest under it (quasi-static loading): at least ``sim.ramp_steps_per_level`` steps,
and on until it moved less than ``SETTLED_SHARE`` of the hold tolerances over the last that many
steps, or ``sim.ramp_max_steps_per_level`` steps have passed (it then counts as held: it is still
within tolerance). A level held a fixed few steps was not quasi-static: an object that had begun
to slide was caught levels later the shorter the hold, so the labels fell with every doubling of
the hold (BENCHMARKS.md, "A converged ramp").

A level of ``a`` g is a force ``m a g`` through the centre of mass, or for the twist the torque
``m a g k`` that gives a tangential acceleration of ``a`` g at the object's radius of gyration
``k``. The level held in a direction is the last one before the
object moves past the hold tolerance (drift or rotation in the palm frame). The trial's
robustness is the weakest direction's level, so no direction needs to climb past the weakest level
found: where the engine can pause a climb and resume it bit for bit (MuJoCo), the directions climb
together, one level each in turn, and the ramp ends at the first level any of them fails; elsewhere
(PyBullet) they climb one after another, each only up to the weakest level found so far. Every
climb starts from the same restored moment, so both give the same level, the minimum of the
directions' own limits; they differ only in the steps spent.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from grip_env.config import SimConfig
from grip_env.sim import pose

GRAVITY = 9.81
#: A level has settled when, over its last ``ramp_steps_per_level`` steps, the object moved less
#: than this share of ``hold_tolerance_mm`` and turned less than this share of
#: ``hold_rotation_deg``.
SETTLED_SHARE = 0.01

#: (kind, palm-frame axis, sign) in the grip's plane: forces along the palm's x and y axes and
#: twists about its normal, the wrenches the planar grip's geometry resists.
PLANAR_DISTURBANCES: tuple[tuple[str, int, float], ...] = (
    ("force", 0, +1.0), ("force", 0, -1.0), ("force", 1, +1.0), ("force", 1, -1.0),
    ("torque", 2, +1.0), ("torque", 2, -1.0),
)
#: Out of the plane: pulling the object out of the hand (with gravity) and pushing it in. Every
#: grip resists these by friction alone, about mu * (sum of normal forces) whatever its geometry.
NORMAL_DISTURBANCES: tuple[tuple[str, int, float], ...] = (("force", 2, +1.0), ("force", 2, -1.0))


def disturbances(config: SimConfig) -> tuple[tuple[str, int, float], ...]:
    """The disturbances a trial is ramped along (``sim.ramp_directions``)."""
    if config.ramp_directions == "planar":
        return PLANAR_DISTURBANCES
    return NORMAL_DISTURBANCES + PLANAR_DISTURBANCES


def ramp_levels(config: SimConfig) -> NDArray[np.float64]:
    """The disturbance levels (g): doubling from the first below ``ramp_fine_from_g``, then from
    it (held within ``ramp_levels_g``) to the last ``ramp_ratio`` apart."""
    first, last = config.ramp_levels_g
    fine = min(max(config.ramp_fine_from_g, first), last)
    doublings = int(np.ceil(np.log2(fine / first) - 1e-9))
    count = int(np.floor(np.log(last / fine) / np.log(config.ramp_ratio) + 1e-9)) + 1
    return np.concatenate([first * 2.0 ** np.arange(doublings),
                           fine * config.ramp_ratio ** np.arange(count)])


@dataclass(frozen=True)
class RampProbe:
    """What the ramp needs from a scene, as callables (kept free of PyBullet here).

    ``restore()`` returns the world to the saved moment; ``push(kind, vector)`` applies a world
    force (N) or torque (N·m) to the object for the next step; ``step()`` advances one step;
    ``moved()`` says whether the object is past the hold tolerance; ``where()`` gives the
    object's pose in the palm frame as ``moved()`` last saw it; ``palm_axes`` (3, 3) has the
    palm frame's axes as rows, in world coordinates. ``pause()``, when given, saves this moment
    and returns a callable that resumes it bit for bit (once); without it the directions climb
    one after another.
    """

    restore: Callable[[], None]
    push: Callable[[str, NDArray[np.float64]], None]
    step: Callable[[], None]
    moved: Callable[[], bool]
    where: Callable[[], tuple[pose.Vector, pose.Quaternion]]
    palm_axes: NDArray[np.float64]
    pause: Callable[[], Callable[[], None]] | None = None


def reaches(level_g: float, reference_g: float) -> bool:
    """Whether a held level reaches the reference. A reference on a ramp level (64 g is
    16 x 2^(8/4)) counts as reached although 16 * ratio**8 computes to 63.999999999999986."""
    return bool(reached(np.float64(level_g), reference_g))


def reached(levels_g: NDArray[np.float64], reference_g: float) -> NDArray[np.bool_]:
    """:func:`reaches`, element by element."""
    return np.asarray(levels_g, dtype=float) >= reference_g * (1.0 - 1e-9)


def robustness(probe: RampProbe, mass_kg: float, gyration_m: float, config: SimConfig) -> float:
    """The highest level (g) held in every direction (gravity acts throughout)."""
    levels = ramp_levels(config)
    loads = [_load(probe, d, mass_kg, gyration_m) for d in disturbances(config)]
    if probe.pause is None:
        weakest = _one_after_another(probe, loads, levels, config)
    else:
        weakest = _together(probe, probe.pause, loads, levels, config)
    return float(levels[weakest - 1]) if weakest > 0 else 0.0


Load = tuple[str, NDArray[np.float64]]


def _load(probe: RampProbe, disturbance: tuple[str, int, float], mass_kg: float,
          gyration_m: float) -> Load:
    """A disturbance's kind and its world vector per g of level (N, or N·m for a twist)."""
    kind, axis, sign = disturbance
    scale = mass_kg * GRAVITY * (gyration_m if kind == "torque" else 1.0)
    return kind, sign * probe.palm_axes[axis] * scale


def _one_after_another(probe: RampProbe, loads: list[Load], levels: NDArray[np.float64],
                       config: SimConfig) -> int:
    """Each direction from the saved moment up to the weakest level found so far: the index
    of the first level that failed in some direction (``len(levels)`` if none did)."""
    weakest = len(levels)
    for kind, unit in loads:
        probe.restore()
        weakest = min(weakest, _first_failure(probe, kind, unit, levels[:weakest], config))
        if weakest == 0:
            break
    return weakest


def _together(probe: RampProbe, pause: Callable[[], Callable[[], None]], loads: list[Load],
              levels: NDArray[np.float64], config: SimConfig) -> int:
    """Every direction one level at a time, each resumed where ``pause`` left it, until one
    fails: the index of that level (``len(levels)`` if none did). Within a level, the direction
    whose object has crept nearest its tolerance goes first, as the likeliest to fail there."""
    resumes: list[Callable[[], None]] = [probe.restore] * len(loads)
    nearness = [0.0] * len(loads)
    reference: tuple[pose.Vector, pose.Quaternion] | None = None
    for index, level in enumerate(levels):
        for d in sorted(range(len(loads)), key=lambda d: -nearness[d]):
            resumes[d]()
            if reference is None:  # the saved moment's pose, seen after the first restore
                reference = probe.where()
            kind, unit = loads[d]
            if not _holds(probe, kind, unit * level, config):
                return index
            resumes[d] = pause()
            drift, turn = pose.moved_from(reference, probe.where())
            nearness[d] = max(drift / config.hold_tolerance_mm, turn / config.hold_rotation_deg)
    return len(levels)


def direction_limits(probe: RampProbe, mass_kg: float, gyration_m: float,
                     config: SimConfig) -> NDArray[np.float64]:
    """Each disturbance's own limit (g, in the order of ``disturbances(config)``; 0 when its
    first level fails): every direction climbs to its own first failure, where
    :func:`robustness` stops at the weakest level found. A diagnostic: it costs
    more, and since every climb starts from the same restored moment (in both engines),
    :func:`robustness` is the minimum of these limits."""
    levels = ramp_levels(config)
    failed = [_climb(probe, d, mass_kg, gyration_m, levels, config)
              for d in disturbances(config)]
    return np.array([levels[k - 1] if k > 0 else 0.0 for k in failed], dtype=float)


def _climb(probe: RampProbe, disturbance: tuple[str, int, float], mass_kg: float,
           gyration_m: float, levels: NDArray[np.float64], config: SimConfig) -> int:
    """From the saved moment, ramp one disturbance through ``levels``: the index of the first
    level at which the object moved (``len(levels)`` if none did)."""
    kind, unit = _load(probe, disturbance, mass_kg, gyration_m)
    probe.restore()
    return _first_failure(probe, kind, unit, levels, config)


def _first_failure(
    probe: RampProbe, kind: str, unit: NDArray[np.float64], levels: NDArray[np.float64],
    config: SimConfig,
) -> int:
    """Index of the first level at which the object moved (``len(levels)`` if none did)."""
    for index, level in enumerate(levels):
        if not _holds(probe, kind, unit * level, config):
            return index
    return len(levels)


def _holds(probe: RampProbe, kind: str, vector: NDArray[np.float64], config: SimConfig) -> bool:
    """Hold one level until the object is at rest under it (or the step cap): whether it
    stayed within the hold tolerance."""
    window = config.ramp_steps_per_level
    longest = max(config.ramp_max_steps_per_level, window)
    still_mm = SETTLED_SHARE * config.hold_tolerance_mm
    still_deg = SETTLED_SHARE * config.hold_rotation_deg
    recent = deque([probe.where()], maxlen=window + 1)
    for step in range(1, longest + 1):
        probe.push(kind, vector)
        probe.step()
        if probe.moved():
            return False
        recent.append(probe.where())
        if step >= window:
            drift, turn = pose.moved_from(recent[0], recent[-1])
            if drift < still_mm and turn < still_deg:
                break
    return True
