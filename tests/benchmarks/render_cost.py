"""What a picture costs in each engine (run by hand):

    python -m tests.benchmarks.render_cost --frames 30

For each engine, the default rectangle is held by its best grip by Q_C (run without noise), and
the held scene is drawn ``--frames`` times at each frame size the toolkit uses: 320 x 240 (trial
strips), 360 x 270 (``grip-env show --sim``) and 400 x 400 (the environments' ``render()``).
Printed per frame: wall milliseconds and the process's CPU milliseconds (every thread: Mesa's
llvmpipe rasterises on several), and the first frame of a size apart (MuJoCo makes its OpenGL
context then). Last, the perception camera (``grip_env.sim.camera.render_mask``: PyBullet's
TinyRenderer, the same in both engines) at the default config, per object.
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

import argparse
import os
import platform
import time
from datetime import UTC, datetime

import numpy as np
import pandas as pd

from grip_env.config import Config
from grip_env.objects import load_object_set
from grip_env.planning.pipeline import candidates
from grip_env.sim.frames import CAMERA_OFFSET_MM
from grip_env.sim.trial import TrialScene, grip_plans
from grip_env.sim.uncertainty import zero_noise

SIZES = ((320, 240), (360, 270), (400, 400))


def _timed(draw: object, frames: int) -> tuple[float, float]:
    """Wall and CPU milliseconds per call of ``draw`` over ``frames`` calls."""
    wall, cpu = time.perf_counter(), time.process_time()
    for _ in range(frames):
        draw()  # type: ignore[operator]
    return ((time.perf_counter() - wall) * 1e3 / frames,
            (time.process_time() - cpu) * 1e3 / frames)


def engine_costs(engine: str, frames: int) -> list[dict[str, object]]:
    """Per frame size: the first frame's and a frame's wall and CPU ms, in ``engine``."""
    box = next(o for o in load_object_set("default") if o.name == "rectangle")
    grip = candidates(box).sort_values("Q_C", ascending=False, kind="stable").head(1)
    rows: list[dict[str, object]] = []

    def measure(phase: str, scene: TrialScene) -> None:
        if phase != "held":
            return
        target = np.array([*box.centroid, 60.0])
        eye = target + np.array(CAMERA_OFFSET_MM)
        for width, height in SIZES:
            first_wall, _ = _timed(
                lambda w=width, h=height: scene.world.render(eye, target, w, h), 1)
            wall, cpu = _timed(lambda w=width, h=height: scene.world.render(eye, target, w, h),
                               frames)
            rows.append({"engine": engine, "size": f"{width}x{height}",
                         "first_ms": round(first_wall, 1), "wall_ms": round(wall, 1),
                         "cpu_ms": round(cpu, 1)})

    with TrialScene(box, Config().override(sim={"engine": engine})) as scene:
        scene.run(grip_plans(pd.DataFrame(grip))[0], zero_noise(scene.config), on_phase=measure)
    return rows


def perception_cost(objects: int) -> dict[str, object]:
    """The perception camera's wall and CPU ms per object (default config, one world reused)."""
    from grip_env.sim.camera import render_mask
    from grip_env.sim.world import World

    chosen = load_object_set("default")[:objects]
    with World() as world:
        wall, cpu = time.perf_counter(), time.process_time()
        for obj in chosen:
            render_mask(obj, world=world)
        return {"objects": len(chosen),
                "wall_ms": round((time.perf_counter() - wall) * 1e3 / len(chosen), 1),
                "cpu_ms": round((time.process_time() - cpu) * 1e3 / len(chosen), 1)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--objects", type=int, default=8)
    args = parser.parse_args()
    print(f"{datetime.now(UTC):%Y-%m-%d %H:%M} UTC, {platform.processor() or platform.machine()},"
          f" {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.2f}")
    rows = [row for engine in ("pybullet", "mujoco") for row in engine_costs(engine, args.frames)]
    print(pd.DataFrame(rows).to_string(index=False))
    print("perception camera (PyBullet's TinyRenderer, either engine):",
          perception_cost(args.objects))


if __name__ == "__main__":
    main()
