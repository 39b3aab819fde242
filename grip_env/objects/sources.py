"""Turning a user's object specification into ``PlanarObject``: a shape name, a file, a folder of
files or a glob of them.

Object files are images (segmented; scaled by ``mm_per_px``) or vertex files: CSV with ``x, y``
columns in mm (an ``x,y`` header is optional) or JSON holding a list of ``[x, y]``. A file that
cannot become one simple polygon raises ``ValueError`` naming the file.

The scale of the images in a folder can be given once, in a sidecar file ``scale.yaml`` in that
folder holding ``mm_per_px: <number>`` (YAML, so ``{"mm_per_px": 0.5}`` works too); it applies to
every image of the folder, and a ``--mm-per-px`` that differs from it is refused.
"""

from __future__ import annotations

import glob
import json
import math
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from grip_env.config import MAX_OBJECT_VERTICES
from grip_env.objects.planar import PlanarObject
from grip_env.objects.shapes import SHAPE_NAMES, make_shape

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")
VERTEX_SUFFIXES = (".csv", ".json")
OBJECT_SUFFIXES = IMAGE_SUFFIXES + VERTEX_SUFFIXES
#: A vertex file larger than this is refused unread (far above any polygon that can be simulated).
MAX_VERTEX_FILE_BYTES = 64_000_000
#: The most objects one folder or glob may name.
MAX_OBJECT_FILES = 100_000
_GLOB_CHARS = frozenset("*?[")
#: The sidecar file giving the scale of a folder's images.
SCALE_FILE = "scale.yaml"
_MAX_SCALE_FILE_BYTES = 10_000


def object_from_spec(spec: str, mm_per_px: float = 1.0) -> PlanarObject:
    """A named shape, an image file (scaled by ``mm_per_px``), or a vertex file (.json or .csv)."""
    if spec in SHAPE_NAMES:
        return make_shape(spec)
    check_file_spec(spec)
    path = Path(spec)
    if not path.exists():
        raise ValueError(
            f"object {spec!r} is neither a known shape ({', '.join(SHAPE_NAMES)}) nor a file"
        )
    return object_from_file(path, mm_per_px)


def check_file_spec(spec: str) -> None:
    """Refuse a spec that names a file (by its suffix, or a folder in its path) that is not
    there, as a missing file rather than as an unknown object name (``FileNotFoundError``)."""
    path = Path(spec)
    if is_path_spec(spec):  # an existing path, or a glob
        return
    kinds = {**dict.fromkeys(IMAGE_SUFFIXES, "image file"),
             **dict.fromkeys(VERTEX_SUFFIXES, "vertex file"), ".obj": "mesh file"}
    kind = kinds.get(path.suffix.lower(), "file" if len(path.parts) > 1 else None)
    if kind is not None:
        where = "" if path.is_absolute() else f" (looked for {path.absolute()})"
        raise FileNotFoundError(f"{kind} {spec} does not exist{where}")


def is_path_spec(spec: str) -> bool:
    """Whether ``spec`` names files (an existing path, or a glob pattern) rather than a set."""
    return Path(spec).exists() or any(char in spec for char in _GLOB_CHARS)


def object_files(spec: str | Path) -> list[Path]:
    """The object files a path names: the file itself, a folder's object files (by suffix, not
    hidden, sorted), or a glob's matches (sorted).

    Raises:
        ValueError: no such path, a file of unknown type, or no object file found.
    """
    text = str(spec)
    path = Path(text)
    if path.is_dir():
        files = sorted(p for p in path.iterdir() if _is_object_file(p))
        where = f"folder {path}"
    elif path.exists():
        files = [path]
        where = str(path)
    elif any(char in text for char in _GLOB_CHARS):
        files = sorted(Path(p) for p in glob.glob(text, recursive=True) if _is_object_file(Path(p)))
        where = f"pattern {text!r}"
    else:
        raise ValueError(f"objects path {text} does not exist")
    if not files:
        raise ValueError(
            f"{where} holds no object file (images {', '.join(IMAGE_SUFFIXES)} or vertex files "
            f"{', '.join(VERTEX_SUFFIXES)})"
        )
    if len(files) > MAX_OBJECT_FILES:
        raise ValueError(f"{where} names {len(files)} object files, more than {MAX_OBJECT_FILES}")
    return files


def objects_from_path(spec: str | Path, mm_per_px: float | None = None) -> list[PlanarObject]:
    """Every object a file, folder or glob names, in file-name order; each object's name is its
    file's stem and its ``source`` the file's path.

    Args:
        spec: a file, a folder or a glob pattern of object files.
        mm_per_px: the scale of the images (required when there is one; refused when none).

    Raises:
        ValueError: a bad path or scale, or a file that is not one simple polygon (naming it).
    """
    files = object_files(spec)
    images = [path for path in files if path.suffix.lower() in IMAGE_SUFFIXES]
    if not images and mm_per_px is not None:
        raise ValueError(f"--mm-per-px {mm_per_px:g} is for images, and {spec} names none")
    scales = {path: image_scale(path, mm_per_px) for path in images}
    return [object_from_file(path, scales.get(path, 1.0)) for path in files]


def image_scale(path: Path, mm_per_px: float | None, default: float | None = None) -> float:
    """The scale of image ``path``: its folder's ``scale.yaml``, else ``mm_per_px``, else
    ``default``.

    Raises:
        ValueError: no scale at all, a bad sidecar, or a ``mm_per_px`` that contradicts it.
    """
    given = folder_scale(path.parent)
    if given is not None:
        if mm_per_px is not None and not math.isclose(mm_per_px, given, rel_tol=1e-9):
            raise ValueError(f"--mm-per-px {mm_per_px:g} contradicts {path.parent / SCALE_FILE} "
                             f"(mm_per_px: {given:g}); give one of them")
        return given
    if mm_per_px is not None:
        return mm_per_px
    if default is not None:
        return default
    raise ValueError(f"{path} is an image: give its scale with --mm-per-px or in "
                     f"{path.parent / SCALE_FILE} (mm_per_px: <mm per pixel>)")


def folder_scale(folder: Path) -> float | None:
    """The ``mm_per_px`` of a folder's ``scale.yaml``, None when it has none.

    Raises:
        ValueError: the sidecar is unreadable, not YAML, or holds no positive ``mm_per_px``.
    """
    import yaml

    path = folder / SCALE_FILE
    if not path.is_file():
        return None
    try:
        if path.stat().st_size > _MAX_SCALE_FILE_BYTES:
            raise ValueError(f"is larger than {_MAX_SCALE_FILE_BYTES} bytes")
        data = yaml.safe_load(path.read_text(encoding="utf-8-sig"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise ValueError(f"scale file {path}: cannot read it ({exc})".splitlines()[0]) from None
    except ValueError as exc:
        raise ValueError(f"scale file {path} {exc}") from None
    value = data.get("mm_per_px") if isinstance(data, dict) else None
    extra = sorted(set(data) - {"mm_per_px"}) if isinstance(data, dict) else []
    if extra:
        raise ValueError(f"scale file {path}: unknown key {extra[0]!r} (only mm_per_px)")
    try:
        check_mm_per_px(value)  # type: ignore[arg-type]
    except ValueError:
        raise ValueError(f"scale file {path} must hold mm_per_px: <positive number>, "
                         f"got {data!r}") from None
    return float(value)  # type: ignore[arg-type]


def object_from_file(path: Path, mm_per_px: float = 1.0) -> PlanarObject:
    """The object of one image or vertex file, named by its stem, with the file as its source.

    Raises:
        ValueError: unknown type, unreadable, too large, or not one simple polygon (naming it).
    """
    suffix = path.suffix.lower()
    if suffix not in OBJECT_SUFFIXES:
        raise ValueError(f"object file {path} has unknown type {suffix!r} (image, .json or .csv)")
    try:
        if suffix in IMAGE_SUFFIXES:
            check_mm_per_px(mm_per_px)
            check_image_size(path)
            obj = PlanarObject.from_image(path, mm_per_px, name=path.stem)
        else:
            obj = PlanarObject.from_polygon(read_vertex_file(path), name=path.stem)
    except ValueError as exc:
        message = str(exc)
        raise ValueError(message if str(path) in message else f"object file {path}: {message}"
                         ) from None
    return PlanarObject(obj.contour, name=path.stem, source=path.as_posix())


def read_vertex_file(path: Path) -> NDArray[np.float64]:
    """The (N, 2) vertices (mm) of a CSV (``x, y`` columns, optional header) or JSON file."""
    try:
        size = path.stat().st_size
        if size > MAX_VERTEX_FILE_BYTES:
            raise ValueError(f"is {size} bytes, more than {MAX_VERTEX_FILE_BYTES}")
        text = path.read_text(encoding="utf-8-sig")  # a byte-order mark is not part of x
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"cannot read it: {exc}") from None
    vertices = _json_vertices(text) if path.suffix.lower() == ".json" else _csv_vertices(text)
    if len(vertices) > MAX_OBJECT_VERTICES:
        raise ValueError(f"has {len(vertices)} vertices, more than {MAX_OBJECT_VERTICES}: "
                         "simplify the polygon")
    return vertices


def _json_vertices(text: str) -> NDArray[np.float64]:
    try:
        data = json.loads(text)
    except (json.JSONDecodeError, RecursionError) as exc:
        raise ValueError(f"is not valid JSON ({exc})") from None
    if not isinstance(data, list) or not all(
        isinstance(p, list) and len(p) == 2 and all(_is_number(v) for v in p) for p in data
    ):
        raise ValueError("must hold a JSON list of [x, y] vertices in mm")
    return np.array(data, dtype=float).reshape(-1, 2)


def _csv_vertices(text: str) -> NDArray[np.float64]:
    rows = [line.split(",") for line in text.splitlines() if line.strip()]
    if not rows:
        raise ValueError("holds no vertex")
    header = [cell.strip().lower() for cell in rows[0]]
    columns = (0, 1)
    if not all(_parses(cell) for cell in header):
        if "x" not in header or "y" not in header:
            raise ValueError(f"header {rows[0]} has no x and y columns")
        columns, rows = (header.index("x"), header.index("y")), rows[1:]
    elif len(header) != 2:
        raise ValueError(f"rows must be x,y (or have an x,y header), got {len(header)} columns")
    try:
        return np.array([[float(row[columns[0]]), float(row[columns[1]])] for row in rows])
    except (IndexError, ValueError):
        raise ValueError("every row must hold two numbers, x and y in mm") from None


def _parses(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def check_mm_per_px(mm_per_px: float) -> None:
    """Refuse a scale that is not a positive finite number."""
    if isinstance(mm_per_px, bool) or not isinstance(mm_per_px, (int, float)) or not (
        math.isfinite(mm_per_px) and mm_per_px > 0
    ):
        raise ValueError(f"--mm-per-px must be a positive number, got {mm_per_px!r}")


def check_image_size(path: Path) -> None:
    """Refuse an image with more than ``MAX_IMAGE_PIXELS`` before decoding it."""
    from PIL import Image, UnidentifiedImageError

    from grip_env.config import MAX_IMAGE_PIXELS

    try:
        with Image.open(path) as image:
            width, height = image.size
    except (OSError, UnidentifiedImageError, Image.DecompressionBombError) as exc:
        raise ValueError(f"cannot read image file {path}: {exc}") from None
    if width * height > MAX_IMAGE_PIXELS:
        raise ValueError(
            f"image {path} is {width} x {height} pixels, more than {MAX_IMAGE_PIXELS} in all; "
            "downscale it (and raise --mm-per-px to match)"
        )


def _is_object_file(path: Path) -> bool:
    return path.is_file() and not path.name.startswith(".") and (
        path.suffix.lower() in OBJECT_SUFFIXES
    )
