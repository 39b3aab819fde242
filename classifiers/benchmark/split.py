"""The benchmark's standard split: fixed, versioned held-out objects and training seeds.

``grip-select-standard`` v1 is the study's object split of the default dataset
(``runs/default/dataset``, 52 objects: 7 basic shapes and 45 procedural ones):
:func:`grip_env.dataset.split.split_objects` with ``test_fraction=0.25`` and seed 0 holds out the
13 objects of :data:`STANDARD_TEST_OBJECTS`. Pinning the ids (rather than re-deriving them from
whatever dataset is given) keeps two users' numbers on the same objects; a dataset that lacks
any of them is refused. A method is trained on the other objects only.

Each held-out object shows its ``max_candidates`` (64) best grips by ``Q_C``, lowest first, with
the twelve features S1..C6 under the signed-log normalisation: exactly the observation of
``GripSelect-v0`` with its defaults. Stochastic methods are run with the training seeds
``0..4`` (a run per seed); a deterministic method is one run.

A new version (other objects, seeds or candidates) gets a new ``version``; the leaderboard
records the version and the dataset's checksum.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

import pandas as pd

from grip_env.columns import FEATURES
from grip_env.config import Config
from grip_env.dataset.split import held_out_objects
from grip_env.envs.observation import CandidateSet

STANDARD_TEST_OBJECTS: tuple[str, ...] = (
    "l_shape", "proc_0_00003", "proc_0_00004", "proc_0_00011", "proc_0_00015", "proc_0_00017",
    "proc_0_00018", "proc_0_00022", "proc_0_00023", "proc_0_00029", "proc_0_00030",
    "proc_0_00031", "proc_0_00035",
)  # fmt: skip


@dataclass(frozen=True)
class BenchmarkSplit:
    """Which objects are held out, how their candidates are shown, and the training seeds."""

    name: str
    version: int
    test_objects: tuple[str, ...]
    seeds: tuple[int, ...]
    max_candidates: int = 64
    features: tuple[str, ...] = FEATURES
    normalize: str = "log"
    test_fraction: float = 0.25
    split_seed: int = 0

    def describe(self) -> dict[str, object]:
        """The split as JSON values (for the leaderboard)."""
        found = asdict(self)
        return {k: list(v) if isinstance(v, tuple) else v for k, v in found.items()}


STANDARD_SPLIT = BenchmarkSplit("grip-select-standard", 1, STANDARD_TEST_OBJECTS, (0, 1, 2, 3, 4))


def check_standard_objects(table: pd.DataFrame, split: BenchmarkSplit = STANDARD_SPLIT) -> None:
    """ValueError naming the held-out objects of ``split`` that ``table`` lacks."""
    present = set(table["object_id"].astype(str))
    missing = [oid for oid in split.test_objects if oid not in present]
    if missing:
        raise ValueError(
            f"dataset lacks {len(missing)} of the {len(split.test_objects)} objects of the "
            f"standard split {split.name} v{split.version} (e.g. {missing[:3]}); generate it with "
            f"the default config (grip-env generate) to benchmark on the standard split"
        )


def study_split(table: pd.DataFrame, config: Config, seeds: Sequence[int]) -> BenchmarkSplit:
    """The standard split when the study's own held-out objects are it, else the study's split."""
    learning = config.learning
    _, test = held_out_objects(table["object_id"].astype(str), learning)
    standard = (test == STANDARD_TEST_OBJECTS
                and config.selector.max_candidates == STANDARD_SPLIT.max_candidates)  # fmt: skip
    return BenchmarkSplit(
        STANDARD_SPLIT.name if standard else "study", STANDARD_SPLIT.version if standard else 0,
        tuple(test), tuple(int(s) for s in seeds), config.selector.max_candidates,
        test_fraction=learning.test_fraction, split_seed=learning.seed,
    )  # fmt: skip


def split_config(config: Config, split: BenchmarkSplit) -> Config:
    """``config`` with the split's candidate count and object split."""
    return config.override(
        selector={"max_candidates": split.max_candidates},
        learning={"test_fraction": split.test_fraction, "seed": split.split_seed},
    )


def candidate_sets(table: pd.DataFrame, config: Config, split: BenchmarkSplit) -> list[
        CandidateSet]:  # fmt: skip
    """The held-out objects' candidate sets, as ``GripSelect-v0`` shows them."""
    from classifiers.selector.evaluation import _test_candidate_sets

    sets = _test_candidate_sets(table, split_config(config, split), split.test_objects)
    if not sets:
        raise ValueError("no held-out object of the split has a candidate grip")
    return sets


def candidate_table(sets: Sequence[CandidateSet]) -> pd.DataFrame:
    """One row per (object, candidate slot): the candidate's columns, ``candidate`` = slot and
    ``success_rate`` as the environments read it (successes / trials)."""
    frames = [s.rows.assign(object_id=s.object_id, candidate=range(s.count),
                            success_rate=s.success_rate[: s.count]) for s in sets]  # fmt: skip
    return pd.concat(frames, ignore_index=True)
