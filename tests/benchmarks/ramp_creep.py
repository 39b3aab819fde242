"""Does a held object creep through the ramp's levels, or break away at one? (run by hand)

    python -m tests.benchmarks.ramp_creep --family mesh --workers 2

Every grip of the standard dataset's 80-object cross-check sample in ``--family``, in the lowest
and highest third of C1 within its object, runs trial 0 (its recorded draw) in both engines with
every direction ramped to its own first failure (``disturbance.direction_limits``), the object's
drift and turn in the palm frame read after every step. For the weakest direction (the trial's
label) it reports the drift and turn the object had reached at the last level it held (creep
already spent of the 5 mm / 10 degree hold tolerance), the share of failures that come after
the object had crept past half the tolerance, and the steps a held level took to settle; and
how far the fingers' flexion joints moved by then: the most any went back below its worm-gear
floor (the stop's give) and the most any moved from where the ramp found it.
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

from typing import Any

import numpy as np
import pandas as pd

from tests.benchmarks.engines import ENGINES
from tests.benchmarks.hold_squeeze import _checks, family_table


class _Recorder:
    """Wraps a ramp's probe: after every step, the climb, the level and the object's motion."""

    def __init__(self, probe: Any, scene: Any) -> None:
        from grip_env.sim.disturbance import RampProbe

        self.inner, self.scene, self.hand, self.rows = probe, scene, scene.hand, []
        self.start = self.hand.joint_states()[0]
        self.climb, self.level, self.reference = -1, 0.0, None
        self.probe = RampProbe(self.restore, self.push, self.step, probe.moved, probe.where,
                               probe.palm_axes)

    def restore(self) -> None:
        self.inner.restore()
        self.climb += 1
        self.reference = self.inner.where()

    def push(self, kind: str, vector: np.ndarray) -> None:
        self.level = float(np.linalg.norm(vector))
        self.inner.push(kind, vector)

    def step(self) -> None:
        from grip_env.sim import pose

        self.inner.step()
        self.inner.moved()  # updates where()
        drift, turn = pose.moved_from(self.reference, self.inner.where())
        q = self.hand.joint_states()[0]
        give = float(np.max(self.hand.state().peak - q))
        travel = float(np.max(np.abs(q - self.start)))
        self.rows.append((self.climb, self.level, drift, turn, give, travel))


def run_object(item: tuple[str, str], recorder: type[_Recorder] = _Recorder,
               summarize: Any = None) -> list[dict[str, Any]]:
    """The lowest and highest third of one object's grips by C1, trial 0, both engines, each
    ramp's steps kept by ``recorder`` and its weakest climb read by ``summarize`` (default
    ``_weakest``)."""
    from grip_env.sim import disturbance
    from grip_env.sim.execution import grip_keys, object_key
    from grip_env.sim.trial import TrialScene, grip_plans
    from grip_env.sim.uncertainty import trial_noises

    family, object_id = item
    check = next(c for c in _checks(family) if c.task.object_id == object_id)
    config, obj = check.task.config, check.task.obj
    grips = check.recorded.assign(object_id=object_id).reset_index(drop=True)
    third = pd.qcut(grips.C1.rank(method="first"), 3, labels=["low", "mid", "high"])
    draws = trial_noises(config, config.dataset.seed, object_key(obj, grips), grip_keys(grips),
                         range(1))
    read = summarize or _weakest
    rows: list[dict[str, Any]] = []
    for engine in ENGINES:
        recorders: list[_Recorder] = []
        scenes: list[Any] = []

        def ramp(probe: Any, mass: float, gyration: float, sim: Any,
                 recorders: list[_Recorder] = recorders, scenes: list[Any] = scenes) -> float:
            kept = recorder(probe, scenes[0])
            recorders.append(kept)
            return float(disturbance.direction_limits(kept.probe, mass, gyration, sim).min())

        scene_config = config.override(sim={"engine": engine})
        with TrialScene(obj, scene_config, ramp=ramp) as scene:
            scenes.append(scene)
            for k, (plan, noise) in enumerate(zip(grip_plans(grips), draws, strict=True)):
                if third[k] == "mid":
                    continue
                recorders.clear()
                result = scene.run(plan, noise[0])
                if result.held and recorders:
                    rows.append({"engine": engine, "object_id": object_id, "grip": k,
                                 "C1 third": third[k], "robustness": result.robustness_g,
                                 **read(recorders[0], scene_config.sim)})
    return rows


def weakest_climb(table: pd.DataFrame, sim: Any) -> tuple[int, float]:
    """The climb (a ``climb`` column's value) that failed at the lowest level, and that level
    (inf if no climb failed)."""
    failed = table.groupby("climb").apply(
        lambda c: c[(c.drift > sim.hold_tolerance_mm) | (c.turn > sim.hold_rotation_deg)]
        .level.min(), include_groups=False)
    climb = int(failed.fillna(np.inf).idxmin())
    return climb, float(failed[climb])


def _weakest(recorder: _Recorder, sim: Any) -> dict[str, float]:
    """The weakest direction's climb: the lowest failing level, its motion before it failed."""
    table = pd.DataFrame(recorder.rows,
                         columns=["climb", "level", "drift", "turn", "give", "travel"])
    climb, first_bad = weakest_climb(table, sim)
    rows = table[table.climb == climb]
    held = rows[rows.level < first_bad] if np.isfinite(first_bad) else rows
    last = held[held.level == held.level.max()] if len(held) else held
    return {"direction": climb, "drift_held_mm": float(last.drift.iloc[-1]) if len(last) else 0.0,
            "turn_held_deg": float(last.turn.iloc[-1]) if len(last) else 0.0,
            "steps_per_level": float(held.groupby("level").size().mean()) if len(held) else 0.0,
            "give_mrad": 1e3 * float(held.give.max()) if len(held) else 0.0,
            "travel_mrad": 1e3 * float(held.travel.max()) if len(held) else 0.0,
            "broke": bool(np.isfinite(first_bad))}


def main() -> None:
    table, family = family_table(__doc__, run_object)
    table["crept past half"] = (table.drift_held_mm > 2.5) | (table.turn_held_deg > 5.0)
    columns = ["robustness", "drift_held_mm", "turn_held_deg", "crept past half",
               "steps_per_level", "give_mrad", "travel_mrad"]
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        print(f"{table.object_id.nunique()} {family} objects, held trials by engine")
        print(table.groupby(["C1 third", "engine"], observed=True)[columns].mean().round(2)
              .to_string())
        print(table.groupby(["C1 third", "engine"], observed=True).size().to_string())


if __name__ == "__main__":
    main()
