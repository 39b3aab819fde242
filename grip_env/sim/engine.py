"""The engine seam: what the trial protocol asks of a physics engine, and how one is chosen.

The protocol (``grip_env.sim.trial``, ``hand``, ``disturbance``) is written once against
:class:`Engine`; each engine is one module that satisfies it: PyBullet's ``World``
(``grip_env.sim.world``, the default and the standard dataset's) and MuJoCo's ``MujocoWorld``
(``grip_env.sim.mujoco_world``, the optional extra ``grip-env[mujoco]``). ``sim.engine`` in the
config picks one; :func:`make_world` builds it.

Geometry crosses the seam in millimetres; bodies are integer ids and links PyBullet's indices
(-1 the base, then the joints in the URDF's order), which every engine keeps.
"""

from __future__ import annotations

import importlib
import importlib.util
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np
from numpy.typing import NDArray

from grip_env.config import ENGINES
from grip_env.sim.body import Body

if TYPE_CHECKING:
    from grip_env.config import SimConfig
    from grip_env.objects import PlanarObject

#: The Python package each engine needs, and how to install it.
_PACKAGES = {"pybullet": "pybullet", "mujoco": "mujoco"}
#: The module of grip_env that wraps each engine (importing it loads the engine, quietly).
_MODULES = {"pybullet": "grip_env.sim.world", "mujoco": "grip_env.sim.mujoco_world"}
_INSTALL = {"pybullet": "pip install grip-env", "mujoco": 'pip install "grip-env[mujoco]"'}

Pose = tuple[tuple[float, float, float], tuple[float, float, float, float]]


class EngineUnavailable(ValueError):
    """``sim.engine`` names an engine whose package is not installed."""


class Engine(Protocol):
    """One headless physics world, as the trial protocol uses it (``World`` is the reference:
    its docstrings give each method's contract)."""

    timestep: float
    #: Whether ``resume`` continues a saved moment bit for bit, so that the ramp's directions
    #: can climb together (``grip_env.sim.disturbance``).
    resumes_exactly: bool

    def step(self, steps: int = 1) -> None: ...
    def close(self) -> None: ...
    def add_table(self, friction: float = 0.5, half_size_mm: float = 500.0) -> Body: ...
    def add_object(self, obj: PlanarObject, thickness_mm: float = 30.0, mass_kg: float = 0.3,
                   friction: float = 0.5, rgba: tuple[float, float, float, float] = ...,
                   tolerance_mm: float = ...) -> Body: ...
    def add_mesh(self, path: str | Path, scale: float, com_mm: NDArray[np.float64],
                 position_mm: NDArray[np.float64], orientation: tuple[float, float, float, float],
                 mass_kg: float, friction: float, inertia_per_kg: tuple[float, float, float],
                 axes: tuple[float, float, float, float] = ...,
                 rgba: tuple[float, float, float, float] = ...) -> Body: ...
    def add_sphere(self, radius_mm: float, mass_kg: float, friction: float,
                   position_mm: NDArray[np.float64], inertia_kg_m2: float | None = None,
                   rgba: tuple[float, float, float, float] = ...) -> Body: ...
    def set_dynamics(self, body: Body, mass_kg: float, friction: float,
                     spinning_friction: float = 0.0) -> None: ...
    def pose_mm(self, body: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...
    def pose_floats_mm(self, body: int) -> Pose: ...
    def load_robot(self, urdf: str | Path) -> int: ...
    def link_count(self, body: int) -> int: ...
    def link_pose_floats_mm(self, body: int, link: int) -> Pose: ...
    def add_axis_inertia(self, body: int, link: int, axis: int, inertia_kg_m2: float) -> None: ...
    def set_pad_friction(self, body: int, link: int, lateral: float,
                         torsion_mm: float) -> None: ...
    def set_contact_compliance(self, body: int, link: int, stiffness_n_per_m: float,
                               damping_n_s_per_m: float) -> None: ...
    def set_joint(self, body: int, joint: int, position: float) -> None: ...
    def velocity_motors(self, body: int, joints: list[int], speeds: list[float],
                        torques: list[float]) -> None: ...
    def position_motors(self, body: int, joints: list[int], targets: list[float],
                        torques: list[float], gain: float | None = None) -> None: ...
    def joint_floors(self, body: int, joints: list[int], lowers: list[float],
                     uppers: list[float], holds: list[float]) -> None: ...
    def joint_limits(self, body: int, joint: int) -> tuple[float, float]: ...
    def joint_states(self, body: int, joints: list[int]) -> tuple[
        NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]: ...
    def joint_positions_velocities(self, body: int,
                                   joints: list[int]) -> tuple[list[float], list[float]]: ...
    def joint_positions(self, body: int, joints: list[int]) -> list[float]: ...
    def touching_links(self, body: int, other: int) -> set[int]: ...
    def contact_normal_force_n(self, body: int, other: int) -> float: ...
    def set_gravity(self, gravity: tuple[float, float, float]) -> None: ...
    def save(self) -> int: ...
    def restore(self, state: int) -> None: ...
    def pause(self) -> int: ...
    def resume(self, state: int) -> None: ...
    def forget(self, state: int) -> None: ...
    def push(self, body: int, force_n: NDArray) -> None: ...
    def twist(self, body: int, torque_nm: NDArray) -> None: ...
    def set_colour(self, body: Body, rgba: tuple[float, float, float, float]) -> None: ...
    def render(self, eye_mm: NDArray[np.float64], target_mm: NDArray[np.float64],
               width: int = 320, height: int = 240,
               fov_deg: float = 50.0) -> NDArray[np.uint8]: ...


def require_engine(name: str) -> None:
    """Check that engine ``name`` is known and installed.

    Raises:
        ValueError: an unknown engine.
        EngineUnavailable: its package is not installed or cannot be imported (the message
            says how to install it).
    """
    if name not in ENGINES:
        raise ValueError(f"unknown engine {name!r}: sim.engine is one of {', '.join(ENGINES)}")
    package = _PACKAGES[name]
    if importlib.util.find_spec(package) is None:
        raise EngineUnavailable(f"engine {name!r} is not installed: {_INSTALL[name]}")
    try:  # installed but unloadable (a missing shared library, a wheel of another Python, or
        # MuJoCo's MUJOCO_GL naming a platform it cannot load: it loads it with itself)
        importlib.import_module(_MODULES[name])
    except (ImportError, RuntimeError, AttributeError, OSError) as exc:
        raise EngineUnavailable(f"engine {name!r} is installed but cannot be loaded ("
                                f"{type(exc).__name__}: {exc}): reinstall it: "
                                f"{_INSTALL[name]}") from None


def make_world(config: SimConfig) -> Engine:
    """A new world of ``config.engine`` with the config's timestep and solver iterations.

    Raises:
        ValueError: an unknown engine, or one that is not installed (``require_engine``).
    """
    require_engine(config.engine)
    if config.engine == "mujoco":
        from grip_env.sim.mujoco_world import MujocoWorld

        return MujocoWorld(timestep=config.timestep, solver_iterations=config.solver_iterations)
    from grip_env.sim.world import World

    return World(timestep=config.timestep, solver_iterations=config.solver_iterations)
