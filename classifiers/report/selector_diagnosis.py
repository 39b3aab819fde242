"""Why the RL selector stops short of the best supervised method, in one sentence from the
measured curves (issue 47 part 1).

The measurements are committed beside the docs, in :data:`DIAGNOSIS_FOLDER`: ``curves.csv``
(held-out top-1 success of the default selector against environment steps, per seed, written
by ``scripts/selector_curve.py``), ``ceiling.csv`` (full-information fits of the selector's
per-candidate scorer and LightGBM's lambdarank, written by ``scripts/selector_ceiling.py``) and
the figure ``curve.png``. Both were measured on the standard dataset's split, so the sentence is
stated for a study of the standard dataset only (:func:`measured_on_standard`). Every figure in
it is read from the two files here: none is typed.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pandas as pd

#: Where the diagnosis lives, relative to the repository root (the README's folder).
DIAGNOSIS_FOLDER = "docs/_static/selector"
CURVES, CEILING, FIGURE = "curves.csv", "ceiling.csv", "curve.png"
#: The curve's variant that is the default selector (reward ``success``), and the step from
#: which its plateau is read (the curve rises to it within the first 10,000 steps).
DEFAULT_VARIANT, PLATEAU_FROM = "success", 10_000
_TREES = "trees"
LAMBDARANK = "ranker_lambdarank"
#: The curve figure's alt text.
FIGURE_ALT = ("Held-out top-1 success of the RL selector against environment steps, by reward "
              "and seed, with lambdarank's and best-Q_C's lines")


def diagnosis(folder: Path) -> dict[str, Any] | None:
    """The figures of the diagnosis read from ``folder``'s ``curves.csv`` and ``ceiling.csv``
    (None when either is missing): the default curve's plateau (the range of its seed means at
    the checkpoints from :data:`PLATEAU_FROM` steps), the neural full-information ceilings (the
    range over scorer configurations of their seed mean at the last iteration, and the best
    single checkpoint) and lambdarank's held-out top-1 per seed in the same fits."""
    curves_path, ceiling_path = Path(folder) / CURVES, Path(folder) / CEILING
    if not (curves_path.is_file() and ceiling_path.is_file()):
        return None
    curves = pd.read_csv(curves_path)
    curve = curves[curves["variant"] == DEFAULT_VARIANT]
    means = curve.groupby("timesteps")["held_out_success"].mean()
    plateau = means[means.index >= PLATEAU_FROM]
    ceiling = pd.read_csv(ceiling_path)
    trees = ceiling[ceiling["encoding"] == _TREES].drop_duplicates(["seed"])
    neural = ceiling[ceiling["encoding"] != _TREES]
    last = neural[neural["iteration"] == neural["iteration"].max()]
    configuration = ["encoding", "objective", "target", "activation", "hidden"]
    by_configuration = last.groupby(configuration, dropna=False)["held_out_top1"].mean()
    if plateau.empty or by_configuration.empty or trees.empty:
        return None
    return {
        "plateau": [float(plateau.min()), float(plateau.max())],
        "plateau_steps": [int(plateau.index.min()), int(plateau.index.max())],
        "curve_seeds": int(curve["seed"].nunique()),
        "ceiling": [float(by_configuration.min()), float(by_configuration.max())],
        "ceiling_best": float(neural["held_out_top1"].max()),
        "ceiling_configurations": len(by_configuration),
        "ceiling_iterations": int(last["iteration"].iloc[0]),
        "lambdarank": [float(trees["held_out_top1"].min()), float(trees["held_out_top1"].max())],
    }


def diagnosis_sentence(found: dict[str, Any], train_objects: int | None,
                       figure: str | None = None) -> str:  # fmt: skip
    """The sentence (Markdown): not steps, not capacity or the reward's noise, but the objective
    and the function class on the training objects; ``figure``: the curve's path to link."""
    low, high = found["plateau"]
    first, last = found["plateau_steps"]
    ceiling_low, ceiling_high = found["ceiling"]
    rank_low, rank_high = found["lambdarank"]
    objects = f"{train_objects} training objects" if train_objects else "the training objects"
    shown = f" ([curve]({figure}))" if figure else ""
    return (
        f"**Why the RL selector stops short of `lambdarank`.** Not for want of steps: its "
        f"held-out top-1 stays within {low:.3f}–{high:.3f} from {first:,} to {last:,} steps "
        f"(the mean of {found['curve_seeds']} seeds at each checkpoint){shown}. Nor of capacity "
        f"or of the 0/1 reward's noise: fitted with every training outcome and no sampling, "
        f"{found['ceiling_configurations']} configurations of its per-candidate neural scorer "
        f"(objectives and input encodings) hold out at {ceiling_low:.3f}–{ceiling_high:.3f} "
        f"after {found['ceiling_iterations']} iterations (best single checkpoint "
        f"{found['ceiling_best']:.3f}), where lambdarank on the same candidates holds out at "
        f"{rank_low:.3f}–{rank_high:.3f}. It is the objective and the function class: a "
        f"softmax top-1 objective fitted by a small network to {objects} generalises no "
        f"further (`{DIAGNOSIS_FOLDER}/{CURVES}`, `{CEILING}`; BENCHMARKS.md, issue 47)."
    )


def measured_on_standard(out: Path, standard: Path | None = None) -> bool:
    """Whether the study in ``out`` learned on the shipped standard dataset, the dataset the
    diagnosis was measured on: its ``data.json`` names a dataset folder (not one it generated)
    whose manifest is the standard dataset's (``standard``: that folder; default the shipped
    one), wherever the two are checked out."""
    recorded = Path(out) / "data.json"
    if not recorded.is_file():
        return False
    data = json.loads(recorded.read_text())
    if data.get("generated") or not data.get("dataset"):
        return False
    if standard is None:
        from grip_env.datasets import SHIPPED

        standard = SHIPPED
    manifests = [Path(folder) / "manifest.json" for folder in (data["dataset"], standard)]
    return all(path.is_file() for path in manifests) and (
        manifests[0].read_bytes() == manifests[1].read_bytes())


def falls_short(answers: dict[str, Any] | None) -> bool:
    """Whether the study's answers put the RL selector below lambdarank, the method the ceilings
    are measured against (the interval of their paired difference below zero)."""
    row = (answers or {}).get("picks", {}).get(f"rl - {LAMBDARANK}")
    return bool(row) and float(row["ci"][1]) < 0


def source_root() -> Path:
    """The repository root of this source checkout (where :data:`DIAGNOSIS_FOLDER` is)."""
    return Path(__file__).resolve().parents[2]


def study_diagnosis(out: Path, answers: dict[str, Any] | None, root: Path | None = None,
                    standard: Path | None = None) -> dict[str, Any] | None:  # fmt: skip
    """The diagnosis to state for the study in ``out``: when it learned on the standard dataset
    (``standard``, see :func:`measured_on_standard`), its RL selector fell short of the best
    supervised method, and ``root`` (default: this source checkout) holds the measured curves;
    else None."""
    if not (falls_short(answers) and measured_on_standard(out, standard)):
        return None
    return diagnosis((root or source_root()) / DIAGNOSIS_FOLDER)


def training_objects(out: Path) -> int | None:
    """How many training objects the study's selector learned on (its ``selector.json``)."""
    path = Path(out) / "selector" / "selector.json"
    if not path.is_file():
        return None
    train = json.loads(path.read_text()).get("split", {}).get("train")
    return len(train) if train else None


def diagnosis_markdown(out: Path, found: dict[str, Any], prefix: str = DIAGNOSIS_FOLDER,
                       ) -> list[str]:  # fmt: skip
    """The sentence and the curve figure (its path under ``prefix``), as Markdown paragraphs."""
    return [diagnosis_sentence(found, training_objects(out)), f"![{FIGURE_ALT}]({prefix}/{FIGURE})"]
