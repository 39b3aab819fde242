"""Grip datasets: Parquet shards per object, a manifest, parallel and resumable generation.

>>> from grip_env.dataset import generate, load, validate      # doctest: +SKIP
>>> path = generate(load_config(), "runs/data", objects=3)      # doctest: +SKIP
>>> grips = load(path); problems = validate(path)               # doctest: +SKIP
"""

from grip_env.dataset.backends import BACKENDS, WorkerLost
from grip_env.dataset.catalog import load_objects, load_perceived_objects, read_objects
from grip_env.dataset.generation import DatasetMismatchError, generate
from grip_env.dataset.jobs import (
    ObjectJob,
    ObjectTask,
    planned_candidates,
    planned_object,
    simulate_object,
    with_outcomes,
)
from grip_env.dataset.loading import (
    dataset_label_model,
    dataset_manifest,
    label_model_notice,
    load,
)
from grip_env.dataset.manifest import FORMAT_VERSION, CorruptManifestError, FormatVersionError
from grip_env.dataset.sampling import keep_grips, kept_ranks
from grip_env.dataset.split import held_out_objects, split_objects, split_table
from grip_env.dataset.validation import validate

__all__ = [
    "BACKENDS",
    "FORMAT_VERSION",
    "CorruptManifestError",
    "DatasetMismatchError",
    "FormatVersionError",
    "ObjectJob",
    "ObjectTask",
    "WorkerLost",
    "dataset_label_model",
    "dataset_manifest",
    "generate",
    "held_out_objects",
    "keep_grips",
    "kept_ranks",
    "label_model_notice",
    "load",
    "load_objects",
    "load_perceived_objects",
    "planned_candidates",
    "planned_object",
    "read_objects",
    "simulate_object",
    "split_objects",
    "split_table",
    "validate",
    "with_outcomes",
]
