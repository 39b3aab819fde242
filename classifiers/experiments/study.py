"""The main job: dataset, classifiers, ablation, RL selector, leaderboard, label calibration,
the answers to the study's questions, report.

Every stage records what it read in ``<stage>/stage.json``: the config fields it depends on
(:data:`STAGE_INPUTS`), the dataset's checksum, the grip-env version and a digest of the code it
runs (:mod:`classifiers.experiments.stage_code`), hashed into its key
(:func:`stage_key`). A rerun into the same folder reuses a stage whose key is unchanged and
recomputes, and says so, a stage whose inputs changed. The dataset is the dataset layer's own
resumable run: it is reused unless a setting it depends on changed, so adding a model to
``learning.models`` retrains the classifiers (and the selector, whose baselines they are) on the
same grips and leaves the dataset, the ablation and the calibration alone.
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pandas as pd

from classifiers.experiments.stage_code import stage_code_digest
from grip_env.config import Config

#: ``--quick``: a tiny profile for tests; a field is replaced only where the config leaves it at
#: its default, so settings the user chose are kept (and the log says which were replaced).
QUICK_OVERRIDES: dict[str, dict[str, Any]] = {
    "objects": {"set": "basic", "procedural_count": 2, "mesh_count": 1},
    "dataset": {"trials": 2, "max_grips_per_object": 8},
    "learning": {"folds": 2, "repeats": 1, "models": ("logreg", "knn", "rank_qc", "random"),
                 "regressors": ("ridge", "rank_qc", "rank_qg", "random"),
                 "rankers": ("lambdarank", "rank_qc", "random"), "seeds": 2,
                 "image_models": ("cnn",)},
    "selector": {"timesteps": 512, "max_candidates": 16, "seeds": 2},
}
STAGE_FILE = "stage.json"


@dataclass(frozen=True)
class StudyRun:
    """What every stage of one study reads: the configuration, the dataset (its folder and its
    loaded table) and the folder the study writes to."""

    config: Config
    data_dir: Path
    table: pd.DataFrame
    checksum: str  # the table's (:func:`classifiers.learners.persistence.dataset_checksum`)
    out: Path
    quick: bool = False
    log: Callable[[str], None] = print


@dataclass(frozen=True)
class Stage:
    """One step of the study: the config fields it reads (a section, or ``section.field``), the
    result file that marks it done (relative to the study folder) and what runs it."""

    name: str
    inputs: tuple[str, ...]
    result: str
    run: Callable[[StudyRun], object]


def _classifiers(run: StudyRun) -> object:
    from classifiers.experiments.training import train_and_save

    return train_and_save(run.table, run.out / "classifiers", run.config)


def _ablation(run: StudyRun) -> object:
    from classifiers.experiments.ablation import named_feature_sets, run_ablation

    return run_ablation(run.table, run.out / "ablation", run.config, sets=named_feature_sets())


def _selector(run: StudyRun) -> object:
    from classifiers.experiments.selector.seeds import run_selectors

    return run_selectors(run.table, run.out / "selector", run.config)


def _selector_retry(run: StudyRun) -> object:
    from classifiers.experiments.selector.seeds import RETRY_METHOD, run_selectors
    from grip_env.dataset.shards import recorded_trial_successes

    attempts, result = run.config.selector.retry_attempts, run.out / SELECTOR_RETRY.result
    if attempts < 2:
        return _skipped(result, "selector.retry_attempts is 1")
    if not recorded_trial_successes(run.table.columns):
        return _skipped(result, "the dataset does not record every trial's outcome")
    retry = run.config.override(selector={"max_attempts": attempts})
    return run_selectors(run.table, result.parent, retry, method=RETRY_METHOD)


def _images(run: StudyRun) -> object:
    if not run.config.learning.image_models:
        return _skipped(run.out / IMAGES.result, "learning.image_models is empty")
    from classifiers.experiments.image_evaluator import run_image_study

    return run_image_study(run.table, run.data_dir, run.out / "images", run.config)


def _skipped(path: Path, reason: str) -> dict[str, str]:
    path.parent.mkdir(parents=True, exist_ok=True)
    result = {"skipped": reason}
    path.write_text(json.dumps(result, indent=2))
    return result


def _benchmark(run: StudyRun) -> object:
    from classifiers.experiments.benchmark import study_benchmark
    from classifiers.report.leaderboard import write_leaderboard_markdown

    board = study_benchmark(run.table, run.out, run.config)
    if board.get("methods"):
        write_leaderboard_markdown(board, run.out / "benchmark")
    return board


def _calibration(run: StudyRun) -> object:
    recorded = None if run.quick else recorded_calibration(run.data_dir, run.config)
    if recorded is None:
        return run_calibration(run.config, run.out / "calibration", run.table, run.quick, run.log)
    run.log(f"[study] calibration: the one recorded with the dataset ({recorded.parent}), of "
            "this label model and recipe at full size: not measured again")
    return copy_calibration(recorded, run.out / "calibration")


def _replication(run: StudyRun) -> object:
    """A seeded sample of the given dataset's grips simulated again from its recipe."""
    from grip_env.dataset.resimulation import resimulate

    grips = REPLICATION_GRIPS_QUICK if run.quick else REPLICATION_GRIPS
    found = resimulate(run.data_dir, grips, seed=run.config.learning.seed,
                       workers=run.config.dataset.workers)
    run.log(f"[study] replication: {found.summary()}")
    result = {"dataset": str(run.data_dir), "seed": run.config.learning.seed, **asdict(found),
              "identical": found.identical, "summary": found.summary()}
    path = run.out / REPLICATION.result
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(result, indent=2))
    return result


def _perception(run: StudyRun) -> object:
    from classifiers.experiments.perception_effect import run_perception_effect

    return run_perception_effect(run.config, run.data_dir, run.out / "perception")


#: The RL selector of the retry task (``selector.retry_attempts`` attempts an episode sharing one
#: trial index), when the dataset records every trial's outcome.
SELECTOR_RETRY = Stage("selector_retry", ("learning.models", "learning.seed",
                                          "learning.test_fraction", "selector", "sim"),
                       "selector_retry/selector.json", _selector_retry)
#: The image models beside the measures' learner (:mod:`classifiers.experiments.image_evaluator`).
IMAGES = Stage("images", ("learning.image_models", "learning.ablation_model", "learning.folds",
                          "learning.repeats", "learning.seed", "learning.seeds",
                          "learning.test_fraction", "selector.max_candidates"),
               "images/images.json", _images)
#: The study's stages, in the order they run (the selector's baselines are the classifiers'
#: learners; the benchmark reads the classifiers', the image models' and the selectors' scores).
STAGES: tuple[Stage, ...] = (
    Stage("classifiers", ("learning", "selector.max_candidates", "sim.ramp_levels_g",
                          "sim.ramp_ratio"), "classifiers/metrics.json", _classifiers),
    Stage("ablation", ("learning.ablation_model", "learning.folds", "learning.repeats",
                       "learning.seed"), "ablation/ablation.json", _ablation),
    Stage("selector", ("learning.models", "learning.seed", "learning.test_fraction", "selector",
                       "sim"), "selector/selector.json", _selector),
    SELECTOR_RETRY,
    IMAGES,
    Stage("benchmark", ("learning", "selector", "sim", "grasp.mu"),
          "benchmark/leaderboard.json", _benchmark),
    Stage("calibration", ("grasp", "objects", "perception", "synthesis", "sim", "uncertainty",
                          "dataset.seed", "dataset.trials", "dataset.max_grips_per_object",
                          "dataset.sampling"), "calibration/calibration.json", _calibration),
    Stage("perception", ("grasp", "objects", "perception", "synthesis", "sim", "uncertainty",
                         "dataset", "learning.seed"), "perception/perception.json", _perception),
)
#: A study on a given dataset (``--data``) first re-simulates a seeded sample of it: are its
#: labels what this code makes from its recipe?
REPLICATION = Stage("replication", ("learning.seed",), "replication/replication.json",
                    _replication)
#: Grips re-simulated by the replication stage (5 an object: 20 objects), and with ``--quick``.
REPLICATION_GRIPS, REPLICATION_GRIPS_QUICK = 100, 10
#: The config fields each stage reads, by stage name.
STAGE_INPUTS: dict[str, tuple[str, ...]] = {
    stage.name: stage.inputs for stage in (REPLICATION, *STAGES)}
#: What runs each stage, by stage name (its code is part of the stage's key).
STAGE_RUNS: dict[str, Callable[[StudyRun], object]] = {
    stage.name: stage.run for stage in (REPLICATION, *STAGES)}
#: Where a study records which dataset it learned on.
DATA_FILE = "data.json"


def quick_overrides(config: Config) -> dict[str, dict[str, Any]]:
    """The ``--quick`` replacements that apply to ``config``: those of fields left at default."""
    defaults, current = Config().model_dump(), config.model_dump()
    applied = {}
    for section, fields in QUICK_OVERRIDES.items():
        chosen = {k: v for k, v in fields.items() if current[section][k] == defaults[section][k]}
        if chosen:
            applied[section] = chosen
    return applied


def study_config(config: Config, quick: bool = False) -> Config:
    """The configuration a study runs on (``quick`` shrinks every stage left at its default)."""
    overrides = quick_overrides(config) if quick else {}
    return config.override(**overrides) if overrides else config


def describe_quick(config: Config) -> str:
    """One line: what ``--quick`` replaces in ``config`` and what it keeps from it."""
    applied = quick_overrides(config)
    changed = [f"{s}.{k}={_show(v)}" for s, fields in applied.items() for k, v in fields.items()]
    kept = [f"{s}.{k}" for s, fields in QUICK_OVERRIDES.items() for k in fields
            if k not in applied.get(s, {})]  # fmt: skip
    line = "--quick sets " + (", ".join(changed) if changed else "nothing")
    return line + (f"; keeps {', '.join(kept)} from the config" if kept else "")


def run_study(
    config: Config, out: str | Path, quick: bool = False, log: Callable[[str], None] = print,
    data: str | Path | None = None,
) -> Path:
    """Run every stage of :data:`STAGES` into ``out`` and return the path of ``report.md``.

    Without ``data`` the study generates its dataset from ``config`` into ``out/dataset``. With
    ``data`` (a dataset folder, or ``"standard"``) it learns on that dataset, under the
    dataset's own recipe (its recorded config, with ``config``'s ``learning`` and ``selector``),
    and first re-simulates a seeded sample of it (:data:`REPLICATION`).

    Learner names of ``config.learning`` are checked first: an unknown one is a ``ValueError``
    naming its key before the dataset stage spends minutes; so is a dataset labelled by another
    label model (:func:`check_label_model`).
    """
    check_learner_names(config)
    out = Path(out)
    data_dir = out / "dataset" if data is None else resolve_dataset(data)
    check_label_model(data_dir)
    out.mkdir(parents=True, exist_ok=True)
    if quick:
        log(f"[study] {describe_quick(config)}")
    config = study_config(config, quick)
    if data is None:
        run, timings = dataset_stage(config, out, quick, log)
        stages = STAGES
    else:
        run, timings = given_dataset(config, data_dir, out, quick, log), {}
        stages = (REPLICATION, *STAGES)
    (out / DATA_FILE).write_text(json.dumps(
        {"dataset": str(run.data_dir.resolve()), "sha256": run.checksum,
         "generated": data is None}, indent=2))
    for stage in stages:
        timings |= run_stage(stage, run)
    _merge_timings(out / "timings.json", timings)
    from classifiers.experiments.answers import write_answers

    write_answers(out, run.config.learning.seed)  # seconds: always from the stages' results
    log("[study] report ...")
    from classifiers.report.study_report import write_report

    return write_report(out, run.config, run.table)


def study_dataset(out: str | Path) -> Path:
    """The dataset folder the study in ``out`` learned on (its own ``out/dataset``, or the one
    given with ``data``)."""
    recorded = _stored(Path(out) / DATA_FILE) or {}
    return Path(recorded["dataset"]) if "dataset" in recorded else Path(out) / "dataset"


def resolve_dataset(data: str | Path) -> Path:
    """The folder of a ``data`` argument (``"standard"``: the shipped one); ValueError when it
    holds no dataset."""
    from grip_env.dataset.manifest import MANIFEST_FILE
    from grip_env.datasets import resolve_data

    folder = resolve_data(data)
    if not (folder / MANIFEST_FILE).is_file():
        raise ValueError(f"--data {data}: {folder} holds no grip-env dataset (no "
                         f"{MANIFEST_FILE})")
    return folder


def given_dataset(
    config: Config, data_dir: Path, out: Path, quick: bool, log: Callable[[str], None]
) -> StudyRun:
    """A study run on the dataset in ``data_dir``: its recipe, ``config``'s learning settings."""
    from classifiers.learners.persistence import dataset_checksum
    from grip_env.dataset import load

    table = load(data_dir)
    recipe = Config.model_validate(table.attrs["manifest"]["config"])
    config = recipe.override(learning=config.learning.model_dump(),
                             selector=config.selector.model_dump(),
                             dataset={"workers": config.dataset.workers})
    log(f"[study] dataset: learning on {data_dir} ({len(table)} grips, "
        f"{table['object_id'].nunique()} objects)")
    return StudyRun(config, data_dir, table, dataset_checksum(table), out, quick, log)


def dataset_stage(
    config: Config, out: Path, quick: bool, log: Callable[[str], None]
) -> tuple[StudyRun, dict[str, float]]:
    """Generate (or resume, or reuse) the study's dataset in ``out/dataset`` and load it."""
    from classifiers.learners.persistence import dataset_checksum
    from grip_env.dataset import generate, load

    data_dir = out / "dataset"
    before = _manifest_created(data_dir)
    start = time.perf_counter()
    generate(config, data_dir)
    reused = before is not None and before == _manifest_created(data_dir)
    log(f"[study] dataset: {'reusing' if reused else 'generated'} {data_dir}")
    # a reused stage keeps the time it took when it ran
    timings = {} if reused else {"dataset": time.perf_counter() - start}
    table = load(data_dir)
    return StudyRun(config, data_dir, table, dataset_checksum(table), out, quick, log), timings


def run_stage(stage: Stage, run: StudyRun) -> dict[str, float]:
    """Run ``stage`` unless its result exists with an unchanged key; its time, if it ran."""
    record = stage_record(stage.name, run.config, run.checksum, run.quick)
    done = run.out / stage.result
    marker = done.parent / STAGE_FILE
    if done.exists() and _stored_key(marker) == record["key"]:
        run.log(f"[study] {stage.name}: reusing {done}")
        return {}
    if done.exists():
        run.log(f"[study] {stage.name}: {changed_inputs(_stored(marker), record)} changed, "
                "recomputing")
    run.log(f"[study] {stage.name} ...")
    start = time.perf_counter()
    stage.run(run)
    took = time.perf_counter() - start
    record["written"] = datetime.now(UTC).isoformat(timespec="seconds")
    marker.write_text(json.dumps(record, indent=2))
    run.log(f"[study] {stage.name} done in {took:.1f} s")
    return {stage.name: took}


def check_learner_names(config: Config) -> None:
    """ValueError naming the ``learning`` key whose model name no registry knows."""
    from classifiers.learners.models import IMAGE_MODEL_NAMES, MODEL_NAMES, REGRESSOR_NAMES
    from classifiers.learners.ranking import RANKER_NAMES

    learning = config.learning
    for key, names, known in (("models", learning.models, MODEL_NAMES),
                              ("image_models", learning.image_models, IMAGE_MODEL_NAMES),
                              ("ablation_model", (learning.ablation_model,), MODEL_NAMES),
                              ("regressors", learning.regressors, REGRESSOR_NAMES),
                              ("rankers", learning.rankers, RANKER_NAMES)):  # fmt: skip
        unknown = [name for name in names if name not in known]
        if unknown:
            raise ValueError(f"learning.{key}: unknown model {unknown[0]!r}; choose from "
                             f"{', '.join(known)}")


def check_label_model(data_dir: Path) -> None:
    """ValueError when ``data_dir`` holds a dataset of another label model than this code's: a
    study never mixes label models (its stages would compare labels of two simulations)."""
    from grip_env.dataset import dataset_label_model, dataset_manifest
    from grip_env.label_model import LABEL_MODEL, expected_label_model

    found = dataset_label_model(data_dir)
    try:  # the label model this code makes in the dataset's engine
        expected = expected_label_model(dataset_manifest(data_dir))
    except ValueError:  # no readable manifest: its readers say what is wrong
        expected = LABEL_MODEL
    if found not in (None, expected):
        raise ValueError(
            f"{data_dir} holds a dataset of label model {found!r}, this grip-env's is "
            f"{expected!r}: a study does not mix label models; regenerate it into an empty "
            f"folder (another study folder, or delete {data_dir})"
        )


def stage_record(
    name: str, config: Config, dataset_sha256: str, quick: bool = False
) -> dict[str, Any]:
    """What stage ``name`` reads (its config fields, the dataset, the version, its code) and its
    key."""
    inputs = stage_inputs(name, config)
    if name == "calibration":  # its sizes are its own (quick or not), not the config's
        from dataclasses import asdict

        from grip_env.calibration import CalibrationSettings

        inputs["quick"] = quick
        inputs["settings"] = asdict(CalibrationSettings.quick(1) if quick
                                    else CalibrationSettings(workers=1))  # fmt: skip
        inputs["settings"].pop("workers")  # the outcome does not depend on it
    code = stage_code_digest(STAGE_RUNS[name])
    return {"stage": name, "key": _hash(inputs, dataset_sha256, package_version(), code),
            "package_version": package_version(), "dataset_sha256": dataset_sha256,
            "code_sha256": code, "inputs": inputs}  # fmt: skip


def stage_key(name: str, config: Config, dataset_sha256: str, quick: bool = False) -> str:
    """SHA-256 of what stage ``name`` reads: its config fields, the dataset, the version, and the
    source of every project module it runs (:func:`stage_code_digest`).

    A rerun reuses a stage only when its key is unchanged, so a new learning seed recomputes
    the learning stages (on the same dataset) and leaves the calibration alone, an upgrade of
    grip-env recomputes every stage, and a change to the code a stage runs recomputes it.
    """
    return stage_record(name, config, dataset_sha256, quick)["key"]


#: Fields that say how a stage runs, not what it computes: no result depends on them.
HOW_TO_RUN = frozenset({"workers", "backend"})


def stage_inputs(name: str, config: Config) -> dict[str, Any]:
    """The values of the config fields :data:`STAGE_INPUTS` lists for ``name`` (a whole section
    without its :data:`HOW_TO_RUN` fields)."""
    data = config.model_dump(mode="json")
    found = {}
    for path in STAGE_INPUTS[name]:
        section, _, field = path.partition(".")
        found[path] = data[section][field] if field else {
            key: value for key, value in data[section].items() if key not in HOW_TO_RUN}
    return found


def changed_inputs(old: dict[str, Any] | None, new: dict[str, Any]) -> str:
    """Which inputs differ between two stage records, for the rerun's log line."""
    if not old or "inputs" not in old:
        return "its inputs (no record of them)"
    names = [k for k, v in new["inputs"].items() if old["inputs"].get(k) != v]
    if old.get("dataset_sha256") != new["dataset_sha256"]:
        names.append("the dataset")
    if old.get("package_version") != new["package_version"]:
        names.append(f"grip-env {old.get('package_version')} -> {new['package_version']}")
    if old.get("code_sha256") != new["code_sha256"]:
        names.append("its code")
    return ", ".join(names) or "its inputs"


def package_version() -> str:
    """The installed grip-env's version (the package's own in a bare checkout)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("grip-env")
    except PackageNotFoundError:
        from grip_env import __version__

        return __version__


def _hash(inputs: dict[str, Any], dataset_sha256: str, version: str, code_sha256: str) -> str:
    depends = {"inputs": inputs, "dataset": dataset_sha256, "package_version": version,
               "code": code_sha256}
    return hashlib.sha256(json.dumps(depends, sort_keys=True).encode()).hexdigest()


def _stored(marker: Path) -> dict[str, Any] | None:
    try:
        found = json.loads(marker.read_text())
    except (OSError, ValueError):
        return None
    return found if isinstance(found, dict) else None


def _stored_key(marker: Path) -> str | None:
    return (_stored(marker) or {}).get("key")


def _manifest_created(data_dir: Path) -> str | None:
    try:
        manifest = json.loads((data_dir / "manifest.json").read_text())
    except (OSError, ValueError):
        return None
    return f"{manifest.get('created')}/{manifest.get('complete')}" if isinstance(
        manifest, dict) else None


def _show(value: Any) -> str:
    return ",".join(map(str, value)) if isinstance(value, tuple | list) else repr(value)


def run_calibration(
    config: Config, out: Path, table: pd.DataFrame | None = None, quick: bool = False,
    log: Callable[[str], None] = print,
) -> Path:
    """The label-validity checks (``grip-env calibrate``) on ``config``, with the decile checks
    on ``table``; writes ``out/calibration.{json,md,html}``, trials and figures."""
    from classifiers.report.calibration import write_calibration
    from grip_env.calibration import CalibrationSettings, calibrate

    workers = config.dataset.workers
    settings = CalibrationSettings.quick(workers) if quick else CalibrationSettings(workers=workers)
    has_robustness = table is not None and "robustness_mean" in table.columns
    result, trials = calibrate(config, settings, table if has_robustness else None, log)
    return write_calibration(out, result, trials)


#: Where a dataset keeps the calibration of the label model on its recipe (``grip-env calibrate
#: --config RECIPE --data DIR --out DIR/calibration``): the shipped standard dataset has one.
RECORDED_CALIBRATION = Path("calibration") / "calibration.json"


def recorded_calibration(data_dir: Path, config: Config) -> Path | None:
    """The dataset's recorded ``calibration.json`` when it is what the study's calibration stage
    would measure: this code's label model, the stage's config fields equal to ``config``'s and
    the full-size settings of :class:`~grip_env.calibration.CalibrationSettings`; else None.

    A calibration costs about 45 minutes of 2 cores on the standard recipe; like the labels it
    checks, it is measured once with the dataset, and the study's replication stage shows that
    the labels are still this code's.
    """
    from grip_env.calibration import CalibrationSettings
    from grip_env.label_model import label_model_for

    path = Path(data_dir) / RECORDED_CALIBRATION
    found = _stored(path)
    if not found or "config" not in found:
        return None
    try:
        recipe = Config.model_validate(found["config"])
    except ValueError:
        return None
    if found.get("label_model") != label_model_for(recipe.sim.engine):
        return None
    full = asdict(CalibrationSettings())
    settings = {k: v for k, v in (found.get("settings") or {}).items() if k != "workers"}
    same = (stage_inputs("calibration", recipe) == stage_inputs("calibration", config)
            and settings == {k: v for k, v in full.items() if k != "workers"})  # fmt: skip
    return path if same else None


def copy_calibration(recorded: Path, out: Path) -> Path:
    """Write a recorded calibration (its JSON, marked as recorded, and its trials) into ``out``
    as the study's own, with its Markdown and figures; returns ``calibration.md``."""
    from classifiers.report.calibration import TRIALS_FILE, write_calibration

    result = json.loads(recorded.read_text())
    result["recorded_with"] = str(recorded.parent.parent)
    trials = pd.read_parquet(recorded.parent / TRIALS_FILE)
    return write_calibration(out, result, trials)


def _merge_timings(path: Path, timings: dict[str, float]) -> None:
    previous = json.loads(path.read_text()) if path.exists() else {}
    previous.update({k: round(v, 2) for k, v in timings.items()})
    path.write_text(json.dumps(previous, indent=2))
