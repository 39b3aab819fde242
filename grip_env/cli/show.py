"""``grip-env show``: draw an object with its regions and best grips, or a simulated trial."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.objects import (
    MESH_HELP,
    OBJECT_HELP,
    ContourOption,
    MmPerPxOption,
    PlannedObject,
    contour_words,
    is_several,
    load_objects,
    perceives,
    plan,
    require_grips,
)
from grip_env.cli.options import ConfigFile
from grip_env.cli.paths import output_file

if TYPE_CHECKING:
    from grip_env.config import Config
    from grip_env.sim import TrialResult


def show(
    obj: Annotated[str, typer.Argument(
        metavar="OBJECT", help=f"{OBJECT_HELP} (drawn side by side)")],
    out: Annotated[
        Path, typer.Option("--out", "-o", help="PNG file to write (its name ends in .png)")
    ] = Path("show.png"),
    grips: Annotated[int, typer.Option(
        min=0,
        help="draw the best N grips by Q_C (0: regions only) of each object; with --sim, "
             "simulate the best N (0 or 1: the best grip), one row of frames each"
    )] = 0,
    config: ConfigFile = None,
    mm_per_px: MmPerPxOption = None,
    contour: ContourOption = None,
    sim: Annotated[bool, typer.Option(
        "--sim", help="simulate the best grip (or the best --grips N) in the config's engine "
                      "(sim.engine) on the true object and draw its phases: approach, close, "
                      "lift, disturbance ramp; prints each outcome"
    )] = False,
    seed: Annotated[int, typer.Option(
        min=0, help="seed of the simulated trial's draw (friction, mass, placement error)"
    )] = 0,
) -> None:
    """Draw OBJECT with its grasping regions (and grips) to a PNG, or with --sim the phases of
    simulated trials of its best grips.

    Regions and grips are found where generate finds them: on the perceived contour by default
    (see --contour); the figure's title says which, and so does the output when grips are
    drawn. Exit codes: 0 done; 2 bad input, or grips asked for (--grips N, --sim) and no object
    has a feasible one (nothing is written).
    """
    with user_errors():
        from grip_env.config import load_config

        output_file(out, ".png")
        cfg = load_config(config)
        objects = load_objects(obj, mm_per_px, cfg)
        several = is_several(obj)
        if sim and several:
            raise ValueError(f"--sim simulates one object, and {obj} names {len(objects)}")
        perceive = perceives(contour, cfg)
        planned = plan(objects, cfg, perceive, with_grips=bool(grips) or sim)
        if grips or sim:
            require_grips(planned, perceive, cfg)
            typer.echo(f"planned on {contour_words(perceive)}")
        if sim:
            path = _render_trial(planned[0], cfg, max(grips, 1), seed, out)
        else:
            _echo_best(planned, grips)
            path = (_draw_sheet(planned, cfg, grips, out) if several
                    else _draw(planned[0], cfg, grips, out))
    typer.echo(f"wrote {path}")


def _echo_best(planned: list[PlannedObject], grips: int) -> None:
    """Print the drawn grips of each object, and the objects without any."""
    if not grips:
        return
    for item in planned:
        if item.table is None or item.table.empty:
            typer.echo(f"{item.name}: no feasible grip")
            continue
        best = item.table.head(grips)
        shown = ", ".join(f"{g} (Q_C {q:.2f})" for g, q in zip(best["grip_id"], best["Q_C"],
                                                               strict=True))
        typer.echo(f"{item.name}: best {len(best)} of {len(item.table)} grips by Q_C: {shown}")


def _draw_sheet(planned: list[PlannedObject], cfg: Config, grips: int, out: Path) -> Path:
    """Every object with its regions (and its best ``grips`` grips), side by side (up to 6 a
    row), in one PNG."""
    from matplotlib.figure import Figure

    from grip_env.drawing import draw_grip, draw_object, save_figure
    from grip_env.perception.regions import find_regions

    columns = min(6, len(planned))
    rows = -(-len(planned) // columns)
    fig = Figure(figsize=(2.6 * columns, 2.6 * rows))
    axes = fig.subplots(rows, columns, squeeze=False)
    for ax in axes.flat[len(planned):]:
        ax.set_axis_off()
    for ax, item in zip(axes.flat, planned, strict=False):
        regions = find_regions(item.planned_on, cfg.perception, cfg.grasp)
        draw_object(ax, item.planned_on, regions)
        title = f"{item.name}: {len(regions)} regions"
        if grips and item.table is not None:
            best = item.table.head(grips)
            for rank, (_, grip) in enumerate(best.iterrows()):
                draw_grip(ax, grip, highlight=rank == 0)
            title += f", best {len(best)} grips" if len(best) else ", no feasible grip"
        ax.set_title(title, fontsize=8)
    found = "regions and grips" if grips else "regions"
    fig.suptitle(f"{found} on each object's {planned[0].outline}", fontsize=9)
    fig.tight_layout()
    return save_figure(fig, out)


def _draw(item: PlannedObject, cfg: Config, grips: int, out: Path) -> Path:
    from grip_env.drawing import object_figure, save_figure
    from grip_env.perception.regions import find_regions

    regions = find_regions(item.planned_on, cfg.perception, cfg.grasp)
    table = None if not grips or item.table is None else item.table.head(grips)
    title = f"{item.name}: {len(regions)} regions on its {item.outline}"
    if table is not None:
        title += f", best {len(table)} grips by Q_C"
    return save_figure(object_figure(item.planned_on, regions, table, title), out)


def _render_trial(item: PlannedObject, cfg: Config, grips: int, seed: int, out: Path) -> Path:
    """Simulate the best ``grips`` grips on the true object (trial 0 of ``seed`` each), print
    each outcome and draw each trial's phases in one row."""
    from grip_env.drawing import save_figure, trial_figure
    from grip_env.sim import TRIAL_PHASES, trial_frames

    planar, table = item.true, item.table
    assert table is not None  # planned with grips
    best = table.head(grips)
    trials = trial_frames(planar, best, cfg, seed, width=360, height=270)
    rows = []
    for rank, ((_, grip), (result, frames)) in enumerate(
        zip(best.iterrows(), trials, strict=True), start=1
    ):
        outcome = result.describe()
        typer.echo(f"trial of {grip['grip_id']} in {cfg.sim.engine}: {outcome}")
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

    app.command("show", epilog=f"Shape names: {', '.join(SHAPE_NAMES)}. {MESH_HELP}")(show)
