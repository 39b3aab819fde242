"""``grip-env show``: draw an object with its regions and best grips, or a simulated trial."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.options import ConfigFile
from grip_env.cli.paths import output_file

if TYPE_CHECKING:
    from grip_env.config import Config
    from grip_env.objects import PlanarObject
    from grip_env.sim import TrialResult


def show(
    obj: Annotated[str, typer.Argument(
        metavar="OBJECT",
        help="shape name (listed below), mesh (household name, urdf_NNN or an .obj file), "
             "image file, vertex file (.json/.csv), or a folder or glob of such files (drawn "
             "side by side)"
    )],
    out: Annotated[
        Path, typer.Option("--out", "-o", help="PNG file to write (its name ends in .png)")
    ] = Path("show.png"),
    grips: Annotated[int, typer.Option(
        min=0,
        help="draw the best N grips by Q_C (0: regions only); with --sim, simulate the best N "
             "(0 or 1: the best grip), one row of frames each"
    )] = 0,
    config: ConfigFile = None,
    mm_per_px: Annotated[float | None, typer.Option(
        help="scale of an image object (default: the scale.yaml of its folder, else 1)"
    )] = None,
    sim: Annotated[bool, typer.Option(
        "--sim", help="simulate the best grip (or the best --grips N) in PyBullet and draw its "
                      "phases: approach, close, lift, disturbance ramp; prints each outcome"
    )] = False,
    seed: Annotated[int, typer.Option(
        min=0, help="seed of the simulated trial's draw (friction, mass, placement error)"
    )] = 0,
) -> None:
    """Draw OBJECT with its grasping regions (and grips) to a PNG, or with --sim the phases of
    simulated trials of its best grips."""
    with user_errors():
        from grip_env.config import load_config
        from grip_env.objects.sources import check_file_spec

        output_file(out, ".png")
        cfg = load_config(config)
        check_file_spec(obj)
        several = _several_objects(obj, mm_per_px, cfg)
        if several is not None:
            if sim:
                raise ValueError(f"--sim simulates one object, and {obj} names {len(several)}")
            path = _draw_sheet(several, cfg, out)
        else:
            planar = _load_object(obj, mm_per_px, cfg)
            path = (_render_trial(planar, cfg, max(grips, 1), seed, out) if sim
                    else _draw(planar, cfg, grips, out))
    typer.echo(f"wrote {path}")


def _several_objects(spec: str, mm_per_px: float | None, cfg: Config) -> list[PlanarObject] | None:
    """The objects of a folder or glob (each checked as one object is), None for one object."""
    from grip_env.objects.sources import is_path_spec, objects_from_path

    if Path(spec).is_file() or not is_path_spec(spec):
        return None
    found = objects_from_path(spec, mm_per_px)
    for planar in found:
        _check_budget(planar, cfg)
    return found


def _load_object(spec: str, mm_per_px: float | None, cfg: Config) -> PlanarObject:
    """The object of ``spec``, refused when too large or too detailed to process."""
    from grip_env.mesh_sets import mesh_from_spec
    from grip_env.objects import object_from_spec
    from grip_env.objects.sources import IMAGE_SUFFIXES, check_image_size, image_scale

    mesh = mesh_from_spec(spec, cfg.dataset.seed, cfg.objects)
    if mesh is not None:
        _check_budget(mesh, cfg)
        return mesh
    scale = 1.0 if mm_per_px is None else mm_per_px
    if Path(spec).suffix.lower() in IMAGE_SUFFIXES and Path(spec).is_file():
        check_image_size(Path(spec))
        scale = image_scale(Path(spec), mm_per_px, default=1.0)
    planar = object_from_spec(spec, scale)
    _check_budget(planar, cfg)
    return planar


def _check_budget(planar: PlanarObject, cfg: Config) -> None:
    from grip_env.config import check_contour_budget

    low, high = planar.contour.min(axis=0), planar.contour.max(axis=0)
    perimeter = float(planar.polygon.length)
    extent = float((high - low).max())
    check_contour_budget(planar.name, len(planar.contour), perimeter, extent, cfg.perception)


def _draw_sheet(objects: list[PlanarObject], cfg: Config, out: Path) -> Path:
    """Every object with its regions, side by side (up to 6 a row), in one PNG."""
    import matplotlib.pyplot as plt

    from grip_env.drawing import draw_object, save_figure
    from grip_env.perception.regions import find_regions

    columns = min(6, len(objects))
    rows = -(-len(objects) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(2.6 * columns, 2.6 * rows), squeeze=False)
    for ax in axes.flat[len(objects):]:
        ax.set_axis_off()
    for ax, planar in zip(axes.flat, objects, strict=False):
        regions = find_regions(planar, cfg.perception, cfg.grasp)
        draw_object(ax, planar, regions)
        ax.set_title(f"{planar.name}: {len(regions)} regions", fontsize=8)
    return save_figure(fig, out)


def _draw(planar: PlanarObject, cfg: Config, grips: int, out: Path) -> Path:
    from grip_env.drawing import object_figure, save_figure
    from grip_env.perception.regions import find_regions

    regions = find_regions(planar, cfg.perception, cfg.grasp)
    table = None
    if grips:
        from grip_env.planning.pipeline import candidates

        table = candidates(planar, cfg.grasp, cfg, regions=regions).head(grips)
        if table.empty:
            _explain_no_grip(planar, cfg, regions)
    title = f"{planar.name}: {len(regions)} regions"
    if table is not None:
        title += f", best {len(table)} grips by Q_C"
    return save_figure(object_figure(planar, regions, table, title), out)


def _explain_no_grip(planar: PlanarObject, cfg: Config, regions) -> None:
    """Say when an object without grips has some under frictional closure (a cross, a notched
    rectangle: no three of their normals positively span the plane)."""
    from grip_env.planning.pipeline import candidates

    if cfg.synthesis.frictional_closure:
        return
    frictional = cfg.override(synthesis={"frictional_closure": True})
    found = len(candidates(planar, cfg.grasp, frictional, regions=regions))
    if found:
        typer.echo(f"{planar.name}: no grip when three-finger grasps need normals that span the "
                   f"plane without friction (the default, the standard dataset's planner); "
                   f"with friction (synthesis.frictional_closure: true) it has {found}")


def _render_trial(planar: PlanarObject, cfg: Config, grips: int, seed: int, out: Path) -> Path:
    """Simulate the best ``grips`` grips (trial 0 of ``seed`` each), print each outcome and draw
    each trial's phases in one row."""
    from grip_env.drawing import save_figure, trial_figure
    from grip_env.planning.pipeline import candidates
    from grip_env.sim import TRIAL_PHASES, trial_frames

    table = candidates(planar, cfg.grasp, cfg)
    if table.empty:
        raise ValueError(f"object {planar.name!r} has no feasible grip to simulate")
    best = table.head(grips)
    trials = trial_frames(planar, best, cfg, seed, width=360, height=270)
    rows = []
    for rank, ((_, grip), (result, frames)) in enumerate(
        zip(best.iterrows(), trials, strict=True), start=1
    ):
        outcome = result.describe()
        typer.echo(f"trial of {grip['grip_id']}: {outcome}")
        phases = [(_phase_title(phase, result), frames.get(phase)) for phase in TRIAL_PHASES]
        rows.append((f"#{rank} by Q_C ({grip['Q_C']:.2f}), grip {grip['grip_id']}: {outcome}",
                     phases))
    grips_text = "the best grip" if len(best) == 1 else f"the best {len(best)} grips"
    title = f"{planar.name}: a simulated trial (seed {seed}) of {grips_text} by Q_C"
    return save_figure(trial_figure(rows, title), out)


def _phase_title(phase: str, result: TrialResult) -> str:
    """A frame's title: the phase, and what the trial measured in it."""
    from grip_env.sim.trial import grams

    if phase == "approach":
        return "1 approach\nthe pre-shaped hand lowered"
    if phase == "closed":
        return f"2 close\nfingers stopped after {result.close_steps} steps"
    if phase == "held":
        return (f"3 lift and hold\nrose {result.lifted_mm:.0f} mm, drift {result.drift_mm:.1f} mm, "
                f"turn {result.rotation_deg:.1f} deg")
    if not result.held:
        return "4 disturbance ramp\nnot run: not held after the lift"
    return (f"4 disturbance ramp\nheld up to {grams(result.robustness_g)} "
            f"(reference {grams(result.reference_g)})")


def register(app: typer.Typer) -> None:
    """Add the command to the CLI, with the shape names in its help."""
    from grip_env.objects.shapes import SHAPE_NAMES

    meshes = "duck, teddy, mug, lego, jenga, domino, cube, bunny, soccerball"
    app.command("show", epilog=f"Shape names: {', '.join(SHAPE_NAMES)}. Meshes of pybullet_data "
                f"(dropped on the table, seen at rest): {meshes}, urdf_000 to urdf_999, or "
                "an .obj file.")(show)
