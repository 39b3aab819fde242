"""``grip-env generate``: simulate grips of many objects into a resumable Parquet dataset."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, NoReturn

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.options import ConfigFile
from grip_env.shutdown import stop_on_signals

if TYPE_CHECKING:
    from grip_env.objects import PlanarObject


def generate(
    out: Annotated[Path, typer.Option("--out", "-o", help="dataset directory (created if needed)")],
    config: ConfigFile = None,
    objects: Annotated[
        str | None,
        typer.Option(help="object set name (e.g. default; meshes: household, random_urdfs, "
                          "mesh), a number of procedural objects, or your own: a folder or glob "
                          "of images (scale: --mm-per-px or the folder's scale.yaml) or vertex "
                          "files (.csv x,y or .json [[x, y], ...], in mm) "
                          "(default: config objects.set + objects.procedural_count)"),
    ] = None,
    mm_per_px: Annotated[
        float | None,
        typer.Option("--mm-per-px", help="scale of the images given by --objects (required "
                                         "for images unless their folder's scale.yaml "
                                         "gives it)"),
    ] = None,
    trials: Annotated[
        int | None,
        typer.Option(min=1, help="simulated trials per grip (default: config dataset.trials)"),
    ] = None,
    seed: Annotated[
        int | None, typer.Option(min=0, help="run seed (default: config dataset.seed)")
    ] = None,
    workers: Annotated[
        int | None,
        typer.Option(min=1, help="parallel workers; the data do not depend on it "
                          "(default: config dataset.workers)"),
    ] = None,
    backend: Annotated[
        str | None,
        typer.Option(help="process (local process pool) or ray (default: config dataset.backend)"),
    ] = None,
    address: Annotated[
        str | None,
        typer.Option(help="Ray cluster address, e.g. HEAD_IP:6379 or ray://host:10001 (default: "
                          "$RAY_ADDRESS, else a new local Ray)"),
    ] = None,
    overwrite: Annotated[
        bool, typer.Option("--overwrite", help="replace a dataset made with other settings")
    ] = False,
    progress: Annotated[bool, typer.Option(help="show a progress bar")] = True,
) -> None:
    """Plan grips on every object, simulate a stratified sample of them, write a Parquet dataset.

    Grips are planned on each object's perceived contour (rendered from above and segmented,
    perception.source: render, the default; polygon: its true outline) and simulated on the
    true object; the output says which, and names the objects that got no feasible grip.

    Rerunning the same command after an interruption computes only the missing objects;
    rerunning with other settings into the same OUT is refused unless --overwrite, and so is
    a second run while one is writing OUT. Exit codes: 0 done; 1 the run failed (a worker
    lost twice on one object, a full disk): finished objects are kept, rerun to finish;
    2 bad input; 130, 143, 129 stopped by SIGINT, SIGTERM, SIGHUP: rerun to finish.
    """
    with stop_on_signals(f"rerun the same command to finish {out}"), user_errors():
        from grip_env.config import load_config
        from grip_env.dataset import WorkerLost, dataset_manifest
        from grip_env.dataset import generate as generate_dataset
        from grip_env.dataset.jobs import plans_on_render
        from grip_env.sim.engine import require_engine

        cfg = load_config(config)
        require_engine(cfg.sim.engine)
        _check_flags(objects, trials, seed, workers)
        chosen_objects = _objects(objects, mm_per_px)
        chosen = backend or cfg.dataset.backend
        if address is not None and chosen != "ray":
            raise ValueError(f"--address {address} needs --backend ray (the backend is {chosen})")
        try:
            path = generate_dataset(
                cfg, out, objects=chosen_objects, trials=trials, seed=seed, workers=workers,
                backend=backend, address=address, progress=progress, overwrite=overwrite,
            )
        except WorkerLost as exc:
            _fail(f"{exc}; finished objects are kept: rerun the same command to finish {out}")
        except OSError as exc:
            _fail(f"cannot write the dataset in {out}: {exc.strerror or exc}; finished objects "
                  f"are kept: free space and rerun the same command to finish")
        manifest = dataset_manifest(path)
        contours = "perceived contours" if plans_on_render(cfg) else "true outlines"
    typer.echo(f"wrote {path}: {manifest['rows']} grips of {len(manifest['objects'])} objects, "
               f"planned on their {contours}")
    _report_objects_without_grips(manifest)


def _check_flags(
    objects: str | None, trials: int | None, seed: int | None, workers: int | None
) -> None:
    """Bound the flags as the config keys they override are bounded, before any work."""
    from grip_env.config import check_setting

    for key, value, flag in (("trials", trials, "--trials"), ("seed", seed, "--seed"),
                             ("workers", workers, "--workers")):
        if value is not None:
            check_setting("dataset", key, value, flag)
    if objects is not None and objects.strip().isdigit():
        check_setting("objects", "procedural_count", int(objects), "--objects")


def _objects(spec: str | None, mm_per_px: float | None) -> str | list[PlanarObject] | None:
    """What ``--objects`` names: a set or a count (as given), or the objects of its files."""
    from grip_env.objects import OBJECT_SETS, SHAPE_NAMES
    from grip_env.objects.meshes import MESH_SET_NAMES
    from grip_env.objects.sources import check_file_spec, is_path_spec, objects_from_path

    named = spec is None or spec.strip().lstrip("-").isdigit() or spec in OBJECT_SETS or (
        spec in SHAPE_NAMES) or spec in MESH_SET_NAMES
    if named:
        if mm_per_px is not None:
            raise ValueError(f"--mm-per-px {mm_per_px:g} is for image files given by --objects")
        return spec
    check_file_spec(spec)
    if not is_path_spec(spec):
        raise ValueError(
            f"--objects: unknown object set {spec!r}, and no such file, folder or glob "
            f"(sets: {', '.join((*OBJECT_SETS, *MESH_SET_NAMES))}, a shape name, or a number)"
        )
    return objects_from_path(spec, mm_per_px)


#: The most objects without grips ``generate`` names on the console.
NAMED_WITHOUT_GRIPS = 10


def _report_objects_without_grips(manifest: dict) -> None:
    """Name the objects that got no feasible grip (the first few, and how to list them all)."""
    from grip_env.dataset.manifest import objects_without_grips

    empty = objects_without_grips(manifest)
    if not empty:
        return
    named = ", ".join(empty[:NAMED_WITHOUT_GRIPS])
    more = (f" and {len(empty) - NAMED_WITHOUT_GRIPS} more (every object whose shard has rows 0 "
            "in manifest.json)") if len(empty) > NAMED_WITHOUT_GRIPS else ""
    typer.echo(f"{len(empty)} of {len(manifest['objects'])} objects got no feasible grip: "
               f"{named}{more}")


def _fail(message: str) -> NoReturn:
    """A run that failed for a reason outside the user's input: one line, exit code 1."""
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=1)


def register(app: typer.Typer) -> None:
    """Add the command to the CLI."""
    app.command("generate")(generate)
