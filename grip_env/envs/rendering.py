"""Drawing an episode: the simulated scene, or a 2-D sketch of the candidates.

Two styles, both fixed-size ``uint8`` RGB frames:

- ``"scene"`` (:class:`SceneCamera`): the scene in the config's engine, drawn by that engine
  (PyBullet: its TinyRenderer on the CPU; MuJoCo: its OpenGL renderer, off-screen through EGL, in
  Mesa's software rasteriser without a GPU; neither needs a display), seen obliquely: table,
  object and Barrett hand; with a chosen grip, the hand holding it
  at the end of a noise-free execution (the episode's own trial had noise: its outcome colours the
  sketch's highlight and the env's ``info``, not this picture).
- ``"sketch"`` (:func:`draw_candidates`): the object's contour, every candidate's contact triangle
  and the chosen one highlighted, drawn with matplotlib's Agg canvas (no pyplot, no display).

:class:`HumanWindow` shows frames in a matplotlib window when a display exists and does nothing
(one warning) when headless.
"""

from __future__ import annotations

import os
import sys
from typing import TYPE_CHECKING, Any

import numpy as np
from gymnasium import logger
from numpy.typing import NDArray

if TYPE_CHECKING:
    import pandas as pd

    from grip_env.config import Config
    from grip_env.objects import PlanarObject

RENDER_STYLES: tuple[str, ...] = ("scene", "sketch")
FRAME_SIZE_PX = 400
_CAMERA_OFFSET_MM = np.array([300.0, -300.0, 220.0])
_DPI = 100
_HIGHLIGHT = {None: "tab:blue", True: "tab:green", False: "tab:red"}


def draw_candidates(
    contour: NDArray[np.float64] | None,
    contacts: NDArray[np.float64],
    chosen: int | None = None,
    outcome: bool | None = None,
    title: str = "",
    size_px: int = FRAME_SIZE_PX,
) -> NDArray[np.uint8]:
    """An RGB frame (size_px, size_px, 3) of a contour and contact triangles.

    Args:
        contour: (N, 2) object contour in mm, or None to draw the triangles alone.
        contacts: (n, 3, 2) contact points P1..P3 of the candidates in mm.
        chosen: index into ``contacts`` to highlight (None: no highlight).
        outcome: colour of the highlight: green success, red failure, blue not executed.
        title: text above the drawing.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import PolyCollection
    from matplotlib.figure import Figure

    figure = Figure(figsize=(size_px / _DPI, size_px / _DPI), dpi=_DPI)
    canvas = FigureCanvasAgg(figure)
    axes = figure.add_axes((0.02, 0.02, 0.96, 0.90))
    axes.set_aspect("equal")
    axes.set_axis_off()
    if contour is not None:
        axes.fill(contour[:, 0], contour[:, 1], facecolor="0.8", edgecolor="0.2", linewidth=1.5)
    if len(contacts):
        axes.add_collection(PolyCollection(
            contacts, closed=True, facecolors="none", edgecolors="0.45", linewidths=0.6, alpha=0.6
        ))
    if chosen is not None:
        colour = _HIGHLIGHT[outcome]
        axes.add_collection(PolyCollection(
            contacts[chosen:chosen + 1], closed=True, facecolors=colour, edgecolors=colour,
            linewidths=2.5, alpha=0.5,
        ))
        axes.plot(*contacts[chosen].T, "o", color=colour, markersize=6)
    _frame_limits(axes, contour, contacts)
    figure.suptitle(title, fontsize=9)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()


def _frame_limits(axes: object, contour: NDArray | None, contacts: NDArray) -> None:
    points = [p.reshape(-1, 2) for p in (contour, contacts) if p is not None and len(p)]
    if not points:
        return
    stacked = np.vstack(points)
    low, high = stacked.min(axis=0), stacked.max(axis=0)
    centre, half = (low + high) / 2, max(float((high - low).max()) / 2, 1.0) * 1.1
    axes.set_xlim(centre[0] - half, centre[0] + half)
    axes.set_ylim(centre[1] - half, centre[1] + half)


class SceneCamera:
    """Frames of the scene of one object at a time, in the config's engine (its world is kept
    between frames)."""

    def __init__(self, config: Config, size_px: int = FRAME_SIZE_PX) -> None:
        self._config = config
        self._size = size_px
        self._scene: Any = None
        self._name: str | None = None

    def frame(self, obj: PlanarObject, grip: pd.Series | None = None) -> NDArray[np.uint8]:
        """The scene of ``obj``: the hand above it, or holding ``grip`` (a candidate row)."""
        scene = self._scene_of(obj)
        frames: list[NDArray[np.uint8]] = []

        def capture(phase: str, current: Any) -> None:
            if phase == "ramp":  # the hold is the picture; the ramp leaves the object pushed
                return
            palm, _ = current.hand.palm_pose_mm()
            frames.append(self._shot(current, np.array([*palm[:2], 0.5 * palm[2]])))

        if grip is not None:
            import pandas as pd

            from grip_env.sim import grip_plans
            from grip_env.sim.uncertainty import zero_noise

            try:
                plan = grip_plans(pd.DataFrame([dict(grip)]))[0]
                scene.run(plan, zero_noise(scene.config), on_phase=capture)
            except ValueError as exc:  # out of the hand's reach: show the scene as it is
                logger.warn(f"cannot show grip {grip.get('grip_id')!r} in the scene: {exc}")
        if frames:
            return frames[-1]
        return self._shot(scene, np.array([*obj.centroid, 0.5 * self._config.objects.thickness_mm]))

    def _scene_of(self, obj: PlanarObject) -> Any:
        if self._scene is None or self._name != obj.name:
            from grip_env.sim import TrialScene

            self.close()
            self._scene, self._name = TrialScene(obj, self._config), obj.name
        return self._scene

    def _shot(self, scene: Any, target_mm: NDArray[np.float64]) -> NDArray[np.uint8]:
        eye = target_mm + _CAMERA_OFFSET_MM
        return scene.world.render(eye, target_mm, self._size, self._size)

    def close(self) -> None:
        """Release the world (idempotent)."""
        if self._scene is not None:
            self._scene.close()
            self._scene, self._name = None, None


def display_available() -> bool:
    """Whether a window can be opened (macOS, Windows, or an X11/Wayland display)."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


class HumanWindow:
    """A matplotlib window showing frames; a no-op with one warning when headless."""

    def __init__(self, fps: float) -> None:
        self._fps = fps
        self._figure = None
        self._image = None
        self._enabled = display_available()
        if not self._enabled:
            logger.warn("render_mode='human' needs a display; none found, so nothing is shown")

    def show(self, frame: NDArray[np.uint8]) -> None:
        """Draw ``frame`` in the window (opening it on first use)."""
        if not self._enabled:
            return
        import matplotlib.pyplot as plt

        if self._figure is None or not plt.fignum_exists(self._figure.number):
            self._figure = plt.figure("grip-env")
            axes = self._figure.add_axes((0, 0, 1, 1))
            axes.set_axis_off()
            self._image = axes.imshow(frame)
            plt.show(block=False)
        else:
            self._image.set_data(frame)
        self._figure.canvas.draw_idle()
        plt.pause(1.0 / self._fps)

    def close(self) -> None:
        """Close the window (idempotent)."""
        if self._figure is not None:
            import matplotlib.pyplot as plt

            plt.close(self._figure)
            self._figure = None
