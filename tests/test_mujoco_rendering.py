"""MuJoCo's pictures: its own OpenGL renderer (headless through EGL) draws the world where MuJoCo
simulates it, the same bits every time."""

from __future__ import annotations

import ctypes.util
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.path import Path as Polygon
from scipy.spatial import ConvexHull

from grip_env.config import Config
from grip_env.objects import load_object_set
from grip_env.planning.pipeline import candidates
from grip_env.sim.frames import OBJECT_COLOUR
from grip_env.sim.trial import TrialScene, grip_plans
from grip_env.sim.uncertainty import zero_noise

pytest.importorskip("mujoco")

from grip_env.sim.mujoco_world import MujocoWorld

HERE = Path(__file__).resolve().parent

#: MuJoCo draws through OpenGL: headless, EGL's libraries (Mesa's llvmpipe will do) must be there.
needs_opengl = pytest.mark.skipif(
    ctypes.util.find_library("EGL") is None and not os.environ.get("DISPLAY"),
    reason="no OpenGL here: MuJoCo renders headless through EGL (apt install libegl1 libgl1 "
           "libgl1-mesa-dri)")
MUJOCO = Config().override(sim={"engine": "mujoco"})


def _rectangle():
    return next(o for o in load_object_set("default") if o.name == "rectangle")


def _project(points_mm: np.ndarray, eye_mm: np.ndarray, target_mm: np.ndarray, width: int,
             height: int, fov_deg: float) -> np.ndarray:
    """(column, row) of world points in a pinhole camera at ``eye`` looking at ``target``, z up,
    vertical field of view ``fov_deg``, in pixel indices (pixel (r, c)'s centre is at (c, r))."""
    forward = (target_mm - eye_mm) / np.linalg.norm(target_mm - eye_mm)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    view = np.atleast_2d(points_mm) - eye_mm
    depth = view @ forward
    focal = (height / 2) / np.tan(np.radians(fov_deg) / 2)
    column = width / 2 + focal * (view @ right) / depth - 0.5
    row = height / 2 - focal * (view @ up) / depth - 0.5
    return np.stack([column, row], axis=1)


def _object_pixels(frame: np.ndarray) -> np.ndarray:
    """Where the frame shows the object's colour, lit or in shade: blue above red and green (not
    the white table, nor the black, grey and dark red hand)."""
    rgb = frame.astype(int)
    return (rgb[..., 2] - rgb[..., 0] > 30) & (rgb[..., 2] - rgb[..., 1] > 15)


def _centroid(mask: np.ndarray) -> np.ndarray:
    rows, columns = np.nonzero(mask)
    return np.array([columns.mean(), rows.mean()])


@pytest.mark.parametrize(("eye_offset_mm", "least_overlap", "most_shift_px"), [
    ((0.5, -0.5, 2000.0), 0.97, 0.05),  # from straight above: the top face alone
    ((150.0, -250.0, 2000.0), 0.97, 0.3),  # obliquely: two side faces too, in shade
])
@needs_opengl
def test_a_resting_box_is_drawn_on_its_outline_to_a_pixel(eye_offset_mm, least_overlap,
                                                           most_shift_px):
    """Seen from 2 m, the box's silhouette is the projection of its simulated prism, its centre
    within a fraction of a pixel (partly covered edge pixels count as the object, so the overlap
    is short of 1 by about half the outline's pixels); the camera looks beside the box, so a
    turned or mirrored view would miss it."""
    obj, thickness = _rectangle(), 30.0
    width = height = 200
    fov = 6.0
    with MujocoWorld() as world:
        world.add_table()
        body = world.add_object(obj, thickness_mm=thickness)
        world.set_colour(body, OBJECT_COLOUR)
        position, _ = world.pose_mm(body.uid)
        target = position + np.array([25.0, 10.0, 0.0])
        eye = target + np.array(eye_offset_mm)
        frame = world.render(eye, target, width, height, fov)
    assert frame.shape == (height, width, 3) and frame.dtype == np.uint8
    corners = np.vstack([np.column_stack([obj.contour, np.full(len(obj.contour), z)])
                         for z in (0.0, thickness)])
    projected = _project(corners, eye, target, width, height, fov)
    outline = Polygon(projected[ConvexHull(projected).vertices])
    rows, columns = np.mgrid[:height, :width]
    expected = outline.contains_points(np.column_stack([columns.ravel(), rows.ravel()]))
    expected = expected.reshape(height, width)
    drawn = _object_pixels(frame)
    overlap = (drawn & expected).sum() / (drawn | expected).sum()
    assert expected.sum() > 2000  # the box fills a good part of the frame
    assert overlap > least_overlap, overlap
    assert np.abs(_centroid(drawn) - _centroid(expected)).max() < most_shift_px


#: A fixed camera on the held object, from the side and a little above (mm).
TARGET = np.array([*_rectangle().centroid, 60.0])
EYE = TARGET + np.array([0.0, -600.0, 120.0])


@pytest.fixture(scope="module")
def held() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The best grip by Q_C of the rectangle, run in MuJoCo without noise: at the end of the
    close and after the lift, a frame from a fixed camera and the object's pose."""
    obj = _rectangle()
    grip = candidates(obj).sort_values("Q_C", ascending=False, kind="stable").head(1)
    seen: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    def capture(phase: str, scene: TrialScene) -> None:
        if phase in ("closed", "held"):
            scene.world.set_colour(scene.object, OBJECT_COLOUR)
            position, _ = scene.world.pose_mm(scene.object.uid)
            seen[phase] = (scene.world.render(EYE, TARGET, 320, 240, 30.0), position)

    with TrialScene(obj, MUJOCO) as scene:
        result = scene.run(grip_plans(pd.DataFrame(grip))[0], zero_noise(scene.config),
                           on_phase=capture)
    assert result.lifted_mm > 40  # held through the lift: the picture is of a held object
    return seen



@needs_opengl
def test_a_held_object_is_drawn_where_mujoco_says_it_is(held):
    for phase, (frame, position) in held.items():
        drawn = _object_pixels(frame)
        assert drawn.sum() > 200, phase  # the fingers hide some of it, not all
        expected = _project(position, EYE, TARGET, 320, 240, 30.0)[0]
        # the visible part's centre, beside the centre of mass (fingers cover parts of it)
        assert np.linalg.norm(_centroid(drawn) - expected) < 8.0, phase
    (closed, before), (lifted, after) = held["closed"], held["held"]
    moved = (_project(after, EYE, TARGET, 320, 240, 30.0)
             - _project(before, EYE, TARGET, 320, 240, 30.0))[0]
    assert moved[1] < -15  # lifted: up the picture
    shift = _centroid(_object_pixels(lifted)) - _centroid(_object_pixels(closed))
    assert np.linalg.norm(shift - moved) < 2.0, (shift, moved)


def _frame_of_a_fresh_world() -> np.ndarray:
    obj = _rectangle()
    with MujocoWorld() as world:
        world.add_table()
        world.add_object(obj)
        centre = np.array([*obj.centroid, 15.0])
        return world.render(centre + np.array([180.0, -230.0, 180.0]), centre)


@needs_opengl
def test_frames_are_the_same_bits_every_time():
    obj = _rectangle()
    with MujocoWorld() as world:
        world.add_table()
        world.add_object(obj)
        centre = np.array([*obj.centroid, 15.0])
        eye = centre + np.array([180.0, -230.0, 180.0])
        first = world.render(eye, centre)
        other_size = world.render(eye, centre, 100, 80)  # a second renderer in the same world
        again = world.render(eye, centre)
    assert other_size.shape == (80, 100, 3)
    assert np.array_equal(first, again)
    assert np.array_equal(first, _frame_of_a_fresh_world())
    script = ("import numpy as np; from test_mujoco_rendering import _frame_of_a_fresh_world; "
              "import sys; sys.stdout.buffer.write(_frame_of_a_fresh_world().tobytes())")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, cwd=HERE,
                          check=True, timeout=300)
    assert done.stdout == first.tobytes()  # in a fresh process too


def test_a_bad_camera_is_refused_by_value():
    with MujocoWorld() as world:
        world.add_table()
        with pytest.raises(ValueError, match="0 x 240"):
            world.render(np.array([0.0, 0.0, 100.0]), np.zeros(3), width=0)
        with pytest.raises(ValueError, match="same point"):
            world.render(np.zeros(3), np.zeros(3))


def test_without_opengl_rendering_says_what_to_install():
    """A headless machine asked for GLFW (MuJoCo's default, which needs a display): one line
    naming the EGL packages; the physics is untouched."""
    script = ("import numpy as np; from test_mujoco_rendering import _frame_of_a_fresh_world\n"
              "try:\n    _frame_of_a_fresh_world()\nexcept ValueError as exc:\n"
              "    print('refused:', exc)\n")
    environment = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          cwd=HERE, env={**environment, "MUJOCO_GL": "glfw"}, check=True,
                          timeout=300)
    [line] = [line for line in done.stdout.splitlines() if line.startswith("refused:")]
    assert "MuJoCo cannot render here" in line and "MUJOCO_GL=glfw" in line
    assert "apt install libegl1" in line


@needs_opengl
def test_an_environment_in_mujoco_renders_its_scene():
    import gymnasium

    import grip_env.envs  # noqa: F401  (registers the environments)

    env = gymnasium.make("GripSelect-v0", objects=["rectangle"], engine="mujoco",
                         render_mode="rgb_array", max_candidates=4)
    env.reset(seed=0)
    before = env.render()
    env.step(0)
    after = env.render()
    env.close()
    for frame in (before, after):
        assert frame.shape == (400, 400, 3) and frame.dtype == np.uint8
        assert _object_pixels(frame).sum() == 0  # the scene's object is dark grey, not blue
        assert frame.std() > 20  # a scene, not a blank
    assert not np.array_equal(before, after)  # the hand holds the chosen grip


def test_a_mujoco_gl_that_breaks_mujoco_s_import_is_refused_in_one_line():
    """MuJoCo loads the OpenGL platform MUJOCO_GL names when it is imported, and a bad one breaks
    that import: the engine is refused, naming it, not a traceback."""
    script = ("from grip_env.sim.engine import EngineUnavailable, require_engine\n"
              "try:\n    require_engine('mujoco')\nexcept EngineUnavailable as exc:\n"
              "    print('refused:', exc)\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          cwd=HERE, env={**os.environ, "MUJOCO_GL": "bogus"}, check=True,
                          timeout=300)
    [line] = [line for line in done.stdout.splitlines() if line.startswith("refused:")]
    assert "engine 'mujoco' is installed but cannot be loaded" in line
    assert "MUJOCO_GL: bogus" in line


@needs_opengl
def test_show_draws_a_trial_in_mujoco(tmp_path):
    """``grip-env show --sim`` runs and draws the trial in the config's engine, and says which: the
    two engines' frames differ (MuJoCo's background is black, PyBullet's grey)."""
    from cli_runs import cli
    from PIL import Image

    outcomes = {}
    for engine in ("mujoco", "pybullet"):
        config = tmp_path / f"{engine}.yaml"
        config.write_text(f"sim:\n  engine: {engine}\n")
        out = tmp_path / f"{engine}.png"
        code, output = cli("show", "rectangle", "--sim", "--config", config, "--out", out)
        assert code == 0, output
        assert Image.open(out).size[0] > 1000  # four phases side by side
        [line] = [line for line in output.splitlines() if line.startswith("trial of")]
        assert f" in {engine}: " in line
        outcomes[engine] = np.asarray(Image.open(out).convert("RGB"))
    assert outcomes["mujoco"].shape == outcomes["pybullet"].shape
    assert not np.array_equal(outcomes["mujoco"], outcomes["pybullet"])
