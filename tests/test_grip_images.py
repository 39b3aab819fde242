"""Grip images: hand-computed pictures, invariance to moving the object with its grips, the
channels at the contacts, the cache, bad input, scikit-learn composition, and occlusion maps."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.base import BaseEstimator, clone
from sklearn.linear_model import LogisticRegression
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import FunctionTransformer

from classifiers.learners import grip_images as gi
from classifiers.learners.grip_images import (
    CONTOUR_COLUMN,
    HAND_REACH_MM,
    GripImages,
    attach_contours,
    clear_image_cache,
    load_with_contours,
    silhouette_raster,
)
from classifiers.learners.occlusion import occlusion_maps, patch_masks
from grip_env.columns import CONTACTS, FORCES
from grip_env.objects import PlanarObject
from grip_env.objects.shapes import ellipse, rectangle, star

STANDARD = str(Path(__file__).resolve().parents[1] / "grip_env" / "data" / "standard")


def _grip(hand=(0.0, 0.0), yaw=math.pi / 2, contacts=None, forces=None, object_id="box"):
    """One row of a grip table; by default yaw pi/2 puts world x right and world y up."""
    contacts = contacts if contacts is not None else [(-17.5, 12.5), (17.5, 12.5), (2.5, -12.5)]
    forces = forces if forces is not None else [(0.0, -1.0), (0.0, -1.0), (0.0, 1.0)]
    row = {"object_id": object_id, "hand_x": hand[0], "hand_y": hand[1], "hand_yaw": yaw}
    row.update(zip(CONTACTS, np.ravel(contacts), strict=True))
    row.update(zip(FORCES, np.ravel(forces), strict=True))
    return row


def _table(rows, contours: dict[str, np.ndarray]) -> pd.DataFrame:
    objects = pd.DataFrame({"object_id": list(contours),
                            "contour": [c.tolist() for c in contours.values()]})
    return attach_contours(pd.DataFrame(rows), objects)


def _pixel(u: float, v: float, size: int = 48, mm: float = 5.0) -> tuple[int, int]:
    """(row, column) of the pixel holding hand coordinates (u, v)."""
    return math.floor(size / 2 - v / mm), math.floor(size / 2 + u / mm)


# ------------------------------------------------------------------ hand-computed images
def test_a_centred_square_fills_the_pixels_it_covers():
    """A 40 mm square at the palm centre covers the 8 x 8 pixels 20..27 (5 mm a pixel), whole."""
    images = GripImages().transform(_table([_grip()], {"box": rectangle(40.0, 40.0)}))
    silhouette = images[0, 0]
    expected = np.zeros((48, 48), dtype=np.float32)
    expected[20:28, 20:28] = 1.0
    np.testing.assert_array_equal(silhouette, expected)


def test_the_hand_s_frame_moves_and_turns_the_picture():
    """A 40 x 20 mm box (long along world x). The palm 10 mm right of its centre shifts it 2 px
    left; a yaw of 0 turns the thumb's force (image up) to world x, so the box stands upright."""
    box = {"box": rectangle(40.0, 20.0)}
    shifted = GripImages().transform(_table([_grip(hand=(10.0, 0.0))], box))[0, 0]
    expected = np.zeros((48, 48), dtype=np.float32)
    expected[22:26, 18:26] = 1.0
    np.testing.assert_array_equal(shifted, expected)
    upright = GripImages().transform(_table([_grip(yaw=0.0)], box))[0, 0]
    expected = np.zeros((48, 48), dtype=np.float32)
    expected[20:28, 22:26] = 1.0  # hand x = (sin 0, -cos 0): world -y runs right
    np.testing.assert_array_equal(upright, expected)


def test_channels_mark_the_contacts_and_the_fingers_approach():
    contacts = [(-17.5, 12.5), (17.5, 12.5), (2.5, -12.5)]  # pixel centres
    box = {"box": rectangle(40.0, 25.0)}  # its sides at v = +-12.5 run through the contacts
    images = GripImages().transform(_table([_grip(contacts=contacts)], box))
    silhouette, dots, approach = images[0]
    for u, v in contacts:
        row, col = _pixel(u, v)
        assert dots[row, col] == 1.0
        assert dots[row + 3, col] == 0.0 and dots[row, col - 3] == 0.0
    # fingers 1 and 2 press down (-v): their approach runs 60 mm up from the contact
    row, col = _pixel(-17.5, 12.5 + 30.0)
    assert approach[row, col] == 1.0
    assert approach[_pixel(-17.5, 12.5 - 10.0)] == 0.0  # not ahead of the finger
    assert approach[_pixel(-17.5 - 15.0, 12.5 + 30.0)] == 0.0  # beyond its 25 mm width
    assert approach[_pixel(-17.5, 12.5 + 65.0)] == 0.0  # beyond its 60 mm length
    # the thumb presses up from below
    assert approach[_pixel(2.5, -12.5 - 30.0)] == 1.0
    # the contacts lie on the box's sides, half way up their pixels: half of each is object
    for u, v in contacts:
        assert silhouette[_pixel(u, v)] == 0.5


def test_values_are_exact_fractions_of_a_pixel_s_samples():
    table = _table([_grip(yaw=0.3)], {"box": ellipse(45.0, 25.0)})
    images = GripImages().transform(table)
    samples = images * gi.SUPERSAMPLE**2
    np.testing.assert_array_equal(samples, np.round(samples))
    assert images.dtype == np.float32 and images.shape == (1, 3, 48, 48)
    assert images.min() == 0.0 and images.max() == 1.0


def test_the_raster_fills_the_polygon_s_area():
    for contour in (star(5, 60.0, 25.0), ellipse(50.0, 20.0), rectangle(33.3, 17.1)):
        raster = silhouette_raster(contour)
        area = 0.5 * abs(np.dot(contour[:, 0], np.roll(contour[:, 1], -1))
                         - np.dot(contour[:, 1], np.roll(contour[:, 0], -1)))
        perimeter = np.linalg.norm(np.diff(contour, axis=0, append=contour[:1]), axis=1).sum()
        filled = raster.mask.sum() * raster.cell_mm**2
        assert abs(filled - area) <= perimeter * raster.cell_mm
        assert not raster.mask[[0, -1]].any() and not raster.mask[:, [0, -1]].any()
        # points agree with the exact polygon (shapely) but within a cell's diagonal of its edge
        points = np.random.default_rng(0).uniform(-80, 80, size=(20_000, 2))
        exact = PlanarObject(contour).contains(points)
        edge = shapely.distance(shapely.LinearRing(contour), shapely.points(points))
        far = edge > raster.cell_mm * math.sqrt(2)
        np.testing.assert_array_equal(raster.contains(*points.T)[far], exact[far])


# ------------------------------------------------------------------------- invariance
def _rotated(points: np.ndarray, angle: float, shift: np.ndarray) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.asarray(points, float) @ np.array([[c, s], [-s, c]]) + shift


@settings(max_examples=25, deadline=None)
@given(angle=st.floats(-math.pi, math.pi), dx=st.floats(-300, 300), dy=st.floats(-300, 300),
       yaw=st.floats(-math.pi, math.pi))
def test_moving_the_object_with_its_grips_keeps_the_image(angle, dx, dy, yaw):
    """A rigid motion of the object and its grip together leaves the grip's image as it was,
    up to the silhouette's edge samples (its raster is aligned with the world's axes)."""
    contour = star(5, 60.0, 25.0)
    contacts = np.array([(-20.0, 30.0), (25.0, 20.0), (5.0, -40.0)])
    forces = np.array([(0.6, -0.8), (-0.6, -0.8), (0.0, 1.0)])
    hand = np.array([3.0, -7.0])
    shift = np.array([dx, dy])
    moved = _grip(hand=_rotated(hand, angle, shift), yaw=yaw + angle,
                  contacts=_rotated(contacts, angle, shift), forces=_rotated(forces, angle, 0.0),
                  object_id="moved")
    still = _grip(hand=hand, yaw=yaw, contacts=contacts, forces=forces, object_id="still")
    table = _table([still, moved], {"still": contour, "moved": _rotated(contour, angle, shift)})
    before, after = GripImages().transform(table)
    difference = np.abs(before - after)
    assert difference[0].mean() < 0.01  # a sample in 400 flips, on the outline only
    # the outline's pixels: those with object and ground among their eight neighbours
    padded = np.pad(before[0], 1, mode="edge")
    around = np.stack([padded[i:i + 48, j:j + 48] for i in range(3) for j in range(3)])
    outline = (around.max(axis=0) > 0) & (around.min(axis=0) < 1)
    assert not difference[0][~outline].any()
    assert difference[1:].sum() <= 0.5  # the analytic channels: float rounding at most


# --------------------------------------------------------------------------- the cache
def test_the_cache_returns_the_same_bits_and_draws_each_object_once():
    contours = {"box": rectangle(40, 20), "disc": ellipse(30, 30), "star": star(5, 50, 20)}
    rows = [_grip(yaw=0.1 * k, object_id=name) for k, name in enumerate(contours) for _ in "ab"]
    table = _table(rows, contours)
    clear_image_cache()
    fresh = GripImages().transform(table)
    assert len(gi._CACHE.entries) == 3  # one entry per object
    again = GripImages().transform(table)
    assert again.tobytes() == fresh.tobytes() and len(gi._CACHE.entries) == 3
    # a fold of whole objects reuses the entries: same bits as the full table's rows
    fold = table[table["object_id"] != "disc"]
    np.testing.assert_array_equal(GripImages().transform(fold), fresh[fold.index])
    assert len(gi._CACHE.entries) == 3
    clear_image_cache()
    assert GripImages().transform(table).tobytes() == fresh.tobytes()


def test_the_contour_column_shares_one_array_per_object():
    contours = {"box": rectangle(40, 20), "disc": ellipse(30, 30)}
    table = _table([_grip(object_id="box"), _grip(object_id="disc"), _grip(object_id="box")],
                   contours)
    cells = table[CONTOUR_COLUMN].to_numpy()
    assert cells[0] is cells[2] and cells[0] is not cells[1]
    assert not cells[0].flags.writeable
    np.testing.assert_array_equal(cells[1], contours["disc"])


# --------------------------------------------------------------------------- bad input
def test_a_scale_that_does_not_fit_the_hand_is_refused():
    table = _table([_grip()], {"box": rectangle(40, 20)})
    with pytest.raises(ValueError, match=r"mm_per_px 4\.0 .*reach 113\.5 mm"):
        GripImages(mm_per_px=4.0).fit(table)
    with pytest.raises(ValueError, match="mm_per_px must be a positive number, got -5"):
        GripImages(mm_per_px=-5.0).transform(table)
    with pytest.raises(ValueError, match="size_px"):
        GripImages(size_px=4, mm_per_px=100.0).fit(table)
    with pytest.raises(ValueError, match="channels"):
        GripImages(channels=("silhouette", "depth")).fit(table)
    with pytest.raises(ValueError, match=r"use mm_per_px >= 4\.729"):
        GripImages(mm_per_px=4.728).fit(table)
    assert GripImages(mm_per_px=4.729).fit(table).image_shape_ == (3, 48, 48)
    assert HAND_REACH_MM <= 48 * 4.729 / 2


def test_missing_contours_are_named():
    grips = pd.DataFrame([_grip()])
    with pytest.raises(ValueError, match=r"planned_contour.*attach_contours"):
        GripImages().fit(grips)
    assert GripImages(channels=("contacts",)).transform(grips).shape == (1, 1, 48, 48)
    with pytest.raises(ValueError, match=r"no contour column \(perceived_contour or contour\)"):
        attach_contours(grips, pd.DataFrame({"object_id": ["box"], "area": [1.0]}))
    with pytest.raises(ValueError, match=r"1 objects .*\['box'\]"):
        attach_contours(grips, pd.DataFrame({"object_id": ["other"],
                                             "contour": [rectangle(4, 4).tolist()]}))
    with pytest.raises(ValueError, match="object 'box' has no contour"):
        attach_contours(grips, pd.DataFrame({"object_id": ["box"], "contour": [None],
                                             "perceived_contour": [[]]}))
    broken = pd.DataFrame([_grip()]).assign(hand_yaw=np.nan)
    with pytest.raises(ValueError, match=r"\['hand_yaw'\]"):
        GripImages(channels=("contacts",)).transform(broken)


def test_a_run_on_the_render_needs_every_perceived_contour():
    objects = pd.DataFrame({"object_id": ["box", "unused"],
                            "contour": [rectangle(40, 20).tolist(), None],
                            "perceived_contour": [None, None]})
    grips = pd.DataFrame([_grip()])
    # an object without grips needs no contour; the true one serves a run on the true objects
    assert attach_contours(grips, objects)[CONTOUR_COLUMN].iloc[0].shape == (4, 2)
    with pytest.raises(ValueError, match="object 'box' has no perceived contour"):
        attach_contours(grips, objects, on_render=True)
    with pytest.raises(ValueError, match=r"no contour column \(perceived_contour\)"):
        attach_contours(grips, objects.drop(columns="perceived_contour"), on_render=True)


def test_the_perceived_contour_is_preferred_where_stored():
    true, seen = rectangle(40, 20), rectangle(30, 20)
    objects = pd.DataFrame({"object_id": ["a", "b"], "contour": [true.tolist()] * 2,
                            "perceived_contour": [seen.tolist(), None]})
    table = attach_contours(pd.DataFrame([_grip(object_id="a"), _grip(object_id="b")]), objects)
    np.testing.assert_array_equal(table[CONTOUR_COLUMN].iloc[0], seen)
    np.testing.assert_array_equal(table[CONTOUR_COLUMN].iloc[1], true)


# ----------------------------------------------------------------------- scikit-learn
def test_it_clones_and_composes_in_a_pipeline():
    images = GripImages(size_px=32, mm_per_px=8.0, channels=("silhouette", "contacts"))
    copy = clone(images)
    assert copy.get_params() == {"size_px": 32, "mm_per_px": 8.0,
                                 "channels": ("silhouette", "contacts")}
    contours = {"box": rectangle(40, 20), "star": star(5, 50, 20)}
    rows = [_grip(yaw=0.2 * k, object_id=name) for k in range(6) for name in contours]
    table = _table(rows, contours)
    labels = (table["object_id"] == "box").to_numpy()
    model = Pipeline([("images", copy),
                      ("flat", FunctionTransformer(lambda x: x.reshape(len(x), -1))),
                      ("model", LogisticRegression())]).fit(table, labels)
    assert model.predict(table).tolist() == labels.tolist()


# --------------------------------------------------------------------- the real dataset
@pytest.fixture(scope="module")
def standard_grips() -> pd.DataFrame:
    """The standard dataset's grips with their contours."""
    return load_with_contours(STANDARD)


def test_the_standard_dataset_s_grips_have_images(standard_grips):
    grips = standard_grips.groupby("object_id").head(2)
    cells = grips[CONTOUR_COLUMN].to_numpy()
    assert len({id(c) for c in cells}) == grips["object_id"].nunique() == 510
    images = GripImages().transform(grips)
    silhouette, dots, approach = images.transpose(1, 0, 2, 3)
    assert (silhouette.sum(axis=(1, 2)) > 10).all()  # every object is in its picture
    assert (dots.sum(axis=(1, 2)) >= 3).all() and (approach.sum(axis=(1, 2)) > 30).all()
    # the contacts lie on the outline: partly on the silhouette
    assert ((silhouette * dots).sum(axis=(1, 2)) > 0).all()
    # the planner kept every finger's approach clear of the planned contour (sampled on its
    # centre line and edges): away from the contacts the strips and the silhouette meet in a
    # few partial pixels at most; drawn with the fingers on the wrong side, they cross it
    near = dots > 0
    for _ in range(2):
        near = near | np.roll(near, 1, 1) | np.roll(near, -1, 1)
        near = near | np.roll(near, 1, 2) | np.roll(near, -1, 2)
    crossing = (silhouette * approach * ~near).sum(axis=(1, 2))
    assert np.quantile(crossing, 0.99) <= 1.0 and crossing.max() <= 3.0
    wrong_side = (silhouette[:, ::-1] * approach * ~near).sum(axis=(1, 2))
    assert np.quantile(wrong_side, 0.9) > 10.0


@pytest.mark.slow
def test_a_generated_dataset_s_grips_have_images(generated_dataset_dir):
    grips = load_with_contours(generated_dataset_dir)
    images = GripImages().transform(grips)
    assert images.shape == (len(grips), 3, 48, 48)
    assert (images[:, 0].sum(axis=(1, 2)) > 10).all()


# -------------------------------------------------------------------------- occlusion
def _region_model(images: np.ndarray) -> np.ndarray:
    """Looks only at channel 0's pixels [10:14, 20:24]: their mean."""
    return images[:, 0, 10:14, 20:24].mean(axis=(1, 2))


def test_occlusion_finds_the_only_region_a_model_looks_at():
    images = np.ones((3, 2, 32, 32), dtype=np.float32)
    maps = occlusion_maps(_region_model, images, patch_px=4, stride_px=2, fill=0.0,
                          batch_size=50)
    assert maps.shape == (3, 32, 32)
    np.testing.assert_array_equal(maps[0], maps[2])
    # a patch hides part of the region only if it starts within 3 pixels before it
    near = np.zeros((32, 32), dtype=bool)
    near[7:17, 17:27] = True
    assert not maps[0][~near].any()
    assert maps[0][10:14, 20:24].min() > 0
    # the square exactly on the region hides all of it: drop 1, averaged with the others
    masks = patch_masks(32, 32, 4, 2)
    drops = np.array([1 - _region_model(np.where(m, 0.0, images[:1, 0])[:, None])[0]
                      for m in masks])
    expected = (drops[:, None, None] * masks).sum(0) / masks.sum(0)
    np.testing.assert_allclose(maps[0], expected)


def test_occlusion_reads_predict_proba_and_checks_its_input():
    class Model:
        def predict_proba(self, images):
            p = _region_model(images)
            return np.stack([1 - p, p], axis=1)

    images = np.ones((2, 1, 32, 32), dtype=np.float32)
    np.testing.assert_allclose(occlusion_maps(Model(), images, fill=0.0),
                               occlusion_maps(_region_model, images, fill=0.0))
    np.testing.assert_array_equal(occlusion_maps(_region_model, images, fill=[0.0]),
                                  occlusion_maps(_region_model, images, fill=0.0))
    # the default grey is each channel's mean over its image: on a uniform image hiding changes
    # nothing, and an image's map is the same alone as among others
    assert not occlusion_maps(_region_model, images).any()
    mixed = np.random.default_rng(1).uniform(size=(3, 1, 32, 32)).astype(np.float32)
    np.testing.assert_array_equal(occlusion_maps(_region_model, mixed)[1:2],
                                  occlusion_maps(_region_model, mixed[1:2]))
    with pytest.raises(ValueError, match="fill"):
        occlusion_maps(_region_model, images, fill="grey")
    with pytest.raises(ValueError, match="patch_px"):
        occlusion_maps(_region_model, images, patch_px=40)
    with pytest.raises(ValueError, match=r"\(n, C, H, W\)"):
        occlusion_maps(_region_model, images[0])


def test_a_contour_column_read_from_parquet_draws_the_same(tmp_path):
    """A table written with its contours and read back (cells: object arrays of points)."""
    table = _table([_grip(yaw=0.2), _grip(yaw=1.0)], {"box": star(5, 50, 20)})
    as_lists = table.assign(**{CONTOUR_COLUMN: [c.tolist() for c in table[CONTOUR_COLUMN]]})
    as_lists.to_parquet(tmp_path / "grips.parquet")  # Arrow writes lists, not 2-D arrays
    read = pd.read_parquet(tmp_path / "grips.parquet")
    assert read[CONTOUR_COLUMN].iloc[0].dtype == object
    assert GripImages().transform(read).tobytes() == GripImages().transform(table).tobytes()
    broken = read.assign(**{CONTOUR_COLUMN: [[[0.0, 0.0]], [[1.0, 2.0, 3.0]]]})
    with pytest.raises(ValueError, match="planned_contour of row 0 is not a contour"):
        GripImages().transform(broken)


def test_copies_of_a_contour_are_drawn_as_one_object():
    contour = star(5, 50, 20)
    table = pd.DataFrame([_grip(yaw=0.1 * k) for k in range(4)]).assign(
        **{CONTOUR_COLUMN: [contour.copy() for _ in range(4)]})
    clear_image_cache()
    copies = GripImages().transform(table)
    assert len(gi._CACHE.entries) == 1
    shared = _table([_grip(yaw=0.1 * k) for k in range(4)], {"box": contour})
    assert GripImages().transform(shared).tobytes() == copies.tobytes()


# ----------------------------------------------------------------------------- figures
def test_the_figures_show_each_grip_with_its_label(tmp_path, standard_grips):
    import json

    from classifiers.report.grip_images import choose_grips, grip_images_figure, occlusion_figure
    from classifiers.report.study_report import _grip_images

    chosen = choose_grips(standard_grips, count=6, seed=3)
    assert chosen["success"].tolist() == [True] * 3 + [False] * 3
    assert chosen["object_id"].is_unique
    fig = grip_images_figure(chosen)
    titles = [ax.get_title() for ax in fig.axes]
    assert len(titles) == 6 and titles[0].startswith(chosen["object_id"].iloc[0] + "\nsuccess")
    assert "failure: held in" in titles[-1] and titles[-1].endswith(" g")
    images = GripImages().transform(chosen.head(2))
    maps = occlusion_maps(lambda x: x[:, 0].mean(axis=(1, 2)), images)
    assert len(occlusion_figure(images, maps, ["a", "b"]).axes) == 5  # 2 x 2 and a colour bar
    # the study report draws it from the dataset its data.json names, and skips it without one
    (tmp_path / "data.json").write_text(json.dumps({"dataset": STANDARD}))
    table = standard_grips.drop(columns=CONTOUR_COLUMN)
    path = _grip_images(table, tmp_path / "figures" / "grip_images.png", tmp_path)
    assert path is not None and path.stat().st_size > 10_000
    assert _grip_images(table, tmp_path / "x.png", tmp_path / "elsewhere") is None


def test_the_command_line_reports_them_as_bad_input():
    """Each is a ``raise`` of ours, so a command ends with one ``error:`` line and exit 2, also
    when scikit-learn's pipeline calls the transformer."""
    from grip_env.cli.errors import is_input_error

    table = _table([_grip()], {"box": rectangle(40, 20)})
    bare = pd.DataFrame([_grip()])
    pipeline = Pipeline([("images", GripImages()), ("flat", FunctionTransformer())])
    for call in (lambda: GripImages(mm_per_px=4.0).fit(table), lambda: pipeline.fit(bare),
                 lambda: attach_contours(bare, pd.DataFrame({"object_id": ["box"]}))):
        with pytest.raises(ValueError) as caught:
            call()
        assert is_input_error(caught.value), caught.value


def test_occlusion_of_a_grip_pipeline_and_where_its_maps_lie():
    """A pipeline whose model reads only the contacts channel: hiding the contacts is all that
    lowers its prediction, so every map's positive part lies on or next to them."""
    from classifiers.learners.occlusion import grip_occlusion_maps, map_shares

    def contacts_only(images):
        p = images[:, 1].mean(axis=(1, 2)) * 50
        return np.stack([1 - p, p], axis=1)

    contours = {"box": rectangle(40, 25), "star": star(5, 50, 20)}
    table = _table([_grip(yaw=0.4 * k, object_id=name) for k in range(2) for name in contours],
                   contours)
    model = Pipeline([("images", GripImages()), ("model", _Proba(contacts_only))]).fit(table)
    images, maps = grip_occlusion_maps(model, table, patch_px=4, stride_px=2)
    assert images.shape == (4, 3, 48, 48) and maps.shape == (4, 48, 48)
    shares = map_shares(maps, images)
    np.testing.assert_allclose(shares.sum(axis=1), 1.0)
    # a square spreads its drop over the pixels it hid: within 3 pixels of a contact's disc
    near = images[:, 1] > 0
    for _ in range(3):
        near = near | np.roll(near, 1, 1) | np.roll(near, -1, 1)
        near = near | np.roll(near, 1, 2) | np.roll(near, -1, 2)
    assert (maps > 0).any(axis=(1, 2)).all() and not (maps[~near] > 0).any()
    assert (shares.idxmax(axis=1) == "contacts").all()
    with pytest.raises(ValueError, match="GripImages step"):
        grip_occlusion_maps(Pipeline([("model", _Proba(contacts_only))]), table)
    from classifiers.report.grip_images import grip_occlusion_figure

    figure = grip_occlusion_figure(model, table.assign(success=[True, False] * 2), patch_px=4)
    expected = contacts_only(images[:1])[0, 1]
    assert len(figure.axes) == 9  # 2 x 4 and a colour bar
    assert figure.axes[0].get_title() == f"box\nsuccess\npredicted {expected:.2f}"


class _Proba(BaseEstimator):
    """A stand-in model of images with ``predict_proba``."""

    def __init__(self, function=None):
        self.function = function

    def fit(self, X, y=None):
        self.fitted_ = True
        return self

    def predict_proba(self, images):
        return self.function(images)


def test_the_cache_keeps_within_its_bound():
    cache = gi._ImageCache(max_bytes=250)
    for k in range(5):
        cache.put(bytes([k]), np.full(100, k, dtype=np.uint8))
    assert list(cache.entries) == [bytes([3]), bytes([4])] and cache.bytes == 200
    assert cache.get(bytes([3]))[0] == 3 and cache.get(bytes([0])) is None
    cache.put(bytes([5]), np.zeros(100, dtype=np.uint8))  # 4 was used least recently
    assert list(cache.entries) == [bytes([3]), bytes([5])]


_DRAW_IN_ANOTHER_PROCESS = """
import hashlib, sys
from classifiers.learners.grip_images import GripImages, load_with_contours
grips = load_with_contours(sys.argv[1]).iloc[::97]
print(hashlib.sha256(GripImages().transform(grips).tobytes()).hexdigest())
"""


def test_another_process_draws_the_same_bits(standard_grips):
    import hashlib
    import os
    import subprocess
    import sys

    clear_image_cache()
    here = hashlib.sha256(GripImages().transform(standard_grips.iloc[::97]).tobytes()).hexdigest()
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    there = subprocess.run([sys.executable, "-c", _DRAW_IN_ANOTHER_PROCESS, STANDARD], env=env,
                           capture_output=True, text=True, check=True).stdout.strip()
    assert there == here
