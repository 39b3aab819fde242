"""The simulator's faithfulness checks in every engine: every finger touches, the close settles,
the worm gear holds loaded fingers where they closed.

More checks on PyBullet's own client (contact points, each pad's force on a pinned box) are in
``tests/test_sim_fidelity.py``; these go through the engine seam only, so they run in MuJoCo too.
"""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from grip_env.config import Config
from grip_env.sim import TrialScene

NO_MUJOCO = pytest.mark.skipif(importlib.util.find_spec("mujoco") is None,
                               reason="mujoco not installed")
ENGINES = ["pybullet", pytest.param("mujoco", marks=NO_MUJOCO)]


def _config(engine: str) -> Config:
    return Config().override(sim={"engine": engine})


@pytest.fixture(scope="module", params=ENGINES)
def best_grips(request) -> dict[str, object]:
    """One zero-noise trial of each default object's three best grips by Q_C in one engine:
    outcomes, which fingers touch after the close, and each trial's largest slip of a flexion
    joint below its worm gear's floor after the hold (mrad)."""
    from tests.benchmarks.sim_fidelity import best_grip_trials

    engine = request.param
    touching: list[np.ndarray] = []
    slips: list[float] = []

    def on_phase(name: str, scene: TrialScene) -> None:
        if name == "closed":
            touching.append(scene.hand.touching(scene.object.uid).any(axis=1))
        if name == "held":
            q, _ = scene.hand.joint_states()
            slips.append(1e3 * float((np.reshape(scene.hand.state().peak, (3, 2)) - q).max()))

    results = best_grip_trials(_config(engine), on_phase)
    return {"engine": engine, "results": results, "touching": np.array(touching),
            "slips": np.array(slips)}


@pytest.mark.slow
def test_every_finger_touches_after_the_close(best_grips):
    assert len(best_grips["touching"]) >= 40
    assert best_grips["touching"].all(axis=1).mean() >= 0.95


@pytest.mark.slow
def test_the_close_settles_before_the_cap(best_grips):
    cap = Config().sim.max_close_steps
    settled = [r.close_steps < cap for r in best_grips["results"]]
    assert len(settled) >= 40 and np.mean(settled) >= 0.95


@pytest.mark.slow
def test_loaded_fingers_hold_where_they_closed(best_grips):
    """The worm gear: after the lift no flexion joint sits more than 1 mrad below its floor (in
    MuJoCo since its constants are renewed after the rotor inertia is added: 8 mrad before)."""
    assert len(best_grips["slips"]) >= 40 and best_grips["slips"].max() <= 1.0
