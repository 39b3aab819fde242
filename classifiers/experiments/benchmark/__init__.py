"""Grip selection scored the way a robot uses it: one pick per object, against the oracle.

>>> from classifiers.experiments.benchmark import benchmark_method
>>> board = benchmark_method(table, ["mine.zip"], "mine", config)   # leaderboard dict

Modules: ``split`` (the fixed, versioned standard split, or a seeded split of a dataset's own
objects), ``methods`` (baselines and loaders of SB3 zips, d3rlpy policies, saved models and
``module:function`` entry points, observation policies among them, as score tables),
``outputs`` (what a method returns, as scores), ``provenance`` (what a method was trained on: a
run that saw a held-out object is refused; its training budget),
``selection`` (exact per-object metrics), ``retry`` (success within 1-3 attempts that share
the object's draw, on data with every trial's outcome), ``aggregate`` (rliable's IQM,
stratified bootstrap, probability of improvement, performance profiles), ``leaderboard``
(tables, verdicts, files), ``plots``.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from grip_env.config import Config

METHOD_KINDS = ("sb3 zip", "saved model", "module:function", "d3rlpy policy")
#: A d3rlpy algorithm's file (``save``), e.g. the offline baseline of
#: :mod:`classifiers.experiments.offline_rl`.
D3RLPY_SUFFIX = ".d3"
#: The files of a saved model (``grip-env train``'s ``NAME.json`` and what it names, or a bare
#: ``.skops``): the suffixes ``grip-env predict`` takes.
MODEL_SUFFIXES = (".skops", ".json", ".pt", ".txt")

__all__ = ["benchmark_method", "method_kind", "study_benchmark"]


def method_kind(spec: str) -> str:
    """Which kind of method ``spec`` names: an existing ``.zip``, a saved model's file
    (:data:`MODEL_SUFFIXES`, or its name without one) or an entry point ``module:function``."""
    path = Path(spec)
    suffix = path.suffix.lower()
    if suffix in (".zip", D3RLPY_SUFFIX, *MODEL_SUFFIXES):
        if not path.is_file():
            raise ValueError(f"method file not found: {spec}")
        return {".zip": METHOD_KINDS[0], D3RLPY_SUFFIX: METHOD_KINDS[3]}.get(suffix,
                                                                             METHOD_KINDS[1])
    if path.name and path.with_name(f"{path.name}.json").is_file():  # a bare name, as predict
        return METHOD_KINDS[1]
    if ":" in spec and not path.exists():
        return METHOD_KINDS[2]
    raise ValueError(f"a method is an SB3 .zip, a d3rlpy .d3, a saved model (NAME.json or its "
                     f".skops, .pt, .txt) or 'module:function', got {spec!r}")  # fmt: skip


def benchmark_method(
    table: pd.DataFrame, specs: Sequence[str], name: str, config: Config, reps: int = 2000,
    split_version: int | None = None, split: str = "auto", seed: int = 0,
) -> dict[str, Any]:
    """The leaderboard of one user method (``specs``: its runs, e.g. one zip per seed) against
    the baselines, on the split :func:`~classifiers.experiments.benchmark.split.choose_split`
    picks (``split``: ``"auto"`` or ``"standard"``; ``seed``: the auto split's). Its ``split``
    entry says which, ``standard`` whether it is the standard one, ``note`` why another and
    ``seeds`` the runs' seeds; the method's row says what it was trained on (``training``,
    :mod:`~classifiers.experiments.benchmark.provenance`). Raises ValueError on any bad input,
    a method trained on a held-out object included, before any file is written."""
    from classifiers.experiments.benchmark.leaderboard import NoRankableObject
    from classifiers.experiments.benchmark.methods import baseline_scores
    from classifiers.experiments.benchmark.split import (
        DatasetObjects,
        candidate_sets,
        candidate_table,
        choose_split,
    )
    from classifiers.learners.persistence import dataset_checksum

    if not specs:
        raise ValueError("give at least one method")
    if name in ("best_qc", "best_qg", "epsilon", "random", "oracle"):
        raise ValueError(f"method name {name!r} is a baseline's; choose another with --name")
    kinds = {method_kind(s) for s in specs}
    if len(kinds) > 1:
        raise ValueError(f"the runs of one method must be of one kind, got {sorted(kinds)}")
    kind = kinds.pop()
    objects = DatasetObjects.of(table)
    chosen, note = choose_split(objects, split, split_version, seed,
                                config.selector.max_candidates)
    table = _bare(table)
    checksum = dataset_checksum(table)
    training = _training(kind, specs, chosen.test_objects, checksum, objects.with_grips)
    sets = candidate_sets(table, config, chosen)
    candidates = candidate_table(sets)
    mine = pd.concat([_run_scores(kind, spec, run, sets, chosen.seeds, name)
                      for run, spec in enumerate(specs)], ignore_index=True)  # fmt: skip
    # the standard split's baselines do not depend on the user's config (epsilon: default mu)
    scores = pd.concat([baseline_scores(candidates), mine], ignore_index=True)
    info = {**chosen.describe(), **({"note": note} if note else {}),
            "seeds": sorted(int(s) for s in mine["seed"].unique()),
            "dataset_sha256": checksum, "method_files": list(specs)}  # fmt: skip
    try:
        board = _board(candidates, scores, info, reps, config.learning.seed)
    except NoRankableObject as exc:
        if chosen.standard:
            raise
        raise NoRankableObject(f"{exc} (the auto split's held-out {list(chosen.test_objects)}, "
                               f"seed {seed}): try another --seed or a dataset with more "
                               f"objects") from None  # fmt: skip
    board["methods"][name]["training"] = training
    board["methods"][name]["budget"] = _budget(kind, specs)
    return board


def _budget(kind: str, specs: Sequence[str]) -> dict[str, Any]:
    """The method's training budget as its runs record it (the first run's when all agree)."""
    from classifiers.experiments.benchmark.methods import load_entry_point
    from classifiers.experiments.benchmark.provenance import function_budget, recorded_budget

    found = [function_budget(load_entry_point(s)) if kind == METHOD_KINDS[2]
             else recorded_budget(Path(s)) for s in specs]  # fmt: skip
    texts = list(dict.fromkeys(b["text"] for b in found))
    return {**found[0], "text": texts[0] if len(texts) == 1 else "; ".join(texts),
            "runs": found}  # fmt: skip


def _training(kind: str, specs: Sequence[str], held_out: Sequence[str], checksum: str,
              dataset_objects: Sequence[str]) -> dict[str, Any]:  # fmt: skip
    """What each run of the method was trained on, checked against the held-out objects."""
    from classifiers.experiments.benchmark.methods import load_entry_point
    from classifiers.experiments.benchmark.provenance import (
        check_training,
        recorded_file,
        recorded_function,
    )

    if kind == METHOD_KINDS[2]:
        records = [recorded_function(load_entry_point(s), s) for s in specs]
    else:
        records = [recorded_file(Path(s), checksum, dataset_objects) for s in specs]
    return check_training(records, specs, held_out)


def _run_scores(kind: str, spec: str, run: int, sets: Sequence[Any], seeds: Sequence[int],
                name: str) -> pd.DataFrame:  # fmt: skip
    """The score table of one run (one file, or one entry point's seeds offset by the run)."""
    from classifiers.experiments.benchmark.methods import (
        d3rlpy_scores,
        entry_point_scores,
        saved_model_scores,
        sb3_scores,
    )

    if kind == METHOD_KINDS[0]:
        return sb3_scores(Path(spec), sets, run, name)
    if kind == METHOD_KINDS[3]:
        return d3rlpy_scores(Path(spec), sets, name).assign(seed=run)
    if kind == METHOD_KINDS[1]:
        return saved_model_scores(Path(spec), sets, name).assign(seed=run)
    offset = len(seeds) * run
    return entry_point_scores(spec, sets, seeds, name).assign(seed=lambda f: f["seed"] + offset)


def study_benchmark(
    table: pd.DataFrame, out: str | Path, config: Config, reps: int = 2000
) -> dict[str, Any]:
    """The study's leaderboard: the learners' per-seed scores (``classifiers/scores.parquet``,
    ``selector/scores.parquet``), or, without them, each learner fitted with ``learning.seed``
    and the selector's ``model.zip``; plus the baselines. Writes ``out/benchmark/``."""
    from classifiers.experiments.benchmark.leaderboard import NoRankableObject, write_leaderboard
    from classifiers.experiments.benchmark.methods import (
        baseline_scores,
        fitted_scores,
        sb3_scores,
        study_scores,
    )
    from classifiers.experiments.benchmark.split import candidate_sets, candidate_table, study_split
    from classifiers.learners.persistence import dataset_checksum

    out, table = Path(out), _bare(table)
    learned = study_scores(out)
    seeds = sorted(learned["seed"].unique()) if learned is not None else [config.learning.seed]
    split = study_split(table, config, seeds)
    sets = candidate_sets(table, config, split)
    candidates = candidate_table(sets)
    frames = [baseline_scores(candidates, config.grasp)]
    if learned is not None:
        frames.append(learned[learned["object_id"].isin(set(candidates["object_id"]))])
    else:
        frames.append(fitted_scores(table, candidates, config, seeds))
        model = out / "selector" / "model.zip"
        if model.exists():
            frames.append(sb3_scores(model, sets, config.selector.seed, "rl"))
    scores = pd.concat(frames, ignore_index=True)
    info = {**split.describe(), "dataset_sha256": dataset_checksum(table),
            "scores": "per-seed score files" if learned is not None else "one seed fitted here"}
    try:
        board = _board(candidates, scores, info, reps, config.learning.seed)
    except NoRankableObject as exc:  # a tiny study: say so in the report instead of failing
        board = {"split": info, "methods": {}, "skipped": str(exc)}
        (out / "benchmark").mkdir(parents=True, exist_ok=True)
        (out / "benchmark" / "leaderboard.json").write_text(json.dumps(board, indent=2))
        return board
    _study_budgets(board, out, table, split.test_objects)
    write_leaderboard(board, out / "benchmark")
    return board


#: The study folder of each RL selector on its leaderboard (the one-pick and the retry task's).
SELECTOR_FOLDERS = {"rl": "selector", "rl_retry": "selector_retry"}
#: Name prefixes of the study's supervised learners on its leaderboard.
SUPERVISED_PREFIXES = ("classifier_", "regressor_", "ranker_")


def _study_budgets(board: dict[str, Any], out: Path, table: pd.DataFrame,
                   held_out: Sequence[str]) -> None:  # fmt: skip
    """Each learned method's training budget on the study's board: an RL selector's
    environment steps (its runs' zips, ``selector/seed_<s>/model.zip`` and the retry task's
    ``selector_retry/seed_<s>/model.zip``), a supervised learner's
    labelled grips of the training objects (every grip outside ``held_out``)."""
    from classifiers.experiments.benchmark.provenance import budget_text, recorded_budget

    train = table[~table["object_id"].astype(str).isin(set(held_out))]
    trials = int(train["trials"].sum()) if "trials" in train.columns else None
    grips = {"grips": len(train), "objects": int(train["object_id"].nunique()), "trials": trials}
    for name, row in board["methods"].items():
        zips = _selector_zips(out / SELECTOR_FOLDERS[name]) if name in SELECTOR_FOLDERS else []
        if zips:
            found = [recorded_budget(path) for path in zips]
            texts = list(dict.fromkeys(b["text"] for b in found))
            row["budget"] = {**found[0], "runs": found,
                             "text": texts[0] + " a run" if len(texts) == 1 else "; ".join(texts)}
        elif name.startswith(SUPERVISED_PREFIXES):
            row["budget"] = {**grips, "text": budget_text(grips)}


def _selector_zips(folder: Path) -> list[Path]:
    """A study selector's runs (``seed_<s>/model.zip``), or its single run's zip."""
    return sorted(folder.glob("seed_*/model.zip")) or [
        p for p in [folder / "model.zip"] if p.is_file()]


def _bare(table: pd.DataFrame) -> pd.DataFrame:
    """``table`` without its ``attrs`` (the manifest): pandas deep-copies them on every
    operation, which made the candidate sets of one benchmark take seconds."""
    bare = table.copy(deep=False)
    bare.attrs = {}
    return bare


def _board(candidates: pd.DataFrame, scores: pd.DataFrame, split: dict[str, Any], reps: int,
           seed: int) -> dict[str, Any]:  # fmt: skip
    from classifiers.experiments.benchmark.leaderboard import build_leaderboard
    from classifiers.experiments.benchmark.retry import retry_leaderboard, retry_metrics
    from classifiers.experiments.benchmark.selection import selection_metrics
    from grip_env.dataset.shards import recorded_trial_successes

    metrics = selection_metrics(candidates, scores)
    board = build_leaderboard(metrics, split, reps=reps, seed=seed)
    board["per_object"] = metrics.round(6).to_dict(orient="records")
    if recorded_trial_successes(candidates.columns):  # the retry task, from the shared draws
        retry = retry_metrics(candidates, scores)
        board["retry"] = retry_leaderboard(retry, reps, seed)
        board["retry"]["per_object"] = retry.round(6).to_dict(orient="records")
    return board
