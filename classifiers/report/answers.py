"""The study's questions and their answers, one sentence each, worded from ``answers.json``
(:mod:`classifiers.experiments.answers`).

The verb of every answer is :func:`classifiers.evaluation.verdicts.relation` of the interval of the
paired difference, the rule of the leaderboard's verdicts; a difference that cannot carry a
verdict (:func:`~classifiers.report.judge.unjudgeable`, or too few ranked objects) is shown with
the reason instead.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from classifiers.evaluation.verdicts import relation
from classifiers.report.judge import FEW_OBJECTS, unjudgeable

ANSWERS_FILE = "answers.json"
_QC, _QG = "best-Q_C", "best-Q_G"
#: A difference of two rates (top-1 success, ROC-AUC) lies in [-1, 1].
_SPAN = (-1.0, 1.0)


def read_answers(out: Path) -> dict[str, Any] | None:
    """The study's ``answers.json``, or None when it has none."""
    path = Path(out) / ANSWERS_FILE
    return json.loads(path.read_text()) if path.is_file() else None


def signed(value: dict[str, Any], digits: int = 3) -> str:
    """``+0.035 [+0.001, +0.072]`` of an ``{"estimate" or "mean", "ci"}`` block."""
    point = value.get("estimate", value.get("mean"))
    low, high = value["ci"]
    return f"{point:+.{digits}f} [{low:+.{digits}f}, {high:+.{digits}f}]"


def answers_preamble(answers: dict[str, Any]) -> str:
    """What the answers' differences are: top-1 success, paired over the held-out objects."""
    objects = next((row["objects"] for row in answers.get("picks", {}).values()), None)
    over = f"the {objects} held-out objects" if objects else "the held-out objects"
    return (f"A pick's difference is in top-1 success (how often the grip it picks holds), "
            f"paired over {over}, with its 95 % stratified-bootstrap interval; the leaderboard "
            "below judges the normalised score, so its verdict on a method can differ where the "
            "two measures part.")


def answer_sentences(answers: dict[str, Any]) -> list[str]:
    """The three questions and their answers (Markdown), in the order the study asks them."""
    retry = [_retry(answers)] if answers.get("retry") else []
    return [_learned_pick(answers), _hand_measures(answers), _rl_selector(answers),
            _image(answers), *retry]


def strong_methods(answers: dict[str, Any]) -> list[str]:
    """The methods the answers name, for the figures to draw strongly: the best supervised
    method, the RL selector, best-Q_G and best-Q_C."""
    best = answers.get("best_supervised")
    return [name for name in (best, "rl", "best_qg", "best_qc") if name]


def _learned_pick(answers: dict[str, Any]) -> str:
    best = answers.get("best_supervised")
    question = "**Does a learned pick beat best-Q_C, and best-Q_G?**"
    if best is None:
        return f"{question} Not answered: {_no_board(answers)}."
    return (f"{question} `{best}`, the best supervised method on the leaderboard, "
            f"{_compare(answers, best, 'best_qc', _QC)} and "
            f"{_compare(answers, best, 'best_qg', _QG)}.")


def _hand_measures(answers: dict[str, Any]) -> str:
    question = "**Do the hand measures (C1–C6) matter?**"
    hand = answers.get("hand_measures")
    if hand is None:
        learned = "The ablation did not run"
    else:
        problem = unjudgeable(hand, hand.get("objects"), _SPAN)
        learned = (f"A classifier ({hand['model']}) without them changes ROC-AUC by "
                   f"{signed(hand)}, no verdict ({problem})" if problem else
                   f"A classifier ({hand['model']}) without them **{relation(hand['ci'])}** "
                   f"itself with all twelve measures (ROC-AUC {signed(hand)})")  # fmt: skip
    return (f"{question} {learned}; at picking, {_QG}, whose index leaves them out, "
            f"{_compare(answers, 'best_qg', 'best_qc', _QC)}.")


def _rl_selector(answers: dict[str, Any]) -> str:
    question = ("**Does the RL selector beat best-Q_C, and does it match the best supervised "
                "method?**")
    if "rl - best_qc" not in answers.get("picks", {}):
        return f"{question} Not answered: {answers.get('skipped') or 'no RL selector was scored'}."
    best = answers.get("best_supervised")
    against_best = f" and {_compare(answers, 'rl', best, f'`{best}`')}" if best else ""
    return f"{question} The RL selector {_compare(answers, 'rl', 'best_qc', _QC)}{against_best}."


#: The smallest ROC-AUC gain the image answer treats as something the measures miss (the
#: study's target half-width): "yes, they capture it" needs the interval below it.
WORTH_STATING = 0.03
#: How the image models are named in the answer.
_SHOWN = {"cnn": "the image alone (`cnn`)", "cnn_measures": "the image with the measures "
          "(`cnn_measures`)"}


def _image(answers: dict[str, Any]) -> str:
    """The fourth answer: does the image hold what the measures miss? One sentence on the
    image-with-measures model (the image alone beside it), then its picks."""
    question = "**Do the twelve measures capture what the grip's image holds?**"
    image = answers.get("image")
    if not image or not image.get("models"):
        return f"{question} Not answered: the image stage did not run."
    joined = "cnn_measures" if "cnn_measures" in image["models"] else image["models"][0]
    auc = image["auc"].get(joined, {})
    problem = unjudgeable(auc, auc.get("objects"), _SPAN) if auc else "no cross-validation"
    reference = f"`{image['reference']}` on the twelve measures"
    if not auc:
        verdict = "Not answered: the image stage's cross-validation did not run"
    elif problem:
        verdict = (f"Not answered: {_SHOWN.get(joined, joined)} against {reference} changes "
                   f"ROC-AUC by {signed(auc)}, no verdict ({problem})")
    elif auc["ci"][0] > 0:
        verdict = (f"No: they miss something worth {auc['mean']:+.3f} ROC-AUC: "
                   f"{_SHOWN.get(joined, joined)} **beats** {reference} ({signed(auc)})")
    elif auc["ci"][1] <= WORTH_STATING:
        verdict = (f"Yes, as far as this network can tell: {_SHOWN.get(joined, joined)} "
                   f"**{relation(auc['ci'])}** {reference} ({signed(auc)})")
    else:
        verdict = (f"Not answered: {_SHOWN.get(joined, joined)} against {reference} changes "
                   f"ROC-AUC by {signed(auc)}, an interval that allows the image a gain of up "
                   f"to {auc['ci'][1]:+.3f}")
    alone = [_against_it(_SHOWN.get(n, n), image["auc"][n]) for n in image["models"]
             if n != joined and n in image["auc"]]  # fmt: skip
    picks = {"picks": image.get("picks", {}), "ranked_objects": answers.get("ranked_objects", 0)}
    at_picking = _image_picks(picks, joined, image.get("reference"),
                              gained=bool(auc) and not problem and auc["ci"][0] > 0)
    return f"{question} {verdict}{'; ' + '; '.join(alone) if alone else ''}; {at_picking}."


def _image_picks(picks: dict[str, Any], joined: str, reference: str | None, gained: bool) -> str:
    """The image model's picks against the measures' learner, lambdarank and best-Q_C; after a
    ROC-AUC gain (``gained``), whether the gain carries over to picking: it does when its picks
    beat the learner's it gained over (lambdarank's when that learner's picks were not
    scored), it does not when that interval says not, and nothing is claimed without a
    verdict."""
    method = f"classifier_{joined}"
    shown = [(f"classifier_{reference}", f"`{reference}`")] if reference else []
    shown += [("ranker_lambdarank", "`lambdarank`"), ("best_qc", _QC)]
    found = [(versus, name) for versus, name in shown if f"{method} - {versus}" in picks["picks"]]
    if not found:
        return f"at picking, `{joined}` was not compared (no pick of it was scored)"
    parts = [_compare(picks, method, versus, name) for versus, name in found]
    listed = parts[0] if len(parts) == 1 else f"{', '.join(parts[:-1])} and {parts[-1]}"
    key = f"{method} - {found[0][0]}"
    if gained and "no verdict" not in parts[0]:
        carries = relation(picks["picks"][key]["ci"]) == "beats"
        lead = ("and the gain carries over to picking" if carries
                else "but the gain does not carry over to picking")
        return f"{lead}: `{joined}` {listed}"
    return f"at picking, `{joined}` {listed}"


def _against_it(shown: str, auc: dict[str, Any]) -> str:
    """``the image alone (`cnn`) **beats** it (+0.010 [...])``, or its numbers without a verdict."""
    problem = unjudgeable(auc, auc.get("objects"), _SPAN)
    if problem:
        return f"{shown} against it: {signed(auc)}, no verdict ({problem})"
    return f"{shown} **{relation(auc['ci'])}** it ({signed(auc)})"


def image_family_rows(answers: dict[str, Any]) -> list[dict[str, Any]]:
    """The image models' top-1 differences by family, as table rows (family, comparison,
    difference with its interval, objects)."""
    image = answers.get("image") or {}
    return [{"family": family, "comparison": name, "difference": signed(row),
             "objects": row["objects"]}
            for family, found in image.get("families", {}).items()
            for name, row in found.items()]  # fmt: skip


def _compare(answers: dict[str, Any], method: str, versus: str, shown: str) -> str:
    """``beats best-Q_C (+0.035 [+0.001, +0.072])``, or the numbers with why no verdict."""
    row = answers.get("picks", {}).get(f"{method} - {versus}")
    if row is None:
        return f"was not compared with {shown} (one of them was not scored)"
    ranked = answers.get("ranked_objects", 0)
    value = {"mean": row["estimate"], "ci": row["ci"]}
    problem = unjudgeable(value, row.get("objects"), _SPAN)
    if problem is None and ranked < FEW_OBJECTS:
        problem = f"only {ranked} held-out object(s) could be ranked (fewer than {FEW_OBJECTS})"
    if problem:
        return f"against {shown}: {signed(row)}, no verdict ({problem})"
    return f"**{relation(row['ci'])}** {shown} ({signed(row)})"


def _retry(answers: dict[str, Any]) -> str:
    """The retry answer: the RL retry selector within the board's attempts, against best-Q_C's
    and lambdarank's orders of the grips."""
    retry = answers["retry"]
    question = "**Does a retry policy use what a failure tells?**"
    within = retry["within"]
    held = f"{within['rl_retry']['estimate']:.3f}"
    others = "; ".join(f"`{name}` {within[name]['estimate']:.3f}" for name in within
                       if name != "rl_retry")  # fmt: skip
    compared = " and ".join(
        _compare({"picks": retry["picks"], "ranked_objects": retry["objects"]}, "rl_retry",
                 versus, _QC if versus == "best_qc" else f"`{versus}`'s order")
        for versus in ("best_qc", "ranker_lambdarank")
        if f"rl_retry - {versus}" in retry["picks"])  # fmt: skip
    return (f"{question} Within {retry['attempts']} attempts that share the object's draw "
            f"({retry['objects']} held-out objects, {retry['runs']} runs), the RL retry selector, "
            f"which sees which grips failed, holds {held} ({others}): it {compared}.")


def _no_board(answers: dict[str, Any]) -> str:
    return str(answers.get("skipped") or "the leaderboard ranked no supervised method")
