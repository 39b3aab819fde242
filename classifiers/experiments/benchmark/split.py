"""The benchmark's split: the standard one (fixed, versioned held-out objects and training seeds)
or, for a dataset without its objects, a seeded split of the dataset's own objects.

A version pins the held-out object ids, so two users' numbers are on the same objects; a
dataset that lacks grips of any of them cannot be scored on that version. :func:`choose_split`
picks the split: with ``--split auto`` (the default) the latest version whose held-out objects
all have grips in the dataset, else :func:`auto_split`, a seeded split of the dataset's own
objects named :data:`AUTO_SPLIT_NAME` (never to be compared with standard-split scores); with
``--split standard`` (or a ``--split-version``) that version or a refusal saying what fits
instead. Each version's objects are
:func:`grip_env.dataset.split.split_objects` (``test_fraction=0.25``, seed 0) of the objects with
grips of the default dataset of its time (``grip-env generate`` with the default config), listed
in :data:`DEFAULT_OBJECTS` (a test re-derives each version's objects from that list):

- v4 (:data:`STANDARD_SPLITS` ``[4]``, the default): 128 held-out objects of the 510 with grips
  of the shipped standard dataset (``grip_env.datasets``, ``configs/standard.yaml``: 23 named
  shapes and named meshes, 279 procedural shapes, 208 ``pybullet_data`` meshes), each showing
  all its grips (at most 24);
- v3: the 69 objects with grips of the default
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
from typing import Any

import pandas as pd

from grip_env.columns import FEATURES
from grip_env.config import Config
from grip_env.dataset.split import held_out_objects, split_objects
from grip_env.envs.observation import CandidateSet


def object_ids(named: str, procedural: str, meshes: str = "") -> tuple[str, ...]:
    """Sorted object ids from named ids, procedural indices (``"0-2 5"``: ``proc_0_00000`` to
    ``proc_0_00002`` and ``proc_0_00005``) and mesh numbers (``"518"``: ``urdf_518``)."""
    numbers = [n for part in procedural.split() for n in _span(part)]
    return tuple(sorted([*named.split(), *(f"proc_0_{n:05d}" for n in numbers),
                         *(f"urdf_{m}" for m in meshes.split())]))  # fmt: skip


def _span(part: str) -> range:
    low, _, high = part.partition("-")
    return range(int(low), int(high or low) + 1)


_NAMED = ("bean disc ellipse hexagon l_shape parallelogram pentagon rectangle right_triangle "
          "rounded_rectangle square star t_shape trapezoid triangle u_shape")  # fmt: skip
_NAMED_MESHES = "bunny cube domino duck jenga mug"  # named mesh objects since 423a072
DEFAULT_OBJECTS_V1 = object_ids(_NAMED, "0-12 14-18 20-32 35 37 39-41")
DEFAULT_OBJECTS_V2 = object_ids(f"{_NAMED} {_NAMED_MESHES}", "0-12 14-18 20-23",
                                "162 206 222 264 459 674 683 711 814")  # fmt: skip
DEFAULT_OBJECTS_V3 = object_ids(f"{_NAMED} {_NAMED_MESHES} lego",
                                "0-12 14-18 20-30 32 34-35 37 39-43",
                                "206 222 264 459 518 683 711 814")  # fmt: skip
#: The standard dataset's 510 objects with grips (``configs/standard.yaml``, label model
#: ``2026.12-xm``; its meshes are numbered with three digits).
_STANDARD_MESHES = (
    "002 005 013 019 023 026 028 031 045 046 049 053 054 056 068 074 077 081 084 089 094 098 "
    "099 100 103 105 106 111 112 117 121 136 138 141 142 144 150 153 160 164 173 181 186 189 "
    "194 195 201 206 208 209 212 220 222 234 238 244 253 264 269 270 274 281 284 292 296 297 "
    "313 314 323 325 329 330 334 337 340 344 346 356 363 365 371 374 380 386 388 391 398 401 "
    "403 406 412 416 421 423 429 436 439 445 447 450 451 459 464 471 472 474 477 480 481 498 "
    "502 505 508 509 511 519 522 529 530 534 539 544 555 556 558 566 567 577 579 580 583 584 "
    "590 611 625 626 628 629 631 635 641 647 651 652 665 672 673 674 676 679 683 705 707 711 "
    "714 734 735 762 767 768 769 785 786 793 812 813 814 821 829 843 853 859 862 863 865 870 "
    "876 878 879 882 890 898 901 903 905 912 920 922 926 927 928 930 931 945 946 947 953 954 "
    "958 968 972 978 979 984 989 990 991 994"
)
DEFAULT_OBJECTS_V4 = object_ids(
    f"{_NAMED} {_NAMED_MESHES} lego",
    "0-12 14-18 20-30 32 34-35 37 39-44 47-64 66-88 90-97 99-104 106-108 110-114 116 118-122 "
    "124-128 131-138 140-143 145-159 162-163 165-171 175-178 180-184 186-188 191-211 213-229 "
    "231-239 241-270 272-274 276-280 282-287 289-292 295-303 305-311 313-319",
    _STANDARD_MESHES,
)  # fmt: skip

STANDARD_TEST_OBJECTS_V1: tuple[str, ...] = (
    "l_shape", "proc_0_00003", "proc_0_00004", "proc_0_00011", "proc_0_00015", "proc_0_00017",
    "proc_0_00018", "proc_0_00022", "proc_0_00023", "proc_0_00029", "proc_0_00030",
    "proc_0_00031", "proc_0_00035",
)  # fmt: skip


STANDARD_NAME = "grip-select-standard"
#: The name of a seeded split of a dataset's own objects: it says it is not the standard one.
AUTO_SPLIT_NAME = "auto-not-standard"
#: ``--split``: ``auto`` (the standard split when its objects are there, else a seeded split of
#: the dataset's own objects) or ``standard`` (the standard split or an error).
SPLIT_MODES = ("auto", "standard")


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

    @property
    def standard(self) -> bool:
        """Whether this is a version of the standard split (scores compare across users)."""
        return self.name == STANDARD_NAME

    def describe(self) -> dict[str, object]:
        """The split as JSON values (for the leaderboard)."""
        found = {**asdict(self), "standard": self.standard}
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
#: v4: 128 of the standard dataset's 510 objects with grips.
STANDARD_TEST_OBJECTS_V4: tuple[str, ...] = (
    "cube", "duck", "proc_0_00001", "proc_0_00004", "proc_0_00005", "proc_0_00014",
    "proc_0_00024", "proc_0_00026", "proc_0_00027", "proc_0_00029", "proc_0_00044",
    "proc_0_00048", "proc_0_00049", "proc_0_00057", "proc_0_00062", "proc_0_00066",
    "proc_0_00070", "proc_0_00078", "proc_0_00079", "proc_0_00080", "proc_0_00083",
    "proc_0_00084", "proc_0_00085", "proc_0_00090", "proc_0_00094", "proc_0_00095",
    "proc_0_00100", "proc_0_00107", "proc_0_00110", "proc_0_00120", "proc_0_00126",
    "proc_0_00128", "proc_0_00137", "proc_0_00141", "proc_0_00148", "proc_0_00151",
    "proc_0_00153", "proc_0_00154", "proc_0_00159", "proc_0_00163", "proc_0_00169",
    "proc_0_00176", "proc_0_00180", "proc_0_00197", "proc_0_00205", "proc_0_00213",
    "proc_0_00215", "proc_0_00216", "proc_0_00217", "proc_0_00218", "proc_0_00219",
    "proc_0_00225", "proc_0_00226", "proc_0_00229", "proc_0_00237", "proc_0_00238",
    "proc_0_00239", "proc_0_00241", "proc_0_00242", "proc_0_00248", "proc_0_00251",
    "proc_0_00269", "proc_0_00270", "proc_0_00272", "proc_0_00277", "proc_0_00286",
    "proc_0_00298", "proc_0_00299", "proc_0_00307", "proc_0_00311", "proc_0_00318",
    "rounded_rectangle", "square", "urdf_005", "urdf_023", "urdf_049", "urdf_053", "urdf_068",
    "urdf_084", "urdf_089", "urdf_103", "urdf_105", "urdf_111", "urdf_150", "urdf_153",
    "urdf_160", "urdf_173", "urdf_189", "urdf_206", "urdf_208", "urdf_220", "urdf_234",
    "urdf_238", "urdf_244", "urdf_253", "urdf_270", "urdf_292", "urdf_297", "urdf_325",
    "urdf_340", "urdf_363", "urdf_386", "urdf_388", "urdf_391", "urdf_398", "urdf_401",
    "urdf_471", "urdf_481", "urdf_505", "urdf_519", "urdf_647", "urdf_665", "urdf_674",
    "urdf_683", "urdf_711", "urdf_769", "urdf_813", "urdf_878", "urdf_890", "urdf_901",
    "urdf_905", "urdf_927", "urdf_930", "urdf_945", "urdf_946", "urdf_958", "urdf_968",
    "urdf_991"
)  # fmt: skip
_SEEDS = (0, 1, 2, 3, 4)
STANDARD_SPLITS: dict[int, BenchmarkSplit] = {
    1: BenchmarkSplit(STANDARD_NAME, 1, STANDARD_TEST_OBJECTS_V1, _SEEDS),
    2: BenchmarkSplit(STANDARD_NAME, 2, STANDARD_TEST_OBJECTS_V2, _SEEDS),
    3: BenchmarkSplit(STANDARD_NAME, 3, STANDARD_TEST_OBJECTS, _SEEDS),
    4: BenchmarkSplit(STANDARD_NAME, 4, STANDARD_TEST_OBJECTS_V4, _SEEDS),
}
STANDARD_SPLIT = STANDARD_SPLITS[max(STANDARD_SPLITS)]
#: The objects each version's held-out objects were drawn from.
DEFAULT_OBJECTS: dict[int, tuple[str, ...]] = {
    1: DEFAULT_OBJECTS_V1, 2: DEFAULT_OBJECTS_V2, 3: DEFAULT_OBJECTS_V3, 4: DEFAULT_OBJECTS_V4,
}


def standard_split(version: int | None = None) -> BenchmarkSplit:
    """The standard split of ``version`` (default: the latest); unknown → ValueError."""
    if version is None:
        return STANDARD_SPLIT
    if version not in STANDARD_SPLITS:
        raise ValueError(f"unknown standard split version {version!r}; known: "
                         f"{sorted(STANDARD_SPLITS)}")  # fmt: skip
    return STANDARD_SPLITS[version]


@dataclass(frozen=True)
class DatasetObjects:
    """The objects of a dataset: those with grips, and those it holds with none (its manifest
    records a finished shard of no rows: the planning kept no grip, which can differ between
    machines); a bare grip table knows only the first."""

    with_grips: tuple[str, ...]
    without_grips: tuple[str, ...] = ()

    @classmethod
    def of(cls, table: pd.DataFrame) -> DatasetObjects:
        """The objects of ``table`` (a loaded dataset keeps its manifest in ``attrs``)."""
        present = sorted(set(table["object_id"].astype(str)))
        shards = (table.attrs.get("manifest") or {}).get("shards") or {}
        empty = sorted(str(oid) for oid, record in shards.items()
                       if int(record.get("rows", 0)) == 0 and str(oid) not in present)  # fmt: skip
        return cls(tuple(present), tuple(empty))

    def lacks(self, split: BenchmarkSplit) -> str:
        """Which held-out objects of ``split`` have no grip here, in words ("" when none)."""
        have = set(self.with_grips)
        missing = [oid for oid in split.test_objects if oid not in have]
        if not missing:
            return ""
        hollow = [oid for oid in missing if oid in self.without_grips]
        absent = [oid for oid in missing if oid not in hollow]
        parts = [f"{_some(hollow)} {_be(hollow)} in it with no grips (planning kept none here, "
                 "as can differ between machines)" if hollow else "",
                 f"{_some(absent)} {_be(absent)} not in it" if absent else ""]  # fmt: skip
        return (f"dataset lacks {len(missing)} of the {len(split.test_objects)} held-out objects "
                f"of the standard split {split.name} v{split.version}: "
                + "; ".join(p for p in parts if p))  # fmt: skip

    def fitting_versions(self) -> list[int]:
        """The standard split versions whose held-out objects all have grips here."""
        return [v for v, split in sorted(STANDARD_SPLITS.items()) if not self.lacks(split)]


def _some(ids: Sequence[str], shown: int = 3) -> str:
    more = f" and {len(ids) - shown} more" if len(ids) > shown else ""
    return f"{', '.join(ids[:shown])}{more}"


def _be(ids: Sequence[str]) -> str:
    return "is" if len(ids) == 1 else "are"


def check_standard_objects(objects: DatasetObjects, split: BenchmarkSplit = STANDARD_SPLIT) -> None:
    """ValueError naming the held-out objects of ``split`` without grips in the dataset, and
    what to run instead: a standard version whose objects are all there, or ``--split auto``."""
    gap = objects.lacks(split)
    if not gap:
        return
    fits = objects.fitting_versions()
    instead = f"--split-version {fits[-1]} (all its objects are here) or " if fits else ""
    raise ValueError(f"{gap}; use {instead}--split auto (a seeded split of this dataset's own "
                     f"objects, not comparable with standard-split scores)")  # fmt: skip


def auto_split(objects: DatasetObjects, seed: int = 0,
               max_candidates: int = STANDARD_SPLIT.max_candidates) -> BenchmarkSplit:
    """The seeded split of the dataset's own objects with grips (:func:`split_objects` with the
    standard split's ``test_fraction``, seed ``seed``), up to ``max_candidates`` candidates an
    object (the config's ``selector.max_candidates``, so an agent trained on it fits): named
    :data:`AUTO_SPLIT_NAME`, version 0, so it is never taken for the standard split."""
    if len(objects.with_grips) < 2:
        raise ValueError(f"an auto split needs at least 2 objects with grips (one to hold out), "
                         f"the dataset has {len(objects.with_grips)}")  # fmt: skip
    fraction = STANDARD_SPLIT.test_fraction
    _, test = split_objects(objects.with_grips, fraction, seed)
    return BenchmarkSplit(AUTO_SPLIT_NAME, 0, test, _SEEDS, max_candidates,
                          test_fraction=fraction, split_seed=seed)  # fmt: skip


def choose_split(objects: DatasetObjects, mode: str = "auto", version: int | None = None,
                 seed: int = 0, max_candidates: int = STANDARD_SPLIT.max_candidates,
                 ) -> tuple[BenchmarkSplit, str]:  # fmt: skip
    """The split to score a dataset on, and a sentence saying why when it is not the latest
    standard split.

    ``mode="standard"`` (or a ``version`` given): that standard split, or ValueError when the
    dataset lacks grips of its objects. ``mode="auto"``: the latest standard version whose
    held-out objects all have grips, else :func:`auto_split` with ``seed`` and
    ``max_candidates``.
    """
    if mode not in SPLIT_MODES:
        raise ValueError(f"--split must be one of {list(SPLIT_MODES)}, got {mode!r}")
    if mode == "standard" or version is not None:
        split = standard_split(version)
        check_standard_objects(objects, split)
        return split, ""
    gap = objects.lacks(STANDARD_SPLIT)
    if not gap:
        return STANDARD_SPLIT, ""
    fits = objects.fitting_versions()
    if fits:
        split = STANDARD_SPLITS[fits[-1]]
        return split, f"{gap}; scored on v{split.version}, whose held-out objects are all here"
    split = auto_split(objects, seed, max_candidates)
    return split, (f"not the standard split: {gap}; scored on a seeded split (seed {seed}) of "
                   f"this dataset's own {len(objects.with_grips)} objects with grips, "
                   f"{len(split.test_objects)} held out: do not compare its scores with "
                   f"{STANDARD_NAME} scores")  # fmt: skip


def training_objects(table: pd.DataFrame, config: Config) -> tuple[pd.DataFrame, dict[str, Any]]:
    """The grips of the objects a method may train on to be scored by ``grip-env benchmark`` on
    ``table``: all but the held-out objects of the split it picks (``--split auto``, seed
    ``learning.seed``: the standard split on the standard dataset), and that split in words
    (the ``split`` entry of a saved model's ``trained_on`` record)."""
    chosen, _ = choose_split(DatasetObjects.of(table), "auto", None, config.learning.seed,
                             config.selector.max_candidates)  # fmt: skip
    held_out = table["object_id"].astype(str).isin(chosen.test_objects).to_numpy()
    return table[~held_out], {"split": "train", "split_name": chosen.name,
                              "split_version": chosen.version, "split_seed": chosen.split_seed,
                              "held_out_objects": len(chosen.test_objects)}  # fmt: skip


def study_split(table: pd.DataFrame, config: Config, seeds: Sequence[int]) -> BenchmarkSplit:
    """The standard split when the study's own held-out objects are it, else the study's split."""
    learning = config.learning
    _, test = held_out_objects(table["object_id"].astype(str), learning)
    found = [v for v, s in STANDARD_SPLITS.items() if s.test_objects == tuple(test)
             and config.selector.max_candidates == s.max_candidates]  # fmt: skip
    return BenchmarkSplit(
        STANDARD_NAME if found else "study", found[0] if found else 0,
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
