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


def show(
    obj: Annotated[str, typer.Argument(
        help="shape name (listed below), image file, or vertex file (.json/.csv)"
    )],
    out: Annotated[
        Path, typer.Option("--out", "-o", help="PNG file to write (its name ends in .png)")
    ] = Path("show.png"),
    grips: Annotated[int, typer.Option(help="draw the best N grips by Q_C (0: regions only)")] = 0,
    config: ConfigFile = None,
    mm_per_px: Annotated[float, typer.Option(help="scale of an image object")] = 1.0,
    sim: Annotated[bool, typer.Option("--sim", help="simulate the best grip")] = False,
    seed: Annotated[int, typer.Option(min=0, help="seed of the simulated trial")] = 0,
) -> None:
    """Draw OBJECT with its grasping regions (and grips) to a PNG."""
    with user_errors():
        if grips < 0:
            raise ValueError(f"--grips must be >= 0, got {grips}")
        from grip_env.config import load_config

        output_file(out, ".png")
        cfg = load_config(config)
        planar = _load_object(obj, mm_per_px, cfg)
        path = _render_trial(planar, cfg, seed, out) if sim else _draw(planar, cfg, grips, out)
    typer.echo(f"wrote {path}")


def _load_object(spec: str, mm_per_px: float, cfg: Config) -> PlanarObject:
    """The object of ``spec``, refused when too large or too detailed to process."""
    from grip_env.config import check_contour_budget
    from grip_env.objects import object_from_spec
    from grip_env.objects.sources import IMAGE_SUFFIXES, check_image_size

    if Path(spec).suffix.lower() in IMAGE_SUFFIXES and Path(spec).is_file():
        check_image_size(Path(spec))
    planar = object_from_spec(spec, mm_per_px)
    low, high = planar.contour.min(axis=0), planar.contour.max(axis=0)
    perimeter = float(planar.polygon.length)
    extent = float((high - low).max())
    check_contour_budget(planar.name, len(planar.contour), perimeter, extent, cfg.perception)
    return planar


def _draw(planar: PlanarObject, cfg: Config, grips: int, out: Path) -> Path:
    from grip_env.drawing import object_figure, save_figure
    from grip_env.perception.regions import find_regions

    regions = find_regions(planar, cfg.perception, cfg.grasp)
    table = None
    if grips:
        from grip_env.pipeline import candidates

        table = candidates(planar, cfg.grasp, cfg, regions=regions).head(grips)
    title = f"{planar.name}: {len(regions)} regions"
    if table is not None:
        title += f", best {len(table)} grips by Q_C"
    return save_figure(object_figure(planar, regions, table, title), out)


def _render_trial(planar: PlanarObject, cfg: Config, seed: int, out: Path) -> Path:
    from grip_env.pipeline import candidates
    from grip_env.sim import render_trial_strip

    table = candidates(planar, cfg.grasp, cfg)
    if table.empty:
        raise ValueError(f"object {planar.name!r} has no feasible grip to simulate")
    result = render_trial_strip(planar, table.iloc[0], cfg, seed, out)
    outcome = "held" if result.success else "slipped"
    typer.echo(f"trial of {table.iloc[0]['grip_id']}: {outcome} (drift {result.drift_mm:.1f} mm)")
    return out


def register(app: typer.Typer) -> None:
    """Add the command to the CLI, with the shape names in its help."""
    from grip_env.objects.shapes import SHAPE_NAMES

    app.command("show", epilog=f"Shape names: {', '.join(SHAPE_NAMES)}.")(show)
