"""``grip-env export minari``: a dataset's ``GripSelect-v0`` episodes as a Minari dataset, for
offline RL (needs the ``offline`` extra)."""

from __future__ import annotations

from enum import StrEnum
from typing import Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.options import STANDARD_DATA, DatasetDir
from grip_env.shutdown import stop_on_signals


class ExportFormat(StrEnum):
    """The format written (Minari, the Farama Foundation's offline-RL datasets)."""

    minari = "minari"


class Policy(StrEnum):
    """``--policy``: the behaviour policy that logs the episodes."""

    uniform = "uniform"
    epsilon_qc = "epsilon-qc"


class Split(StrEnum):
    """``--split``: the objects whose episodes are exported."""

    train = "train"
    test = "test"
    all = "all"


def export(
    format: Annotated[ExportFormat, typer.Argument(help="the format: minari")],
    dataset_id: Annotated[str, typer.Option(
        "--id", help="the Minari dataset id, [namespace/]name-v<version>; written under "
                     "MINARI_DATASETS_PATH (default ~/.minari/datasets)")
    ] = "grip-env/standard-uniform-v0",
    data: DatasetDir = STANDARD_DATA,
    split: Annotated[Split, typer.Option(
        help="the objects whose episodes are exported: train (the standard split's training "
             "objects on the standard dataset: an offline learner never sees a held-out one), "
             "test or all")] = Split.train,
    episodes: Annotated[int, typer.Option(min=1, max=10_000,
                                          help="episodes per object")] = 10,
    policy: Annotated[Policy, typer.Option(
        help="behaviour policy: uniform (every valid slot alike) or epsilon-qc (the lowest-Q_C "
             "valid slot with probability 1 - epsilon, else uniform)")] = Policy.uniform,
    epsilon: Annotated[float, typer.Option(min=0.0, max=1.0,
                                           help="epsilon of epsilon-qc")] = 0.1,
    seed: Annotated[int, typer.Option(min=0, help="seed of the environment and the "
                                                  "behaviour policy")] = 0,
    max_attempts: Annotated[int | None, typer.Option(
        min=1, help="executions per episode [default: the config's selector.max_attempts, 1]")
    ] = None,
    author: Annotated[str, typer.Option(help="the dataset's author (Minari metadata)")] = (
        "The grip-env authors"),
    overwrite: Annotated[bool, typer.Option(
        help="replace a Minari dataset of the same id")] = False,
) -> None:
    """Log EPISODES episodes of every object of DATA's split in GripSelect-v0 (replay) with a
    seeded behaviour policy and write them as the Minari dataset ID: observations are the
    environment's Dict(features, mask) (Minari has no action mask of its own), rewards the
    replayed recorded trials (1 hold, 0 drop), infos the executed slot's recorded success rate.
    The metadata holds the env spec, the evaluation env (the held-out objects), the reference
    scores (exact random and oracle returns there), the behaviour policy, the objects, the
    dataset's sha256 and grip-env's version. An existing ID is refused unless --overwrite; bad
    input writes nothing (exit 2)."""
    with stop_on_signals(f"rerun with --overwrite to redo {dataset_id}"), user_errors():
        from grip_env.offline.behaviour import BehaviourPolicy
        from grip_env.offline.minari_export import ExportPlan, check_dataset_id, export_minari

        plan = ExportPlan(dataset_id, str(data), split.value, episodes,
                          BehaviourPolicy(policy.value, epsilon if policy != "uniform" else 0.0),
                          seed, max_attempts)  # fmt: skip
        check_dataset_id(dataset_id, overwrite)
        from classifiers.experiments.selector.data import check_grip_table
        from classifiers.learners.persistence import dataset_checksum
        from grip_env.cli import package_version

        checksum = dataset_checksum(_bare(check_grip_table(data)))
        dataset = export_minari(plan, overwrite=overwrite, dataset_sha256=checksum,
                                code_version=_code_version(package_version()), author=author)
    meta = dataset.storage.metadata
    typer.echo(f"wrote Minari dataset {dataset_id}: {meta['total_episodes']} episodes, "
               f"{meta['total_steps']} steps of {len(meta['grip_env']['objects'])} objects "
               f"({format.value}, {meta['dataset_size']} MB); reference scores: random "
               f"{meta['ref_min_score']:.4f}, oracle {meta['ref_max_score']:.4f}")  # fmt: skip


def _bare(table: object) -> object:
    """The table without its manifest ``attrs``, as the benchmark checksums it."""
    bare = table.copy(deep=False)  # type: ignore[attr-defined]
    bare.attrs = {}
    return bare


def _code_version(version: str) -> str:
    from grip_env.dataset.manifest import current_commit

    commit = current_commit()
    return f"{version} (commit {commit})" if commit else version


def register(app: typer.Typer) -> None:
    """Add the command to the CLI."""
    app.command("export")(export)
