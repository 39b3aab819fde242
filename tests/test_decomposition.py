"""Simplification, convex decomposition, the simulated shape: bounded, within tolerance, whole."""

from __future__ import annotations

import time
import tracemalloc

import numpy as np
import pybullet
import pytest
import shapely
from shapely.geometry import Polygon

from grip_env.config import ObjectsConfig
from grip_env.objects import PlanarObject
from grip_env.objects.decomposition import (
    MAX_PIECES,
    bounded_pieces,
    exact_pieces,
    merge_convex,
)
from grip_env.objects.simplify import AREA_SHIFT, simplify_contour
from grip_env.objects.simulated import DEFAULT_TOLERANCE_MM, simulated_shape
from grip_env.sim.world import COLLISION_MARGIN_MM, World


def wavy_disc(points: int, radius: float = 50.0, waves: int = 40, amplitude: float = 3.0,
              noise: float = 0.0, seed: int = 0) -> np.ndarray:
    """A disc whose radius waves ``waves`` times, with optional radial noise (mm)."""
    theta = np.linspace(0, 2 * np.pi, points, endpoint=False)
    r = radius + amplitude * np.sin(waves * theta)
    r = r + np.random.default_rng(seed).normal(0.0, noise, points) if noise else r
    return np.column_stack([r * np.cos(theta), r * np.sin(theta)])


def hausdorff(a: np.ndarray, b: np.ndarray) -> float:
    return float(shapely.hausdorff_distance(shapely.LinearRing(a), shapely.LinearRing(b),
                                            densify=0.1))


def test_config_default_is_the_simulated_shapes_default():
    assert ObjectsConfig().sim_tolerance_mm == DEFAULT_TOLERANCE_MM == 0.5


@pytest.mark.parametrize("noise", [0.0, 0.15])
def test_simplified_contour_is_within_its_stated_deviation_and_keeps_the_area(noise):
    contour = wavy_disc(3000, noise=noise)
    simplified, deviation = simplify_contour(contour, 0.5)
    assert len(simplified) < len(contour) / 3
    assert deviation <= 0.5
    assert hausdorff(contour, simplified) <= deviation + 1e-9
    # a subset of the vertices, in order
    index = [int(np.flatnonzero((contour == p).all(axis=1))[0]) for p in simplified]
    assert np.all(np.diff(index) > 0)
    perimeter = shapely.LinearRing(contour).length
    change = abs(Polygon(simplified).area - Polygon(contour).area)
    assert change <= AREA_SHIFT * 0.5 * perimeter


def test_smooth_convex_arc_keeps_its_area():
    """Dropping vertices of a convex arc cuts material: the area bound keeps enough of them."""
    disc = wavy_disc(400, radius=25.0, amplitude=0.0)
    simplified, _ = simplify_contour(disc, 0.5)
    assert Polygon(simplified).area == pytest.approx(Polygon(disc).area, rel=0.003)


def test_zero_tolerance_keeps_the_contour():
    contour = wavy_disc(200)
    simplified, deviation = simplify_contour(contour, 0.0)
    np.testing.assert_array_equal(simplified, contour)
    assert deviation == 0.0


def test_contour_that_self_intersects_after_simplification_is_refused():
    """A clamp whose upper jaw has a shallow notch with the lower jaw's spike inside it: the
    chord that replaces the notch would cut through the spike."""
    clamp = [(0, 0), (40, 0), (40, 10), (26, 10), (25, 20.2), (24, 10), (10, 10), (10, 20),
             (24, 20), (25, 20.4), (26, 20), (40, 20), (40, 30), (0, 30)]
    obj = PlanarObject.from_polygon(clamp, name="clamp")
    with pytest.raises(ValueError, match=r"'clamp'.*self-intersects after simplification"):
        obj.simulated_shape(0.5)
    assert len(obj.simulated_shape(0.3).pieces) >= 3  # within 0.3 mm the notch stays


@pytest.mark.parametrize("bad", [-0.1, np.nan, np.inf])
def test_bad_tolerance_is_refused(bad):
    with pytest.raises(ValueError, match="tolerance_mm"):
        simplify_contour(wavy_disc(50), bad)


def test_merge_convex_gives_convex_pieces_tiling_the_polygon():
    contour = wavy_disc(300)
    pieces = exact_pieces(contour)
    triangles = shapely.constrained_delaunay_triangles(Polygon(contour)).geoms
    assert len(pieces) < len(triangles) / 2
    for piece in pieces:
        polygon = Polygon(piece)
        assert polygon.is_valid and polygon.area > 0
        assert polygon.convex_hull.area == pytest.approx(polygon.area, rel=1e-9)
    assert sum(Polygon(p).area for p in pieces) == pytest.approx(Polygon(contour).area)
    union = shapely.unary_union([Polygon(p) for p in pieces])
    assert union.symmetric_difference(Polygon(contour)).area < 1e-6


def test_merge_convex_of_two_triangles_makes_the_square():
    a = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    b = np.array([[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    (square,) = merge_convex([a, b])
    assert Polygon(square).area == pytest.approx(1.0) and len(square) == 4


def test_bounded_pieces_fit_the_limit_and_stay_within_the_tolerance():
    contour = wavy_disc(2000, waves=300, amplitude=0.3)  # 300 shallow waves: ~300 exact pieces
    exact = exact_pieces(contour)
    assert len(exact) > MAX_PIECES
    allowed = Polygon(contour).buffer(0.5)
    pieces = bounded_pieces(exact, allowed, MAX_PIECES)
    assert len(pieces) <= MAX_PIECES
    union = shapely.unary_union([Polygon(p) for p in pieces])
    assert union.covers(Polygon(contour).buffer(-1e-6))
    assert allowed.buffer(1e-6).covers(union)


def test_approximate_decomposition_when_exact_pieces_exceed_the_limit():
    shape = simulated_shape(wavy_disc(2000, waves=300, amplitude=0.3), 0.5, max_pieces=40)
    assert shape.approximate and len(shape.pieces) <= 40
    assert shape.deviation_mm == 0.5
    assert shape.area == pytest.approx(Polygon(wavy_disc(2000, waves=300, amplitude=0.3)).area,
                                       rel=0.01)


def comb_contour(teeth: int) -> np.ndarray:
    """A comb: a 5 mm spine, ``teeth`` teeth 2 mm wide, 2 mm apart and 10 mm long (CCW)."""
    outline = [(0.0, 0.0), (4.0 * teeth - 2.0, 0.0)]
    for k in reversed(range(teeth)):
        x0 = 4.0 * k
        outline += [(x0 + 2.0, 5.0), (x0 + 2.0, 15.0), (x0, 15.0), (x0, 5.0)]
    return np.array(outline)


def test_a_shape_that_needs_too_many_pieces_is_refused_not_truncated():
    obj = PlanarObject.from_polygon(comb_contour(150), name="comb")
    assert len(obj.convex_pieces()) > MAX_PIECES
    with pytest.raises(ValueError, match=r"'comb' cannot be simulated whole.*128"):
        obj.simulated_shape()
    with World() as world, pytest.raises(ValueError, match="cannot be simulated whole"):
        world.add_object(obj)


def test_add_object_refuses_a_piece_list_over_the_limit():
    with World() as world:
        box = world.client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=[0.01] * 3)
        shapes = [box] * (MAX_PIECES + 1)
        with pytest.raises(ValueError, match="129 convex pieces exceeds"):
            world._compound(shapes, [-1] * len(shapes), 0.3, [0.0, 0.0, 0.0])


def test_the_piece_limit_is_pybullets():
    """PyBullet keeps 127 links of a multibody and drops the rest silently: MAX_PIECES is it."""
    with World() as world:
        c = world.client
        box = c.createCollisionShape(pybullet.GEOM_BOX, halfExtents=[0.01] * 3)
        links = MAX_PIECES + 10
        uid = c.createMultiBody(
            1.0, box, -1, [0, 0, 0], linkMasses=[0.0] * links,
            linkCollisionShapeIndices=[box] * links, linkVisualShapeIndices=[-1] * links,
            linkPositions=[[0, 0, 0]] * links, linkOrientations=[[0, 0, 0, 1]] * links,
            linkInertialFramePositions=[[0, 0, 0]] * links,
            linkInertialFrameOrientations=[[0, 0, 0, 1]] * links,
            linkParentIndices=[0] * links, linkJointTypes=[pybullet.JOINT_FIXED] * links,
            linkJointAxis=[[0, 0, 1]] * links,
        )
        assert 1 + c.getNumJoints(uid) == MAX_PIECES


def test_body_has_one_link_per_piece_of_its_simulated_shape():
    """A link per convex piece: the visual pieces, or the collision pieces eroded by Bullet's
    margin where the erosion cuts more (the flower's: 41 against 40)."""
    obj = PlanarObject.from_polygon(wavy_disc(600, waves=12, amplitude=8.0), name="flower")
    shape = obj.simulated_shape()
    collision = shape.collision_pieces(COLLISION_MARGIN_MM)
    assert 1 < len(shape.pieces) <= MAX_PIECES and len(collision) <= MAX_PIECES
    with World() as world:
        body = world.add_object(obj)
        assert 1 + world.client.getNumJoints(body.uid) == max(len(shape.pieces), len(collision))
        assert len(body.links) == 1 + world.client.getNumJoints(body.uid)


def test_collision_surface_is_the_shape_not_the_shape_plus_margin():
    """Bullet rounds convex meshes outward by their margin; inset prisms cancel it."""
    obj = PlanarObject.from_polygon([(-45, -27.5), (45, -27.5), (45, 27.5), (-45, 27.5)])
    with World() as world:
        body = world.add_object(obj)
        c = world.client
        probe_shape = c.createCollisionShape(pybullet.GEOM_BOX, halfExtents=[0.005] * 3)
        for gap_mm in (0.5, 2.0):
            probe = c.createMultiBody(0, probe_shape, -1, [(45 + gap_mm + 5) * 1e-3, 0, 0.015])
            (point,) = c.getClosestPoints(body.uid, probe, 0.01)
            assert point[8] * 1e3 == pytest.approx(gap_mm, abs=0.01)
        above = c.createMultiBody(0, probe_shape, -1, [0, 0, (30 + 1 + 5) * 1e-3])
        (point,) = c.getClosestPoints(body.uid, above, 0.01)
        assert point[8] * 1e3 == pytest.approx(1.0, abs=0.01)  # top face at 30 mm


def test_collision_pieces_are_the_shape_eroded_by_the_margin():
    """Grown back by the margin, they give the shape's opening: faces and concave corners exact."""
    l_shape = PlanarObject.from_polygon([(0, 0), (60, 0), (60, 20), (20, 20), (20, 50), (0, 50)])
    shape = l_shape.simulated_shape()
    eroded = shape.collision_pieces(COLLISION_MARGIN_MM)
    grown = shapely.unary_union([Polygon(p).buffer(COLLISION_MARGIN_MM, quad_segs=64)
                                 for p in eroded])
    corner_loss = 5 * (1 - np.pi / 4) * COLLISION_MARGIN_MM**2  # five convex right-angle corners
    assert grown.area == pytest.approx(l_shape.area - corner_loss, abs=0.01)
    assert Polygon(shape.contour).covers(grown.buffer(-1e-6))
    with pytest.raises(ValueError, match="nowhere thicker"):
        PlanarObject.from_polygon([(0, 0), (50, 0), (50, 1.5), (0, 1.5)]).simulated_shape(
        ).collision_pieces(COLLISION_MARGIN_MM)


def test_thousands_of_contour_points_load_in_bounded_time_and_memory():
    obj = PlanarObject.from_polygon(wavy_disc(4000, waves=60, amplitude=4.0, noise=0.1),
                                    name="detailed")
    tracemalloc.start()
    start = time.perf_counter()
    shape = obj.simulated_shape()
    with World() as world:
        world.add_object(obj)
    elapsed = time.perf_counter() - start
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert len(shape.pieces) <= MAX_PIECES
    assert elapsed < 5.0, f"{elapsed:.1f} s"
    assert peak < 100e6, f"{peak / 1e6:.0f} MB"
    union = shapely.unary_union([Polygon(p) for p in shape.pieces])
    assert hausdorff(obj.contour, np.asarray(union.exterior.coords)[:-1]) <= DEFAULT_TOLERANCE_MM
