"""Off-screen frames of a MuJoCo model: ``MujocoWorld.render``'s camera and OpenGL context.

MuJoCo's own ``mujoco.Renderer`` takes the OpenGL platform ``MUJOCO_GL`` named when ``mujoco``
was imported; here the platform is picked when the first frame is asked for: EGL when headless
on Linux and its libraries are installed (Mesa's software rasteriser draws without a GPU), and a
one-line error naming what to install when no context can be made.
"""

from __future__ import annotations

import functools
import math
import os
import sys
from ctypes.util import find_library

import mujoco
import numpy as np
from numpy.typing import NDArray


def look_at(eye_m: NDArray[np.float64], target_m: NDArray[np.float64]) -> mujoco.MjvCamera:
    """MuJoCo's free camera at ``eye_m`` looking at ``target_m`` (metres), z up: MuJoCo places it
    at ``lookat - distance (cos e cos a, cos e sin a, sin e)`` for azimuth a, elevation e."""
    view = target_m - eye_m
    distance = float(np.linalg.norm(view))
    if distance == 0.0:
        raise ValueError("the camera's eye and target are the same point")
    camera = mujoco.MjvCamera()
    camera.type = mujoco.mjtCamera.mjCAMERA_FREE
    camera.lookat[:] = target_m
    camera.distance = distance
    camera.azimuth = math.degrees(math.atan2(view[1], view[0]))
    camera.elevation = math.degrees(math.asin(np.clip(view[2] / distance, -1.0, 1.0)))
    return camera


class Renderer:
    """Off-screen frames of one model at one size: ``mujoco.Renderer``'s steps, in an OpenGL
    context of the platform ``_gl_platform`` picks when the first frame is asked for (MuJoCo's
    own renderer takes the platform ``MUJOCO_GL`` named when ``mujoco`` was imported)."""

    def __init__(self, m: mujoco.MjModel, width: int, height: int) -> None:
        self.width, self.height = width, height
        platform = _gl_platform()
        try:
            self._gl = _gl_context_class(platform)(width, height)
            self._gl.make_current()
            m.vis.global_.offwidth = max(m.vis.global_.offwidth, width)
            m.vis.global_.offheight = max(m.vis.global_.offheight, height)
            self._context = mujoco.MjrContext(m, mujoco.mjtFontScale.mjFONTSCALE_150)
        except Exception as exc:  # each OpenGL platform fails its own way
            raise ValueError(_no_opengl(platform, exc)) from None
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._context)
        self._scene = mujoco.MjvScene(m, maxgeom=10_000)
        self._option = mujoco.MjvOption()
        self._rect = mujoco.MjrRect(0, 0, width, height)
        m.vis.headlight.ambient[:] = 0.35  # a white table reads white (MuJoCo's default, 0.1
        m.vis.headlight.diffuse[:] = 0.65  # ambient and 0.4 diffuse, draws it dark grey)

    def frame(self, m: mujoco.MjModel, d: mujoco.MjData,
              camera: mujoco.MjvCamera) -> NDArray[np.uint8]:
        """The RGB frame of ``d`` seen by ``camera``, row 0 at the top."""
        self._gl.make_current()
        mujoco.mjv_updateScene(m, d, self._option, None, camera, mujoco.mjtCatBit.mjCAT_ALL,
                               self._scene)
        mujoco.mjr_render(self._rect, self._scene, self._context)
        rgb = np.empty((self.height, self.width, 3), np.uint8)
        mujoco.mjr_readPixels(rgb, None, self._rect, self._context)
        return np.flipud(rgb).copy()

    def close(self) -> None:
        """Free the MuJoCo and OpenGL contexts."""
        self._gl.make_current()
        self._context.free()
        self._gl.free()


#: The system packages of off-screen EGL rendering, Mesa's software rasteriser among them
#: (Debian and Ubuntu names).
EGL_PACKAGES = "libegl1 libgl1 libgl1-mesa-dri"


def _gl_platform() -> str:
    """The OpenGL platform of MuJoCo's frames: ``MUJOCO_GL`` when set; else EGL (off-screen, on
    a GPU or Mesa's software rasteriser) on Linux without a display, when its libraries are
    installed; else MuJoCo's default (GLFW, which needs a display, on Linux)."""
    chosen = os.environ.get("MUJOCO_GL", "").lower().strip()
    headless = not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    if not chosen and sys.platform.startswith("linux") and headless and _egl_installed():
        return "egl"
    return chosen or "default"


@functools.cache
def _egl_installed() -> bool:
    """Whether the EGL and OpenGL libraries MuJoCo's EGL platform loads are installed."""
    return bool(find_library("EGL") and (find_library("OpenGL") or find_library("GL")))


def _gl_context_class(platform: str) -> type:
    """The ``GLContext`` of ``platform`` (imported now: importing one whose libraries are
    missing fails)."""
    if platform == "egl":
        from mujoco.egl import GLContext
    elif platform == "osmesa":
        from mujoco.osmesa import GLContext
    else:
        from mujoco.gl_context import GLContext
    return GLContext


def _no_opengl(platform: str, exc: Exception) -> str:
    """Why MuJoCo cannot render here, and what to install, in one line."""
    if platform == "default":
        platform = "glfw, MuJoCo's default, which needs a display"
    reason = " ".join(f"{type(exc).__name__}: {exc}".split())[:200]
    return (f"MuJoCo cannot render here: no OpenGL context with MUJOCO_GL={platform} ({reason}); "
            f"headless, install EGL (e.g. apt install {EGL_PACKAGES}) and unset MUJOCO_GL or "
            f"set it to egl")
