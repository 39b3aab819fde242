"""The benchmark's standard split: fixed, versioned held-out objects and training seeds.

A version pins the held-out object ids, so two users' numbers are on the same objects; a
dataset that lacks any of them is refused. Each version's objects are
:func:`grip_env.dataset.split.split_objects` (``test_fraction=0.25``, seed 0) of the objects with
grips of the default dataset of its time (``grip-env generate`` with the default config), listed
in :data:`DEFAULT_OBJECTS` (a test re-derives each version's objects from that list):

- v3 (:data:`STANDARD_SPLITS` ``[3]``, the default): the 69 objects with grips of the default
  study's dataset at commit fc22e61 (80 objects: 18 named, 44 procedural, 18 meshes; planned on
  the render; 11 get no grip);
- v2: 53 objects of the default set at commit 423a072 (18 named, 24 procedural, 18 meshes);
- v1: the 52 objects of ``runs/default/dataset`` (named and procedural shapes) before that;
  ``grip-env benchmark --split-version 1`` scores a dataset of that time.

A method is trained on the other objects only. Each held-out object shows its
``max_candidates`` (64) best grips by ``Q_C``, lowest first, with the twelve features S1..C6
under the signed-log normalisation: exactly the observation of ``GripSelect-v0`` with its
defaults. Stochastic methods are run with the training seeds ``0..4`` (a run per seed); a
deterministic method is one run. A change of objects, candidates or seeds is a new version; the
leaderboard records the version and the dataset's checksum.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

import pandas as pd

from grip_env.columns import FEATURES
from grip_env.config import Config
from grip_env.dataset.split import held_out_objects
from grip_env.envs.observation import CandidateSet

DEFAULT_OBJECTS_V1: tuple[str, ...] = (
    "bean", "disc", "ellipse", "hexagon", "l_shape", "parallelogram", "pentagon", "proc_0_00000",
    "proc_0_00001", "proc_0_00002", "proc_0_00003", "proc_0_00004", "proc_0_00005", "proc_0_00006",
    "proc_0_00007", "proc_0_00008", "proc_0_00009", "proc_0_00010", "proc_0_00011", "proc_0_00012",
    "proc_0_00014", "proc_0_00015", "proc_0_00016", "proc_0_00017", "proc_0_00018", "proc_0_00020",
    "proc_0_00021", "proc_0_00022", "proc_0_00023", "proc_0_00024", "proc_0_00025", "proc_0_00026",
    "proc_0_00027", "proc_0_00028", "proc_0_00029", "proc_0_00030", "proc_0_00031", "proc_0_00032",
    "proc_0_00035", "proc_0_00037", "proc_0_00039", "proc_0_00040", "proc_0_00041", "rectangle",
    "right_triangle", "rounded_rectangle", "square", "star", "t_shape", "trapezoid", "triangle",
    "u_shape",
)  # fmt: skip

DEFAULT_OBJECTS_V2: tuple[str, ...] = (
    "bean", "bunny", "cube", "disc", "domino", "duck", "ellipse", "hexagon", "jenga", "l_shape",
    "mug", "parallelogram", "pentagon", "proc_0_00000", "proc_0_00001", "proc_0_00002",
    "proc_0_00003", "proc_0_00004", "proc_0_00005", "proc_0_00006", "proc_0_00007", "proc_0_00008",
    "proc_0_00009", "proc_0_00010", "proc_0_00011", "proc_0_00012", "proc_0_00014", "proc_0_00015",
    "proc_0_00016", "proc_0_00017", "proc_0_00018", "proc_0_00020", "proc_0_00021", "proc_0_00022",
    "proc_0_00023", "rectangle", "right_triangle", "rounded_rectangle", "square", "star",
    "t_shape", "trapezoid", "triangle", "u_shape", "urdf_162", "urdf_206", "urdf_222", "urdf_264",
    "urdf_459", "urdf_674", "urdf_683", "urdf_711", "urdf_814",
)  # fmt: skip

DEFAULT_OBJECTS_V3: tuple[str, ...] = (
    "bean", "bunny", "cube", "disc", "domino", "duck", "ellipse", "hexagon", "jenga", "l_shape",
    "lego", "mug", "parallelogram", "pentagon", "proc_0_00000", "proc_0_00001", "proc_0_00002",
    "proc_0_00003", "proc_0_00004", "proc_0_00005", "proc_0_00006", "proc_0_00007", "proc_0_00008",
    "proc_0_00009", "proc_0_00010", "proc_0_00011", "proc_0_00012", "proc_0_00014", "proc_0_00015",
    "proc_0_00016", "proc_0_00017", "proc_0_00018", "proc_0_00020", "proc_0_00021", "proc_0_00022",
    "proc_0_00023", "proc_0_00024", "proc_0_00025", "proc_0_00026", "proc_0_00027", "proc_0_00028",
    "proc_0_00029", "proc_0_00030", "proc_0_00032", "proc_0_00034", "proc_0_00035", "proc_0_00037",
    "proc_0_00039", "proc_0_00040", "proc_0_00041", "proc_0_00042", "proc_0_00043", "rectangle",
    "right_triangle", "rounded_rectangle", "square", "star", "t_shape", "trapezoid", "triangle",
    "u_shape", "urdf_206", "urdf_222", "urdf_264", "urdf_459", "urdf_518", "urdf_683", "urdf_711",
    "urdf_814",
)  # fmt: skip

STANDARD_TEST_OBJECTS_V1: tuple[str, ...] = (
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


STANDARD_TEST_OBJECTS_V2: tuple[str, ...] = (
    "domino", "mug", "parallelogram", "proc_0_00005", "proc_0_00008", "proc_0_00010",
    "proc_0_00011", "proc_0_00015", "proc_0_00016", "proc_0_00023", "rectangle",
    "right_triangle", "square",
)  # fmt: skip
STANDARD_TEST_OBJECTS: tuple[str, ...] = (
    "domino", "jenga", "lego", "proc_0_00002", "proc_0_00005", "proc_0_00006", "proc_0_00009",
    "proc_0_00014", "proc_0_00022", "proc_0_00024", "proc_0_00032", "proc_0_00034", "proc_0_00039",
    "square", "trapezoid", "urdf_264", "urdf_518",
)  # fmt: skip
_SEEDS = (0, 1, 2, 3, 4)
STANDARD_SPLITS: dict[int, BenchmarkSplit] = {
    1: BenchmarkSplit("grip-select-standard", 1, STANDARD_TEST_OBJECTS_V1, _SEEDS),
    2: BenchmarkSplit("grip-select-standard", 2, STANDARD_TEST_OBJECTS_V2, _SEEDS),
    3: BenchmarkSplit("grip-select-standard", 3, STANDARD_TEST_OBJECTS, _SEEDS),
}
STANDARD_SPLIT = STANDARD_SPLITS[max(STANDARD_SPLITS)]
#: The objects each version's held-out objects were drawn from.
DEFAULT_OBJECTS: dict[int, tuple[str, ...]] = {
    1: DEFAULT_OBJECTS_V1, 2: DEFAULT_OBJECTS_V2, 3: DEFAULT_OBJECTS_V3,
}


def standard_split(version: int | None = None) -> BenchmarkSplit:
    """The standard split of ``version`` (default: the latest); unknown → ValueError."""
    if version is None:
        return STANDARD_SPLIT
    if version not in STANDARD_SPLITS:
        raise ValueError(f"unknown standard split version {version!r}; known: "
                         f"{sorted(STANDARD_SPLITS)}")  # fmt: skip
    return STANDARD_SPLITS[version]


def check_standard_objects(table: pd.DataFrame, split: BenchmarkSplit = STANDARD_SPLIT) -> None:
    """ValueError naming the held-out objects of ``split`` that ``table`` lacks."""
    present = set(table["object_id"].astype(str))
    missing = [oid for oid in split.test_objects if oid not in present]
    if missing:
        raise ValueError(
            f"dataset lacks {len(missing)} of the {len(split.test_objects)} objects of the "
            f"standard split {split.name} v{split.version} (e.g. {missing[:3]}); generate it with "
            f"the default config (grip-env generate), or give the --split-version of its time "
            f"(known: {sorted(STANDARD_SPLITS)})"
        )


def study_split(table: pd.DataFrame, config: Config, seeds: Sequence[int]) -> BenchmarkSplit:
    """The standard split when the study's own held-out objects are it, else the study's split."""
    learning = config.learning
    _, test = held_out_objects(table["object_id"].astype(str), learning)
    found = [v for v, s in STANDARD_SPLITS.items() if s.test_objects == tuple(test)
             and config.selector.max_candidates == s.max_candidates]  # fmt: skip
    return BenchmarkSplit(
        STANDARD_SPLIT.name if found else "study", found[0] if found else 0,
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
    from classifiers.experiments.selector.evaluation import _test_candidate_sets

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
