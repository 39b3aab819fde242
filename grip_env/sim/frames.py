"""Pictures of trials: camera frames of each phase a trial reaches, and a PNG strip of them.

The camera watches; it never changes a trial: the frames are rendered between steps, and the
object is painted (its look only), so a pictured trial's outcome is the unpictured one's.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from grip_env.config import Config
from grip_env.objects import PlanarObject
from grip_env.sim.execution import grip_keys, object_key
from grip_env.sim.trial import GripPlan, TrialResult, TrialScene, grip_plans
from grip_env.sim.uncertainty import trial_noises

STRIP_PHASES = ("approach", "closed", "held")
#: The object's colour in pictures of a trial, apart from the hand (black, grey, dark red) and
#: the white table.
OBJECT_COLOUR = (0.2, 0.55, 0.95, 1.0)
#: Where a trial's camera stands, from the point it looks at (mm): above and to one side.
CAMERA_OFFSET_MM = (180.0, -230.0, 180.0)


def trial_frames(
    obj: PlanarObject, grips: pd.DataFrame, config: Config | None = None, seed: int = 0,
    width: int = 320, height: int = 240,
) -> list[tuple[TrialResult, dict[str, NDArray[np.uint8]]]]:
    """Run one trial of each grip (rows of a candidate table) and picture every phase it reached.

    Each trial is trial 0 of ``run_trial_outcomes(obj, grips, config, seed=seed)``: the same
    draw, so the same outcome. Returns, per grip, its result and its frames by phase name
    (``TRIAL_PHASES``; no ``"ramp"`` when the object was not held), seen obliquely from the side
    with the object painted ``OBJECT_COLOUR``.
    """
    plans = grip_plans(grips)
    out: list[tuple[TrialResult, dict[str, NDArray[np.uint8]]]] = []
    with TrialScene(obj, config) as scene:
        noises = trial_noises(scene.config, seed, object_key(obj, grips), grip_keys(grips), [0])
        for plan, (noise,) in zip(plans, noises, strict=True):
            camera = _TrialCamera(plan, width, height)
            out.append((scene.run(plan, noise, on_phase=camera.capture), camera.frames))
    return out


class _TrialCamera:
    """Frames of one trial from one fixed view (so the lift shows), the object painted."""

    def __init__(self, plan: GripPlan, width: int, height: int) -> None:
        self.plan, self.width, self.height = plan, width, height
        self.frames: dict[str, NDArray[np.uint8]] = {}
        self.target: NDArray[np.float64] | None = None

    def capture(self, phase: str, scene: TrialScene) -> None:
        scene.world.set_colour(scene.object, OBJECT_COLOUR)
        if self.target is None:  # halfway up the hand after the approach, plus half the lift
            palm, _ = scene.hand.palm_pose_mm()
            rise = 0.5 * (palm[2] + scene.config.sim.lift_height_mm)
            self.target = np.array([*self.plan.palm_mm, rise])
        eye = self.target + np.array(CAMERA_OFFSET_MM)
        self.frames[phase] = scene.world.render(eye, self.target, self.width, self.height)


def render_trial_strip(
    obj: PlanarObject, grip: pd.Series | dict, config: Config | None = None, seed: int = 0,
    path: str | Path = "trial.png", width: int = 320, height: int = 240,
) -> TrialResult:
    """Run one trial of ``grip`` (a candidate row) and write a PNG strip of its phases.

    Frames: approach, closed, held after the lift (``STRIP_PHASES``), seen obliquely from the
    side; the trial is trial 0 of ``run_trial_outcomes`` (see :func:`trial_frames`). Returns the
    result.
    """
    from PIL import Image

    [(result, frames)] = trial_frames(obj, pd.DataFrame([dict(grip)]), config, seed, width,
                                      height)
    Image.fromarray(np.concatenate([frames[name] for name in STRIP_PHASES], axis=1)).save(
        Path(path))
    return result
