"""Own objects end to end: ``generate --objects PATH`` (folders and globs of images or vertex
files) and ``generate(config, out, objects=[PlanarObject, ...])``, with the real job."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from cli_runs import assert_refused, cli
from PIL import Image

from grip_env.config import MAX_OBJECT_VERTICES, Config
from grip_env.dataset import DatasetMismatchError, generate, load, read_objects, validate
from grip_env.dataset.catalog import resolve_objects
from grip_env.objects import PlanarObject
from grip_env.objects.sources import objects_from_path, read_vertex_file

SMALL = Config().override(dataset={"max_grips_per_object": 3, "trials": 1})






def save_mask(path: Path, mask: np.ndarray) -> Path:
    Image.fromarray(np.where(mask, 255, 0).astype(np.uint8)).save(path)
    return path


def l_mask() -> np.ndarray:
    mask = np.zeros((120, 160), bool)
    mask[20:100, 30:130] = True
    mask[20:60, 30:70] = False
    return mask


@pytest.fixture
def parts(tmp_path: Path) -> Path:
    """A folder with one CSV (x,y header), one JSON and one PNG object, and a stray text file."""
    folder = tmp_path / "parts"
    folder.mkdir()
    (folder / "box.csv").write_text("x,y\n0,0\n90,0\n90,55\n0,55\n")
    (folder / "tri.json").write_text(json.dumps([[0, 0], [60, 0], [30, 50]]))
    save_mask(folder / "ell.png", l_mask())
    (folder / "notes.txt").write_text("not an object")
    return folder


@pytest.fixture
def small_config(tmp_path: Path) -> Path:
    path = tmp_path / "small.yaml"
    path.write_text(yaml.safe_dump(SMALL.model_dump(mode="json")))
    return path


# ----------------------------------------------------------------------------- reading files
def test_vertex_files_csv_with_or_without_header_and_json(tmp_path: Path) -> None:
    square = [[0.0, 0.0], [40.0, 0.0], [40.0, 40.0], [0.0, 40.0]]
    (tmp_path / "a.csv").write_text("0,0\n40,0\n40,40\n0,40\n")
    (tmp_path / "b.csv").write_text("id,y,x\n1,0,0\n2,0,40\n3,40,40\n4,40,0\n")
    (tmp_path / "c.json").write_text(json.dumps(square))
    (tmp_path / "d.csv").write_text("\ufeffX,Y\n0,0\n40,0\n40,40\n0,40\n")  # BOM, upper case
    assert read_vertex_file(tmp_path / "d.csv").tolist() == square
    assert read_vertex_file(tmp_path / "a.csv").tolist() == square
    assert read_vertex_file(tmp_path / "b.csv").tolist() == square  # columns found by header
    assert read_vertex_file(tmp_path / "c.json").tolist() == square


def test_folder_and_glob_give_the_objects_in_file_order_with_their_sources(parts: Path) -> None:
    from_folder = objects_from_path(parts, mm_per_px=0.8)
    assert [o.name for o in from_folder] == ["box", "ell", "tri"]
    assert [o.source for o in from_folder] == [(parts / n).as_posix()
                                               for n in ("box.csv", "ell.png", "tri.json")]
    assert from_folder[0].area == pytest.approx(90 * 55)
    assert from_folder[1].area == pytest.approx(0.64 * (80 * 100 - 40 * 40), rel=0.02)
    from_glob = objects_from_path(str(parts / "*.csv"))
    assert [o.name for o in from_glob] == ["box"]


@pytest.mark.parametrize(("name", "content", "message"), [
    ("bow.json", "[[0, 0], [10, 10], [10, 0], [0, 10]]", "not simple"),
    ("line.csv", "0,0\n1,1\n2,2\n", "zero area"),
    ("words.csv", "a,b\n1,2\n", "no x and y columns"),
    ("ragged.csv", "x,y\n1,2\n3\n", "two numbers"),
    ("dict.json", '{"x": [1, 2]}', "list of [x, y]"),
    ("broken.json", "[[0, 0], [1", "not valid JSON"),
    ("nan.json", "[[0, 0], [10, 0], [NaN, 10]]", "not finite"),
])
def test_a_bad_vertex_file_is_refused_naming_it(
    tmp_path: Path, name: str, content: str, message: str
) -> None:
    (tmp_path / name).write_text(content)
    with pytest.raises(ValueError, match=re.escape(message)) as error:
        objects_from_path(tmp_path / name)
    assert str(tmp_path / name) in str(error.value)


# ----------------------------------------------------------------------------- the CLI
def test_generate_a_folder_of_own_objects_and_validate_it(
    tmp_path: Path, parts: Path, small_config: Path
) -> None:
    out = tmp_path / "data"
    code, output = cli("generate", "--out", out, "--objects", parts, "--mm-per-px", 0.8,
                       "--config", small_config, "--workers", 1, "--no-progress")
    assert code == 0, output
    table = read_objects(out)
    assert table["name"].tolist() == ["box", "ell", "tri"]
    assert table["source"].tolist() == [(parts / n).as_posix()
                                        for n in ("box.csv", "ell.png", "tri.json")]
    grips = load(out)
    assert set(grips["object_id"]) == {"box", "ell", "tri"}
    assert validate(out) == []
    # the same seed gives the same dataset on two workers, from a glob naming the same files
    again = tmp_path / "again"
    code, output = cli("generate", "--out", again, "--objects", f"{parts}/*",
                       "--mm-per-px", 0.8, "--config", small_config, "--workers", 2,
                       "--no-progress")
    assert code == 0, output
    pd.testing.assert_frame_equal(load(again), grips)
    # a rerun is the same run: nothing to do
    code, output = cli("generate", "--out", out, "--objects", parts, "--mm-per-px", 0.8,
                       "--config", small_config, "--no-progress")
    assert code == 0, output
    # an edited file is another run, refused without --overwrite
    (parts / "box.csv").write_text("x,y\n0,0\n80,0\n80,55\n0,55\n")
    assert_refused(*cli("generate", "--out", out, "--objects", parts, "--mm-per-px", 0.8,
                        "--config", small_config, "--no-progress"),
                   "object_contours_sha256", "--overwrite")


def test_bad_object_paths_end_in_one_line_naming_the_file(tmp_path: Path, parts: Path) -> None:
    out = tmp_path / "g"
    assert_refused(*cli("generate", "--out", out, "--objects", tmp_path / "nothere"),
                   "nothere")
    (tmp_path / "empty").mkdir()
    assert_refused(*cli("generate", "--out", out, "--objects", tmp_path / "empty"),
                   "empty", "no object file")
    assert_refused(*cli("generate", "--out", out, "--objects", f"{tmp_path}/*.tif",
                        "--mm-per-px", 1), "*.tif", "no object file")
    assert_refused(*cli("generate", "--out", out, "--objects", parts), "ell.png",
                   "--mm-per-px")
    assert_refused(*cli("generate", "--out", out, "--objects", parts / "box.csv",
                        "--mm-per-px", 1), "--mm-per-px", "images")
    assert_refused(*cli("generate", "--out", out, "--objects", parts / "ell.png",
                        "--mm-per-px", -1), "ell.png", "--mm-per-px")
    assert_refused(*cli("generate", "--out", out, "--objects", "default", "--mm-per-px", 1),
                   "--mm-per-px")
    assert_refused(*cli("generate", "--out", out, "--objects", parts / "notes.txt"),
                   "notes.txt", "unknown type")
    assert not out.exists()


def test_bad_images_and_polygons_end_in_one_line_naming_the_file(tmp_path: Path) -> None:
    two = np.zeros((120, 160), bool)
    two[20:50, 30:60] = two[70:100, 80:130] = True
    holed = l_mask()
    holed[70:90, 80:110] = False
    blank = save_mask(tmp_path / "blank.png", np.zeros((40, 40), bool))
    cases = {
        save_mask(tmp_path / "two.png", two): "2 separate parts",
        save_mask(tmp_path / "holed.png", holed): "hole",
        blank: "",
    }
    for image, message in cases.items():
        assert_refused(*cli("generate", "--out", tmp_path / "g", "--objects", image,
                            "--mm-per-px", 0.8), str(image), message)
    bow = tmp_path / "bow.json"
    bow.write_text("[[0, 0], [10, 10], [10, 0], [0, 10]]")
    assert_refused(*cli("generate", "--out", tmp_path / "g", "--objects", bow),
                   str(bow), "not simple")
    angles = np.linspace(0, 2 * np.pi, MAX_OBJECT_VERTICES + 1, endpoint=False)
    many = tmp_path / "many.csv"
    np.savetxt(many, np.c_[50 * np.cos(angles), 50 * np.sin(angles)], delimiter=",")
    assert_refused(*cli("generate", "--out", tmp_path / "g", "--objects", many),
                   str(many), f"{MAX_OBJECT_VERTICES + 1} vertices")
    huge = tmp_path / "huge.json"
    huge.write_text(json.dumps([[0, 0], [1e7, 0], [0, 1e7]]))
    assert_refused(*cli("generate", "--out", tmp_path / "g", "--objects", huge),
                   str(huge), "mm across")


# ----------------------------------------------------------------------------- Python
def test_generate_accepts_a_list_of_objects_and_keeps_names_inside_the_folder(
    tmp_path: Path,
) -> None:
    square = [[0, 0], [50, 0], [50, 50], [0, 50]]
    objects = [PlanarObject.from_polygon(square, name="../../escape"),
               PlanarObject.from_polygon(np.array(square) * 1.5, name="../../escape"),
               PlanarObject.from_polygon([[0, 0], [70, 0], [35, 60]], name=".hidden/x y")]
    out = generate(SMALL, tmp_path / "data", objects=objects, workers=1, progress=False)
    table = read_objects(out)
    assert table["name"].tolist() == ["../../escape", "../../escape", ".hidden/x y"]
    ids = table["object_id"].tolist()
    assert ids == ["_.._escape-1", "_.._escape-2", "hidden_x_y"]
    inside = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    assert all(not p.startswith("..") for p in inside)
    assert not (tmp_path / "escape").exists() and not list(tmp_path.glob("*escape*"))
    grips = load(out)
    assert set(grips["object_id"]) <= set(ids)
    assert all(g.split("/")[0] in ids for g in grips["grip_id"])
    with pytest.raises(DatasetMismatchError, match="object_contours_sha256"):
        generate(SMALL, out, objects=[objects[1], objects[0], objects[2]], progress=False)


def test_object_ids_are_unique_safe_file_names_whatever_the_names() -> None:
    triangle = [[0, 0], [70, 0], [35, 60]]
    names = ["a", "a", "a-1", "../b", "b", "", "a"]
    entries = resolve_objects(SMALL, [PlanarObject.from_polygon(triangle, name=n) for n in names],
                              seed=0)
    ids = [entry.object_id for entry in entries]
    assert ids == ["a-2", "a-3", "a-1", "_b", "b", "object", "a-4"]
    assert all(re.fullmatch(r"[A-Za-z0-9_+-][A-Za-z0-9_.+-]*", i) for i in ids)


def test_generate_refuses_what_is_not_an_object() -> None:
    with pytest.raises(ValueError, match="PlanarObject"):
        generate(SMALL, "unused", objects=[[[0, 0], [1, 0], [0, 1]]], progress=False)
