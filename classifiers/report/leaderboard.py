"""The leaderboard read back: its tables, its verdict and ``leaderboard.md``, from the board a
benchmark wrote (``leaderboard.json``, :mod:`classifiers.experiments.benchmark.leaderboard`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from classifiers.report.judge import FEW_OBJECTS

MARKDOWN_FILE = "leaderboard.md"


def verdicts(reference: str) -> tuple[str, str, str]:
    """The three verdicts a method can get against ``reference`` (as the board records them)."""
    return (f"beats {reference}", f"worse than {reference}",
            f"not distinguishable from {reference}")


def beaten(board: Mapping[str, Any]) -> dict[str, list[str]]:
    """Method names per verdict (the reference itself left out)."""
    found: dict[str, list[str]] = {v: [] for v in verdicts(board["reference"])}
    for name, row in board["methods"].items():
        if row["verdict"] in found:
            found[row["verdict"]].append(name)
    return found


def verdict_sentence(board: Mapping[str, Any]) -> str:
    """One plain sentence: who beats best-Q_C with an interval excluding zero, and who does not."""
    groups = beaten(board)
    ref = board["reference"]

    def names(key: str) -> str:
        return ", ".join(f"`{n}`" for n in groups[key]) or "none"

    beats, worse, same = (names(v) for v in verdicts(ref))
    return (f"Beat the best-Q_C pick (95% interval of the difference in mean normalised score "
            f"above zero): {beats}. Worse than `{ref}` (interval below zero): {worse}. Not "
            f"distinguishable from `{ref}` (interval contains zero): {same}.")


def leaderboard_frames(board: Mapping[str, Any]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(main table, attempts table) as shown in leaderboard.md and the report."""
    main, attempts = [], []
    budgets = any(isinstance(row.get("budget"), Mapping) for row in board["methods"].values())
    for name, row in board["methods"].items():
        budget = {"training budget": _budget(name, row)} if budgets else {}
        main.append({
            "method": name, "runs": row["runs"], **budget,
            "top-1 success": _ci({"estimate": row["success"], "ci": row["success_ci"]}),
            "success - best_qc": _ci(row["success_difference_vs_reference"]),
            "top-1 robustness (g)": _f(row["robustness"], 1), "regret": _f(row["regret"]),
            "NDCG@5": _f(row["ndcg5"]), "normalised IQM": _ci(row["iqm"]),
            "normalised mean": _ci(row["mean"]),
            "mean - best_qc": _ci(row["difference_vs_reference"]),
            "P(improve over best_qc)": _ci(row["probability_of_improvement"]),
            "verdict": row["verdict"],
        })  # fmt: skip
        attempts.append({"method": name, **{f"{k} attempt{'s' * (k > 1)}":
                         _f(row[f"success_at_{k}"]) for k in range(1, _attempts(board) + 1)},
                         "expected attempts (budget 5)": _f(row["attempts"])})  # fmt: skip
    return pd.DataFrame(main), pd.DataFrame(attempts)


def _budget(name: str, row: Mapping[str, Any]) -> str:
    """A method's training budget in words (a baseline: none; the oracle reads the outcomes)."""
    if isinstance(row.get("budget"), Mapping):
        return str(row["budget"]["text"])
    return "none (reads the outcomes)" if name == "oracle" else "none (analytic)"


def leaderboard_markdown(board: Mapping[str, Any]) -> str:
    """The leaderboard as Markdown (the same table as the study report's)."""
    main, attempts = leaderboard_frames(board)
    split = board["split"]
    lines = [
        f"# Grip-selection leaderboard ({split.get('name', 'split')})", "",
        split_line(board), "", *_training_lines(board), _table(main), "",
        f"Normalised score: (method - random) / (oracle - random) of the top-1 pick's expected "
        f"success, per object; {board['interval']}. {verdict_sentence(board)}", "",
        "## Success within k attempts (GripAccept-v0 / GripSelect-v0 with max_attempts = k)", "",
        _table(attempts), "",
        attempts_caption(board), "",
        *retry_lines(board),
    ]  # fmt: skip
    return "\n".join(lines)


def attempts_caption(board: Mapping[str, Any]) -> str:
    """What the success-within-k table assumes, and where the shared-draw figures are (or why
    there are none)."""
    formula = ("Chance that one of the method's top-k picks holds, from the recorded success "
               "rates, with the attempts taken as independent (1 - prod(1 - p)).")
    if "retry" in board:
        return (f"{formula} The recorded trials share their draws across an object's grips, so "
                "this overstates what a retry gains: the retry section scores the same attempts "
                "on the shared draws.")
    return (f"{formula} The dataset does not record each trial's outcome, so the attempts "
            "cannot be scored on the shared draws (a retry meets the draw that defeated the "
            "first pick): these figures overstate what a retry gains.")


def retry_lines(board: Mapping[str, Any], heading: bool = True) -> list[str]:
    """The retry task's section (Markdown lines), when the dataset records every trial's
    outcome; ``heading``: with its own heading."""
    if "retry" not in board:
        return []
    retry = board["retry"]
    title = "Retry: success within m attempts that share the object's draw"
    return [*([f"## {title}", ""] if heading else [f"**{title}.**"]),
            retry_table(retry), "",
            f"Each method's order of the grips (an RL retry selector's: the grips it picks "
            f"after each failure); attempt m replays the same trial index k as the first "
            f"(same friction, mass and pose noise), averaged over k, on {retry['objects']} "
            f"objects; paired 95 % intervals. \"Independence overstates\": the column above "
            f"(1 - prod(1 - p)) minus this.", ""]


def write_leaderboard_markdown(board: Mapping[str, Any], out: str | Path) -> Path:
    """Write ``out/leaderboard.md`` (:func:`leaderboard_markdown`); returns its path."""
    path = Path(out) / MARKDOWN_FILE
    path.write_text(leaderboard_markdown(board))
    return path


def split_line(board: Mapping[str, Any]) -> str:
    """One sentence: which split, how many objects, seeds and the dataset's checksum."""
    split = board["split"]
    seeds = split.get("seeds")
    return (f"Split `{split.get('name')}` (version {split.get('version')}): "
            f"{len(board['objects']) + len(board['degenerate_objects'])} held-out objects "
            f"({len(board['degenerate_objects'])} where every candidate has the same success "
            f"rate are left out of the normalised score), up to {split.get('max_candidates')} "
            f"candidates each (lowest Q_C first); training seeds {seeds}; dataset sha256 "
            f"`{str(split.get('dataset_sha256', ''))[:12]}`." + _not_standard(split)
            + _few_objects(board))  # fmt: skip


def training_sentences(board: Mapping[str, Any]) -> list[str]:
    """What each scored method was trained on, as the benchmark checked it (one sentence per
    method with a ``training`` entry: a user's method)."""
    return [f"`{name}`: {row['training']['note']}." for name, row in board["methods"].items()
            if isinstance(row.get("training"), Mapping)]  # fmt: skip


def _training_lines(board: Mapping[str, Any]) -> list[str]:
    sentences = training_sentences(board)
    return [" ".join(sentences), ""] if sentences else []


def _not_standard(split: Mapping[str, Any]) -> str:
    """Why the split is not the latest standard one, and, when it is no standard split at all,
    that its scores do not compare with the standard leaderboards."""
    if split.get("note"):
        return f" Split chosen: {split['note']}."
    if split.get("standard", True):
        return ""
    return " Not the standard split: do not compare these scores with its leaderboards."


def _few_objects(board: Mapping[str, Any]) -> str:
    """A caution when the bootstrap has too few objects to resample."""
    n = len(board["objects"])
    if n >= FEW_OBJECTS:
        return ""
    return (f" Only {n} objects enter the normalised score: a bootstrap over so few objects "
            f"understates the uncertainty; read its intervals and verdicts as indicative only.")


def _table(frame: pd.DataFrame) -> str:
    head = "| " + " | ".join(frame.columns) + " |"
    rule = "| " + " | ".join("---" for _ in frame.columns) + " |"
    body = ["| " + " | ".join(str(v) for v in row) + " |" for row in frame.itertuples(index=False)]
    return "\n".join([head, rule, *body])


def _ci(value: Mapping[str, Any]) -> str:
    low, high = value["ci"]
    return f"{_f(value['estimate'])} [{_f(low)}, {_f(high)}]"


def _f(value: float | None, digits: int = 3) -> str:
    if value is None or not np.isfinite(value):
        return "n/a"
    return f"{round(float(value), digits) + 0.0:.{digits}f}"  # + 0.0: no "-0.000"




def _attempts(board: Mapping[str, Any]) -> int:
    """The most attempts the board records a success rate for (``success_at_k``)."""
    row = next(iter(board["methods"].values()), {})
    return max((int(key.rsplit("_", 1)[1]) for key in row if key.startswith("success_at_")),
               default=0)


def retry_table(board: Mapping[str, Any], methods: Sequence[str] | None = None) -> str:
    """The retry board as a Markdown table: success within m under shared draws [interval],
    minus the reference [paired interval], and the independence formula's overstatement."""
    attempts, reference = int(board["attempts"]), board["reference"]
    names = list(methods or board["methods"])
    head = ["method", *(f"within {m}" for m in range(1, attempts + 1)),
            *(f"within {m} minus {reference}" for m in range(2, attempts + 1)),
            *(f"independence overstates, {m}" for m in range(2, attempts + 1))]
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for name in names:
        row = board["methods"][name]
        cells = [name, *(_signed_ci(row[f"shared_at_{m}"]) for m in range(1, attempts + 1)),
                 *(_signed_ci(row[f"shared_at_{m}_minus_{reference}"], signed=True)
                   for m in range(2, attempts + 1)),
                 *(_signed_ci(row[f"overstatement_at_{m}"], signed=True)
                   for m in range(2, attempts + 1))]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _signed_ci(found: Mapping[str, Any], signed: bool = False) -> str:
    low, high = found["ci"]
    form = "{:+.3f}" if signed else "{:.3f}"
    return f"{form.format(found['estimate'])} [{form.format(low)}, {form.format(high)}]"
