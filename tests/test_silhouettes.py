"""Every object is simulated whole: its collision body and its render are the object (issue 21).

Objects come from every source: the named sets, procedural shapes, masks, image files, and two
real silhouettes no one here drew (``tests/data/teddy.png``, ``duck.png``: meshes shipped with
``pybullet_data`` projected top-down, see ``tests/data/mesh_silhouette.py``).
"""

from __future__ import annotations

from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pybullet
import pytest
from PIL import Image
from scipy import ndimage
from typer.testing import CliRunner

from grip_env.cli import _register_commands, app
from grip_env.config import PerceptionConfig
from grip_env.dataset.catalog import DatasetObject, objects_table
from grip_env.objects import PlanarObject, load_object_set, object_from_spec, procedural_objects
from grip_env.objects.decomposition import MAX_PIECES
from grip_env.objects.simulated import DEFAULT_TOLERANCE_MM
from grip_env.perception import contour_error_mm, find_regions
from grip_env.planning.pipeline import candidates
from grip_env.sim.camera import perceive
from grip_env.sim.world import World

DATA = Path(__file__).parent / "data"
SILHOUETTE_MM_PER_PX = 0.4  # the silhouettes are about 330 x 250 px: 132 x 100 mm objects


def silhouette_mask(name: str) -> np.ndarray:
    return iio.imread(DATA / f"{name}.png") < 128


def every_object() -> list[PlanarObject]:
    """The default set, procedural shapes, objects from masks and from image files."""
    from_masks = [
        PlanarObject.from_mask(silhouette_mask(name), SILHOUETTE_MM_PER_PX, name=f"{name}_mask")
        for name in ("teddy", "duck")
    ]
    rows, cols = np.mgrid[:160, :160]
    theta = np.arctan2(rows - 80.0, cols - 80.0)
    blob = np.hypot(rows - 80.0, cols - 80.0) < 60 + 8 * np.sin(9 * theta)  # a nine-petal flower
    from_masks.append(PlanarObject.from_mask(blob, 0.6, name="wavy_mask"))
    from_files = [object_from_spec(str(DATA / f"{name}.png"), SILHOUETTE_MM_PER_PX)
                  for name in ("teddy", "duck")]
    return (load_object_set("default") + procedural_objects(12, 0, (50.0, 150.0))
            + from_masks + from_files)


OBJECTS = every_object()
IDS = [f"{obj.source}:{obj.name}" for obj in OBJECTS]


@pytest.fixture(scope="module")
def world():
    with World() as shared:
        yield shared


def collision_footprint_mm2(world: World, obj: PlanarObject) -> float:
    """Area of the object's PyBullet collision body, seen from above: a point probe on a grid at
    mid-thickness, inside where PyBullet reports contact; enclosed voids (where pieces' rounded
    corners meet inside the body) count as inside."""
    world.reset()
    body = world.add_object(obj)
    c = world.client
    probe = c.createMultiBody(0, c.createCollisionShape(pybullet.GEOM_SPHERE, radius=1e-6), -1,
                              [0, 0, 1])
    low, high = obj.contour.min(axis=0) - 2.0, obj.contour.max(axis=0) + 2.0
    step_mm = float(np.clip(np.max(high - low) / 250.0, 0.3, 0.6))
    xs = np.arange(low[0], high[0], step_mm) + 0.37 * step_mm  # off the polygons' round numbers
    ys = np.arange(low[1], high[1], step_mm) + 0.29 * step_mm
    inside = np.zeros((len(ys), len(xs)), dtype=bool)
    for row, y in enumerate(ys):
        for col, x in enumerate(xs):
            c.resetBasePositionAndOrientation(probe, [x * 1e-3, y * 1e-3, 0.015], [0, 0, 0, 1])
            inside[row, col] = bool(c.getClosestPoints(body.uid, probe, 0.0))
    return float(ndimage.binary_fill_holes(inside).sum()) * step_mm**2


@pytest.mark.parametrize("obj", OBJECTS, ids=IDS)
def test_simulated_shape_is_the_object_within_the_tolerance(obj):
    shape = obj.simulated_shape()
    assert len(shape.pieces) <= MAX_PIECES
    assert shape.deviation_mm <= DEFAULT_TOLERANCE_MM
    assert contour_error_mm(obj, PlanarObject(shape.contour)) <= shape.deviation_mm + 1e-6
    assert shape.area == pytest.approx(obj.area, rel=0.01)


@pytest.mark.slow
@pytest.mark.parametrize("obj", OBJECTS, ids=IDS)
def test_collision_body_area_is_the_objects_within_one_percent(world, obj):
    assert collision_footprint_mm2(world, obj) == pytest.approx(obj.area, rel=0.01)


@pytest.mark.parametrize("obj", OBJECTS, ids=IDS)
def test_rendered_contour_lies_within_a_pixel_of_the_true_one(world, obj):
    config = PerceptionConfig()
    seen = perceive(obj, config, world=world)
    mm_per_px = max(config.mm_per_px, float(np.ptp(obj.contour, axis=0).max()) / (256 - 9))
    assert contour_error_mm(obj, seen) <= mm_per_px


@pytest.mark.parametrize("name", ["teddy", pytest.param("duck", marks=pytest.mark.xfail(
    strict=False, reason="the duck's true contour is a binary mask's staircase and 9 of its 11 "
    "regions lie within 0.5 mm of min_region_mm or rho of 1/3: which survive decides the grip "
    "count (329 on the mask, 235 on the anti-aliased render since the level-anchored cuts; "
    "regions 11 and 11)"))])
def test_perception_of_a_detailed_silhouette(world, name):
    """Rendered at the silhouette's own 0.4 mm/px: area within 2 %, contour within 1 mm, as many
    grasping regions as the polygon within 10 %, and about as many grips to plan."""
    obj = PlanarObject.from_image(DATA / f"{name}.png", SILHOUETTE_MM_PER_PX)
    assert len(obj.contour) > 1000 and len(obj.convex_pieces()) > MAX_PIECES  # the case
    config = PerceptionConfig(mm_per_px=SILHOUETTE_MM_PER_PX, resolution_px=384)
    seen = perceive(obj, config, world=world)
    assert seen.area == pytest.approx(obj.area, rel=0.02)
    assert contour_error_mm(obj, seen) <= 1.0
    true_regions, seen_regions = len(find_regions(obj, config)), len(find_regions(seen, config))
    assert abs(seen_regions - true_regions) <= 0.1 * true_regions
    planned, seen_planned = len(candidates(obj)), len(candidates(seen))
    assert seen_planned == pytest.approx(planned, rel=0.25)  # the teddy has none: no 3 regions fit


def test_objects_table_records_source_and_simulated_shapes():
    entries = [DatasetObject(i, obj.name, obj) for i, obj in enumerate(OBJECTS[-3:])]
    table = objects_table(entries).to_pandas()
    for column in ("vertices", "area", "sim_vertices", "sim_tolerance_mm", "sim_deviation_mm",
                   "sim_pieces", "sim_area", "sim_approximate", "sim_contour"):
        assert column in table.columns
    assert (table["sim_vertices"] < table["vertices"]).all()
    assert (table["sim_pieces"] <= MAX_PIECES).all()
    assert (table["sim_deviation_mm"] <= table["sim_tolerance_mm"]).all()
    np.testing.assert_allclose(table["sim_area"], table["area"], rtol=0.01)
    assert [len(c) for c in table["sim_contour"]] == list(table["sim_vertices"])


def test_a_speck_in_a_mask_is_noise_but_a_second_part_is_not():
    mask = np.zeros((120, 120), dtype=bool)
    mask[10:110, 10:110] = True
    clean = PlanarObject.from_mask(mask, 1.0)
    mask[2, 2] = True  # one pixel against 10 000: noise
    mask[50, 50] = False  # a one-pixel hole: noise too
    assert PlanarObject.from_mask(mask, 1.0).area == pytest.approx(clean.area)
    mask[112:118, 10:40] = True  # 180 px: a second part
    with pytest.raises(ValueError, match="2 separate parts"):
        PlanarObject.from_mask(mask, 1.0)


def test_a_mask_with_a_hole_is_refused():
    mask = np.zeros((100, 100), dtype=bool)
    mask[10:90, 10:90] = True
    mask[40:60, 40:60] = False
    with pytest.raises(ValueError, match=r"1 hole\(s\) \(400 px\)"):
        PlanarObject.from_mask(mask, 1.0)


@pytest.mark.parametrize(
    ("cut", "message"),
    [((slice(45, 55), slice(0, 100)), "2 separate parts"),  # a band cut across: two halves
     ((slice(40, 60), slice(40, 60)), "hole")],
)
def test_show_on_a_bad_mask_file_is_one_line_and_exit_code_2(tmp_path, cut, message):
    image = np.full((100, 100), 255, dtype=np.uint8)
    image[10:90, 10:90] = 0
    image[cut] = 255
    path = tmp_path / "bad.png"
    Image.fromarray(image).save(path)
    _register_commands()
    result = CliRunner().invoke(app, ["show", str(path), "--mm-per-px", "1",
                                      "--out", str(tmp_path / "x.png")])
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert result.exit_code == 2, result.output
    assert len(lines) == 1 and lines[0].startswith("error:") and message in lines[0], lines
