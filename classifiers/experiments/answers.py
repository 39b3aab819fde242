"""The study's three questions, answered with paired differences from its stages' results.

1. Does a learned pick beat best-Q_C, and best-Q_G? The best supervised method of the
   leaderboard (its highest IQM among classifiers, regressors and rankers) against each.
2. Do the hand measures matter? The ablation's ROC-AUC without C1–C6 against all twelve, and, at
   picking, best-Q_G (whose index leaves the hand measures out) against best-Q_C.
3. Does the RL selector beat best-Q_C, and does it match the best supervised method?
4. Do the twelve measures capture what the grip's image holds? The image stage's paired ROC-AUC
   of each image model (``cnn``, ``cnn_measures``) against the measures' learner, and, at
   picking, each image model against the measures' learner, lambdarank and best-Q_C, over all
   held-out objects and by family (meshes, procedural and named shapes).
5. Does a retry policy use what a failure tells? On a dataset that records every trial, the RL
   retry selector's success within the retry board's attempts, which share the object's draw,
   against best-Q_C's and lambdarank's orders of the grips.

A pick's comparison is the difference of top-1 success (the pick's recorded success rate),
paired over every held-out object with the leaderboard's stratified bootstrap: the same resamples
(reps, seed) as the board's ``success_difference_vs_reference``, so a comparison with best-Q_C
equals the board's. :func:`write_answers` writes ``answers.json``; the report words it
(:mod:`classifiers.report.answers`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pandas as pd

from classifiers.experiments.benchmark import SUPERVISED_PREFIXES
from classifiers.experiments.benchmark.aggregate import estimate, mean, paired_bootstraps
from classifiers.experiments.benchmark.leaderboard import REFERENCE, metric_matrices

ANSWERS_FILE = "answers.json"
#: Method name prefixes of the supervised learners on the leaderboard.
SUPERVISED = SUPERVISED_PREFIXES
RL, RL_RETRY, BEST_QG, ORACLE = "rl", "rl_retry", "best_qg", "oracle"
#: The leaderboard method the image models are compared with at picking, beside best-Q_C.
LAMBDARANK = "ranker_lambdarank"
#: The leaderboard's bootstrap of top-1 success (:func:`study_benchmark`'s reps; its seed is
#: ``learning.seed + 1``).
REPS = 2000


def best_supervised(board: dict[str, Any]) -> str | None:
    """The leaderboard's first supervised method (it is sorted by IQM), or None."""
    return next((name for name in board.get("methods", {}) if name.startswith(SUPERVISED)), None)


def pick_differences(board: dict[str, Any], pairs: list[tuple[str, str]], seed: int,
                     reps: int = REPS) -> dict[str, dict[str, Any]]:  # fmt: skip
    """``{"a - b": {"method", "versus", "estimate", "ci", "objects"}}``: top-1 success of ``a``
    minus ``b``, paired over every held-out object of ``board`` (its ``per_object`` rows)."""
    metrics = pd.DataFrame(board["per_object"])
    objects = sorted(set(metrics["object_id"]))
    success = metric_matrices(metrics, "success", objects)
    unknown = sorted({name for pair in pairs for name in pair} - set(success))
    if unknown:
        raise ValueError(f"the leaderboard has no method {unknown[0]!r}")
    boot = paired_bootstraps(success, reps, seed + 1, task_bootstrap=True, objects=objects)
    found = {}
    for a, b in pairs:
        difference = estimate(mean(success[a]) - mean(success[b]),
                              mean(boot[a]) - mean(boot[b]))  # fmt: skip
        found[f"{a} - {b}"] = {"method": a, "versus": b, **difference, "objects": len(objects)}
    return found


def study_answers(out: Path, seed: int) -> dict[str, Any]:
    """The answers of the study in ``out`` (``seed``: its ``learning.seed``), from
    ``benchmark/leaderboard.json`` and ``ablation/ablation.json``; a question whose stage
    scored nothing has None."""
    board = _json(out / "benchmark" / "leaderboard.json")
    best = best_supervised(board)
    ranked = len(board.get("objects", []))
    wanted = [(best, REFERENCE), (best, BEST_QG), (BEST_QG, REFERENCE), (RL, REFERENCE),
              (RL, best)] if best else [(BEST_QG, REFERENCE), (RL, REFERENCE)]  # fmt: skip
    present = set(board.get("methods", {}))
    pairs = [pair for pair in wanted if set(pair) <= present]
    picks = pick_differences(board, pairs, seed) if pairs else {}
    return {"best_supervised": best, "reference": REFERENCE, "ranked_objects": ranked,
            "skipped": board.get("skipped"), "picks": picks,
            "hand_measures": hand_difference(_json(out / "ablation" / "ablation.json")),
            "image": image_answers(board, _json(out / "images" / "images.json"), seed),
            "retry": retry_answers(board, seed),
            "leaderboard_dataset_sha256": board.get("split", {}).get("dataset_sha256")}  # fmt: skip


def hand_difference(ablation: dict[str, Any]) -> dict[str, Any] | None:
    """The ablation's paired ROC-AUC difference without the hand measures (C1–C6) against all
    twelve, with its model and object count, or None without it."""
    model = ablation.get("model")
    block = (ablation.get("feature_sets", {}).get("without_hand", {})
             .get("paired_difference", {}).get(model, {}).get("roc_auc"))  # fmt: skip
    if block is None:
        return None
    return {"model": model, "mean": block["mean"], "ci": block["ci"],
            "objects": ablation.get("cv", {}).get("n_objects")}


def image_answers(board: dict[str, Any], images: dict[str, Any],
                  seed: int) -> dict[str, Any] | None:  # fmt: skip
    """The image stage's answer: each image model's paired ROC-AUC difference to the measures'
    learner (``"auc"``), and its top-1 success against that learner's picks, lambdarank's and
    best-Q_C's over every held-out object (``"picks"``) and each family's (``"families"``);
    None without the stage."""
    models = images.get("models", [])
    if not models:
        return None
    cv = images.get("cv") or {}
    auc = {name: {**cv["paired_difference"][name]["roc_auc"], "objects": cv.get("n_objects")}
           for name in models if name in cv.get("paired_difference", {})}  # fmt: skip
    present = set(board.get("methods", {}))
    learner = f"classifier_{cv['reference']}" if cv.get("reference") else None
    versus_all = (*([learner] if learner else []), LAMBDARANK, REFERENCE)
    pairs = [(f"classifier_{name}", versus) for name in models for versus in versus_all
             if {f"classifier_{name}", versus} <= present]  # fmt: skip
    picks = pick_differences(board, pairs, seed) if pairs else {}
    families: dict[str, Any] = {}
    by_family = images.get("families", {})
    for family in sorted(set(by_family.values())):
        rows = [row for row in board.get("per_object", [])
                if by_family.get(str(row["object_id"])) == family]  # fmt: skip
        if pairs and rows:
            families[family] = pick_differences({"per_object": rows}, pairs, seed)
    return {"reference": cv.get("reference"), "models": models, "auc": auc, "picks": picks,
            "families": families, "resemblance": images.get("resemblance")}


def retry_answers(board: dict[str, Any], seed: int, reps: int = REPS) -> dict[str, Any] | None:
    """The retry board's answer: success within its most attempts of the RL retry selector,
    best-Q_C, lambdarank and the oracle, and the selector's paired differences to best-Q_C and
    lambdarank (the board's resamples); None without a retry selector on the board."""
    from classifiers.experiments.benchmark.retry import retry_leaderboard

    retry = board.get("retry") or {}
    if RL_RETRY not in retry.get("methods", {}) or not retry.get("per_object"):
        return None
    attempts, metrics = int(retry["attempts"]), pd.DataFrame(retry["per_object"])
    within = f"shared_at_{attempts}"
    shown = [name for name in (RL_RETRY, REFERENCE, LAMBDARANK, ORACLE) if name in retry["methods"]]
    differences = {}
    for versus in (REFERENCE, LAMBDARANK):
        if versus in retry["methods"]:
            paired = retry_leaderboard(metrics, reps, seed, reference=versus, attempts=attempts)
            differences[f"{RL_RETRY} - {versus}"] = {
                "method": RL_RETRY, "versus": versus, "objects": retry["objects"],
                **paired["methods"][RL_RETRY][f"{within}_minus_{versus}"]}
    return {"attempts": attempts, "objects": retry["objects"],
            "within": {name: retry["methods"][name][within] for name in shown},
            "runs": retry["methods"][RL_RETRY]["runs"], "picks": differences}


def write_answers(out: str | Path, seed: int) -> Path:
    """Write ``out/answers.json`` (:func:`study_answers`); returns its path."""
    path = Path(out) / ANSWERS_FILE
    path.write_text(json.dumps(study_answers(Path(out), seed), indent=2))
    return path


def _json(path: Path) -> dict[str, Any]:
    return json.loads(path.read_text()) if path.is_file() else {}
