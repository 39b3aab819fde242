"""Drawing an episode: the object's contour, its candidate contact triangles, the chosen one.

``draw_candidates`` renders off-screen with matplotlib's Agg canvas (no pyplot, no display) into a
fixed-size ``uint8`` RGB array. :class:`HumanWindow` shows such frames in a matplotlib window when a
display exists and does nothing (one warning) when headless.
"""

from __future__ import annotations

import os
import sys

import numpy as np
from gymnasium import logger
from numpy.typing import NDArray

FRAME_SIZE_PX = 400
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
