"""The objects ``show`` and ``candidates`` name, and the grips planned on them as ``generate``
plans them.

An object spec is a shape name, a mesh (household name, ``urdf_NNN`` or an ``.obj`` file), an
image or vertex file, or a folder or glob of such files (several objects, in file-name order, as
``generate --objects`` takes them). An image needs its scale (``--mm-per-px`` or its folder's
``scale.yaml``), as for ``generate``.

Object ``i`` is planned as ``generate`` plans object ``i`` of a run: by default on its perceived
contour (rendered from above and segmented, under the perception seed of object ``i``), when the
config's ``perception.source`` is ``render``; ``--contour true`` plans on the true outline.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

if TYPE_CHECKING:
    import pandas as pd

    from grip_env.config import Config
    from grip_env.objects import PlanarObject
    from grip_env.sim.world import World


class Contour(StrEnum):
    """The contour grips are planned on."""

    perceived = "perceived"
    true = "true"


ContourOption = Annotated[Contour | None, typer.Option(
    "--contour",
    help="plan on the perceived contour (rendered from above and segmented, as generate plans "
         "with perception.source: render) or on the true outline (default: as generate plans "
         "under the config: perceived with the default config)",
)]
MmPerPxOption = Annotated[float | None, typer.Option(
    "--mm-per-px",
    help="scale of image objects (required for images unless their folder's scale.yaml gives "
         "it, as for generate)",
)]
OBJECT_HELP = ("shape name (listed below), mesh (household name, urdf_NNN or an .obj file), "
               "image file, vertex file (.json/.csv), or a folder or glob of such files")
MESH_HELP = ("Meshes of pybullet_data (dropped on the table, seen at rest): duck, teddy, mug, "
             "lego, jenga, domino, cube, bunny, soccerball, urdf_000 to urdf_999, or an .obj "
             "file.")


@dataclass(frozen=True)
class PlannedObject:
    """One object, the object its grips are planned on, and its candidates (None: not planned)."""

    true: PlanarObject
    planned_on: PlanarObject
    table: pd.DataFrame | None = None

    @property
    def name(self) -> str:
        return self.true.name

    @property
    def outline(self) -> str:
        """What the grips are planned on, in a figure's words."""
        return "true outline" if self.planned_on is self.true else "perceived contour"


def perceives(contour: Contour | None, config: Config) -> bool:
    """Whether grips are planned on the perceived contour under ``--contour`` and ``config``."""
    from grip_env.dataset.jobs import plans_on_render

    return plans_on_render(config) if contour is None else contour is Contour.perceived


def contour_words(perceive: bool) -> str:
    """What the grips were planned on, for a command's output."""
    if perceive:
        return "the perceived contour (rendered and segmented, as generate plans)"
    return "the true outline"


def is_several(spec: str) -> bool:
    """Whether ``spec`` names a folder or a glob of object files rather than one object."""
    from grip_env.objects.sources import is_path_spec

    return not Path(spec).is_file() and is_path_spec(spec)


def load_objects(spec: str, mm_per_px: float | None, config: Config) -> list[PlanarObject]:
    """The objects ``spec`` names (see the module docstring), each checked against the
    perception budget.

    Raises:
        ValueError: an unknown name (with the nearest known one), a missing scale, a bad file.
    """
    from grip_env.objects.sources import check_file_spec, objects_from_path

    check_file_spec(spec)
    found = objects_from_path(spec, mm_per_px) if is_several(spec) else [
        _one_object(spec, mm_per_px, config)]
    for planar in found:
        _check_budget(planar, config)
    return found


def plan(
    objects: list[PlanarObject], config: Config, perceive: bool, with_grips: bool = True,
) -> list[PlannedObject]:
    """Each object (object ``i`` of a run) with the object its grips are planned on and, when
    ``with_grips``, its candidates; one simulation world renders them all."""
    from grip_env.dataset.jobs import planned_candidates, planned_object

    def one(index: int, obj: PlanarObject, world: World | None) -> PlannedObject:
        if with_grips:
            return PlannedObject(obj, *planned_candidates(obj, config, perceive=perceive,
                                                          index=index, world=world))
        return PlannedObject(obj, planned_object(obj, config, perceive=perceive, index=index,
                                                 world=world))

    if not perceive:
        return [one(index, obj, None) for index, obj in enumerate(objects)]
    from grip_env.sim.world import World

    with World() as world:
        return [one(index, obj, world) for index, obj in enumerate(objects)]


def without_grips(planned: list[PlannedObject]) -> list[str]:
    """The names of the planned objects that have no feasible grip."""
    return [p.name for p in planned if p.table is not None and p.table.empty]


def require_grips(planned: list[PlannedObject], perceive: bool, config: Config) -> None:
    """Refuse a request for grips when no object has a feasible one (``ValueError``)."""
    empty = without_grips(planned)
    if not planned or len(empty) < len(planned):
        return
    where = contour_words(perceive).split(" (")[0]
    other = " (--contour true plans on the true outline)" if perceive else ""
    if len(planned) == 1:
        raise ValueError(f"object {planned[0].name!r} has no feasible grip on {where}{other}"
                         f"{_frictional_closure_hint(planned[0], config)}")
    raise ValueError(f"none of the {len(planned)} objects has a feasible grip on {where}{other}")


def _frictional_closure_hint(item: PlannedObject, config: Config) -> str:
    """Say how many grips an object without any has when three-finger grasps may close with
    friction (a cross, a notched rectangle: no three of their normals span the plane alone)."""
    from grip_env.planning.pipeline import candidates

    if config.synthesis.frictional_closure:
        return ""
    frictional = config.override(synthesis={"frictional_closure": True})
    found = len(candidates(item.planned_on, frictional.grasp, frictional))
    if not found:
        return ""
    return ("; three-finger grasps here need normals that span the plane without friction (the "
            "default, the standard dataset's planner); with friction in the closure "
            f"(synthesis.frictional_closure: true) it has {found}")


def _one_object(spec: str, mm_per_px: float | None, config: Config) -> PlanarObject:
    from grip_env.mesh_sets import mesh_from_spec
    from grip_env.objects import object_from_spec
    from grip_env.objects.sources import IMAGE_SUFFIXES, check_image_size, image_scale

    path = Path(spec)
    if path.suffix.lower() in IMAGE_SUFFIXES and path.is_file():
        check_image_size(path)
        return object_from_spec(spec, image_scale(path, mm_per_px))
    if mm_per_px is not None:
        raise ValueError(f"--mm-per-px {mm_per_px:g} is for image files, and {spec} is none")
    mesh = mesh_from_spec(spec, config.dataset.seed, config.objects)
    if mesh is not None:
        return mesh
    _check_name(spec)
    return object_from_spec(spec)


def _check_name(spec: str) -> None:
    """Refuse a bare name that is no shape and no mesh, with the nearest known name."""
    from grip_env.mesh_sets import HOUSEHOLD_MESHES
    from grip_env.objects import SHAPE_NAMES

    if Path(spec).exists() or spec in SHAPE_NAMES:
        return
    names = [*SHAPE_NAMES, *HOUSEHOLD_MESHES]
    close = difflib.get_close_matches(spec, names, n=1, cutoff=0.6)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise ValueError(f"unknown object {spec!r}{hint} (a shape name: {', '.join(SHAPE_NAMES)}; "
                     "a mesh; or an image, vertex file, folder or glob)")


def _check_budget(planar: PlanarObject, config: Config) -> None:
    from grip_env.config import check_contour_budget

    low, high = planar.contour.min(axis=0), planar.contour.max(axis=0)
    perimeter = float(planar.polygon.length)
    extent = float((high - low).max())
    check_contour_budget(planar.name, len(planar.contour), perimeter, extent, config.perception)
