"""The main job: dataset, classifiers, ablation, RL selector, label calibration, report.

Every stage reuses what an earlier run already produced in ``out`` when the config sections it
depends on and the dataset are unchanged (:func:`stage_key`, kept in ``<stage>/stage.json``), so an
interrupted study resumes and a new learning seed recomputes only the learning stages.
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pandas as pd

from grip_env.config import Config

QUICK_OVERRIDES: dict[str, dict[str, Any]] = {
    "objects": {"set": "basic", "procedural_count": 2},
    "dataset": {"trials": 2, "max_grips_per_object": 8},
    "learning": {"folds": 2, "repeats": 1, "models": ("logreg", "knn", "rank_qc", "random"),
                 "regressors": ("ridge", "rank_qc", "rank_qg", "random")},
    "selector": {"timesteps": 512, "max_candidates": 16},
}


def study_config(config: Config, quick: bool = False) -> Config:
    """The configuration a study runs on (``quick`` shrinks every stage for tests)."""
    return config.override(**QUICK_OVERRIDES) if quick else config


def run_study(
    config: Config, out: str | Path, quick: bool = False, log: Callable[[str], None] = print
) -> Path:
    """Run every stage into ``out`` and return the path of ``report.md``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    config = study_config(config, quick)
    timings: dict[str, float] = {}

    def stage(name: str, done: Path, run: Callable[[], object]) -> None:
        key = stage_key(name, config, checksum, quick)
        marker = done.parent / STAGE_FILE
        if done.exists() and _stored_key(marker) == key:
            log(f"[study] {name}: reusing {done}")
            return
        if done.exists():
            log(f"[study] {name}: its settings or the dataset changed, recomputing")
        log(f"[study] {name} ...")
        start = time.perf_counter()
        run()
        marker.write_text(json.dumps({"stage": name, "key": key}, indent=2))
        timings[name] = time.perf_counter() - start
        log(f"[study] {name} done in {timings[name]:.1f} s")

    from classifiers.ablation import run_ablation
    from classifiers.persistence import dataset_checksum
    from classifiers.selector import run_selector
    from classifiers.training import train_and_save
    from grip_env.dataset import generate, load

    data_dir = out / "dataset"
    log("[study] dataset (resumes or reuses what is already in place) ...")
    start = time.perf_counter()
    generate(config, data_dir)
    timings["dataset"] = time.perf_counter() - start
    table = load(data_dir)
    checksum = dataset_checksum(table)
    stage("classifiers", out / "classifiers" / "metrics.json",
          lambda: train_and_save(table, out / "classifiers", config))
    stage("ablation", out / "ablation" / "ablation.json",
          lambda: run_ablation(table, out / "ablation", config))
    stage("selector", out / "selector" / "selector.json",
          lambda: run_selector(table, out / "selector", config))
    stage("calibration", out / "calibration" / "calibration.json",
          lambda: run_calibration(config, out / "calibration", table, quick, log))
    _merge_timings(out / "timings.json", timings)
    log("[study] report ...")
    from classifiers.report.study_report import write_report

    return write_report(out, config, table)


STAGE_FILE = "stage.json"
_STAGE_SECTIONS = {
    "classifiers": ("learning",),
    "ablation": ("learning",),
    "selector": ("learning", "selector", "sim"),
    "calibration": ("grasp", "objects", "perception", "synthesis", "sim", "uncertainty"),
}


def stage_key(name: str, config: Config, dataset_sha256: str, quick: bool = False) -> str:
    """What a stage's result depends on, hashed: its config sections and the dataset.

    A rerun reuses a stage only when its key is unchanged, so a new learning seed recomputes
    the learning stages (on the same dataset) and leaves the calibration alone.
    """
    data = config.model_dump(mode="json")
    depends = {section: data[section] for section in _STAGE_SECTIONS[name]}
    if name == "calibration":
        depends["dataset_seed"] = config.dataset.seed  # seeds the procedural objects
        depends["quick"] = quick
    depends["dataset"] = dataset_sha256
    return hashlib.sha256(json.dumps(depends, sort_keys=True).encode()).hexdigest()


def _stored_key(marker: Path) -> str | None:
    try:
        return json.loads(marker.read_text()).get("key")
    except (OSError, ValueError, AttributeError):
        return None


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


def _merge_timings(path: Path, timings: dict[str, float]) -> None:
    previous = json.loads(path.read_text()) if path.exists() else {}
    previous.update({k: round(v, 2) for k, v in timings.items()})
    path.write_text(json.dumps(previous, indent=2))
