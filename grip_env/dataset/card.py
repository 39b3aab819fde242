"""A dataset card (``docs/dataset.md`` for the standard dataset), written from the dataset itself.

    grip-env validate DIR --resimulate 100 --retest 40 --report R.json
    grip-env validate DIR --crosscheck 80 --report DIR/crosscheck/crosscheck.json
    python -m grip_env.dataset.card DIR --out docs/dataset.md --report R.json

Every figure comes from the dataset's manifest and grips (and, when given, the report of a
``grip-env validate`` run), so the card is re-made, never edited, when the
dataset changes.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from grip_env.dataset.loading import load
from grip_env.dataset.manifest import earlier_runs, recorded_engine
from grip_env.label_model import label_model_of

#: What "g" means wherever robustness is defined (the card, the concepts page, the columns).
GRAVITY_UNIT = ("A level in g is an acceleration of the object, a multiple of gravity's 9.81 m/s² "
                "(a force of level × mass × 9.81 N), not grams")
#: The quantiles of mean robustness the card tabulates.
QUANTILES = (0.1, 0.25, 0.5, 0.75, 0.9)


def dataset_card(directory: str | Path, report: dict[str, Any] | None = None) -> str:
    """The card of the (finished or partial) dataset in ``directory``, as Markdown."""
    grips = load(directory, allow_partial=True)
    manifest = grips.attrs["manifest"]
    families = pd.Series({e["object_id"]: e["family"] for e in manifest["objects"]})
    sections = [_heading(manifest, grips), _making(manifest, grips),
                _composition(grips, families, manifest), _outcomes(grips, manifest),
                _reliability(report), _calibration(Path(directory)),
                _engines(manifest, Path(directory), report), _limits(manifest, report),
                _licence()]
    return "\n\n".join(sections) + "\n"


def _heading(manifest: dict[str, Any], grips: pd.DataFrame) -> str:
    done = len(manifest["shards"])
    state = ("" if manifest.get("complete") else
             f"\n\n**Unfinished:** {done} of {len(manifest['objects'])} objects generated so far; "
             "every figure below is of those.")
    return (f"# Dataset card: {len(grips):,} grips on "
            f"{grips['object_id'].nunique():,} objects (label model "
            f"`{label_model_of(manifest)}`){state}")


def _making(manifest: dict[str, Any], grips: pd.DataFrame) -> str:
    earlier = earlier_runs(manifest)  # trials added to smaller runs of it
    sessions = [s for run in [*earlier, manifest] for s in run.get("sessions", [])]
    wall_h = sum(s["seconds"] for s in sessions) / 3600
    core_h = sum(s["seconds"] * s["workers"] for s in sessions) / 3600
    commits = [str(run["git_commit"])[:7] for run in [*earlier, manifest] if run.get("git_commit")]
    added = [f"- {_trial_steps(earlier, manifest)} by `python -m grip_env.dataset.trial_extension` "
             "(the same run: every object's grips re-planned bit for bit, only the new trials "
             "simulated)."] if earlier else []
    machines = sorted({s["machine"] for s in sessions}) or ["unrecorded"]
    rate = len(grips) / (core_h * 3600) if core_h else float("nan")
    config = manifest["config"]
    return "\n".join([
        "## How it was made", "",
        "    grip-env generate --config configs/standard.yaml --out DIR",
        "",
        f"- Code at commit {', '.join(commits)}; label model `{label_model_of(manifest)}`; "
        f"run seed "
        f"{manifest['seed']}; grip-env {manifest['package_version']}.",
        f"- {manifest['trials']} trials a grip (common random numbers across an object's grips), "
        f"at most {config['dataset']['max_grips_per_object']} grips an object, sampled "
        f"`{config['dataset']['sampling']}` by Q_C; grips planned on the contour segmented from a "
        f"{config['perception']['resolution_px']} px top-down render.",
        f"- Cost: {wall_h:.2f} h of wall time over {len(sessions)} run(s), "
        f"**{core_h:.2f} core-hours**, {rate:.2f} grips a core-second "
        f"(workers × wall time, with perception, including any time the run was paused or "
        f"shared its cores); on {'; '.join(machines)}.",
        *added,
    ])


def _trial_steps(earlier: list[dict[str, Any]], manifest: dict[str, Any]) -> str:
    """How the trials were made, step by step: 'Trials 1–3 made at e868eef, trial 4 added at
    bf0369d, ...'."""
    ends = [int(run["trials"]) for run in earlier] + [int(manifest["trials"])]
    commits = [str(run.get("git_commit"))[:7] for run in [*earlier, manifest]]
    steps = [f"{'Trial 1' if ends[0] == 1 else f'Trials 1–{ends[0]}'} made at {commits[0]}"]
    for start, end, commit in zip(ends[:-1], ends[1:], commits[1:], strict=True):
        span = f"trial {end}" if end == start + 1 else f"trials {start + 1}–{end}"
        steps.append(f"{span} added at {commit}")
    return ", ".join(steps)


def _composition(grips: pd.DataFrame, families: pd.Series, manifest: dict[str, Any]) -> str:
    by_object = grips.groupby("object_id").size()
    listed = families[[e["object_id"] for e in manifest["objects"]
                       if e["object_id"] in manifest["shards"]]]
    rows = ["## Objects and grips", "",
            "| family | objects run | with grips | grips | success | mean robustness (g) |",
            "| --- | --- | --- | --- | --- | --- |"]
    for family in sorted(set(listed)):
        ids = listed.index[listed == family]
        mine = grips[grips["object_id"].isin(ids)]
        rows.append(f"| {family} | {len(ids)} | {int(by_object.reindex(ids).notna().sum())} | "
                    f"{len(mine):,} | {_share(mine['success'])} | "
                    f"{mine['robustness_mean'].mean():.1f} |")
    rows.append(f"| **all** | {len(listed)} | {by_object.size} | {len(grips):,} | "
                f"{_share(grips['success'])} | {grips['robustness_mean'].mean():.1f} |")
    skipped = manifest.get("skipped_objects", [])
    if skipped:
        rows += ["", f"{len(skipped)} meshes were refused by the mesh set (several parts, a "
                 "hole, or no stable rest) and the next ones taken; the manifest lists why."]
    return "\n".join(rows)


def _outcomes(grips: pd.DataFrame, manifest: dict[str, Any]) -> str:
    sim = manifest["config"]["sim"]
    robustness = grips["robustness_mean"]
    quantiles = np.quantile(robustness, QUANTILES) if len(grips) else [np.nan] * len(QUANTILES)
    cap = float(sim["ramp_levels_g"][1])
    return "\n".join([
        "## Outcomes", "",
        f"A grip's `success` is holding the {sim['reference_level_g']:g} g reference in at least "
        f"half its trials; `robustness_mean` is the mean over its trials of the highest planar "
        f"disturbance held in every direction ({sim['ramp_levels_g'][0]:g}–{cap:g} g). "
        f"{GRAVITY_UNIT}.",
        "",
        f"- Success rate {_share(grips['success'])}; per-object success rates range "
        f"{_per_object_range(grips)}.",
        _per_trial_line(grips),
        f"- Robustness: {_share(robustness == 0)} of grips drop the object in every trial, "
        f"{_share(robustness >= cap)} hold the ramp's ceiling in every trial.",
        "",
        "| quantile | " + " | ".join(f"{q:.0%}" for q in QUANTILES) + " |",
        "| --- |" + " --- |" * len(QUANTILES),
        "| mean robustness (g) | " + " | ".join(f"{v:.1f}" for v in quantiles) + " |",
    ])


def _per_trial_line(grips: pd.DataFrame) -> str:
    """Whether the files hold every trial's outcome by trial index."""
    from grip_env.dataset.shards import recorded_trials

    if recorded_trials(grips.columns):
        return ("- Every trial's outcome is recorded by trial index (`trial_success_k`, "
                "`trial_robustness_k`): trial k of an object's grips met one draw, so retries "
                "that share it can be replayed and scored.")
    return ("- Every trial's outcome by trial index is **not** in these files (made before it "
            "was kept): `python -m grip_env.dataset.trial_outcomes DIR --out TRIALS` re-simulates "
            "it, checked against these summaries bit for bit, and `--attach` adds it to them.")


def _reliability(report: dict[str, Any] | None) -> str:
    """From a ``grip-env validate --resimulate N --retest K --report R.json`` report."""
    report = report or {}
    lines = ["## Reliability", ""]
    if "resimulation" in report:
        found = report["resimulation"]
        lines.append(f"- **Reproduced:** `grip-env validate --resimulate {found['grips']}` "
                     f"(seed {found['seed']}): {found['summary']}.")
    else:
        lines.append("- Reproduction not measured yet: `grip-env validate --resimulate N DIR`.")
    if "retest" in report:
        found = report["retest"]
        lines.append(f"- **Test-retest:** `grip-env validate --retest {found['objects']}` "
                     f"(seed {found['seed']}; every grip of the sampled objects under new "
                     f"draws): {found['summary']}.")
    else:
        lines.append("- Within-object test-retest not measured yet: `grip-env validate "
                     "--retest K DIR`.")
    return "\n".join(lines)


#: The label model's calibration recorded with a dataset (``grip-env calibrate --config RECIPE
#: --data DIR --out DIR/calibration``).
CALIBRATION_FILE = Path("calibration") / "calibration.json"


def _calibration(directory: Path) -> str:
    """The recorded calibration's checks, one row each (a pointer to the command without it)."""
    path = directory / CALIBRATION_FILE
    if not path.is_file():
        return ("## Label-model calibration\n\nNot recorded with this dataset: `grip-env calibrate "
                "--config RECIPE --data DIR --out DIR/calibration`.")
    found = json.loads(path.read_text())
    rows = [f"| {name} | {_measured(check)} | {check.get('target', '')} | "
            f"{_verdict(check.get('passed'))} |" for name, check in found["checks"].items()]
    return "\n".join([
        "## Label-model calibration", "",
        f"`grip-env calibrate --config configs/standard.yaml --data DIR --out DIR/calibration` "
        f"(label model `{found.get('label_model')}`, {found['trials']:,} trials, recorded in "
        f"`{CALIBRATION_FILE}` and read by the study): do the labels measure the grip?", "",
        "| check | measured [95 % interval] | target | verdict |", "| --- | --- | --- | --- |",
        *rows,
    ])


def _measured(check: dict[str, Any]) -> str:
    value, ci = check.get("measured"), check.get("ci")
    if isinstance(value, dict):  # per object (the design boxes)
        return ", ".join(f"{name} {level:.1f} g" for name, level in value.items())
    if value is None:
        return "–"
    shown = f"{value:.3f}" + (f" [{ci[0]:.3f}, {ci[1]:.3f}]" if ci and None not in ci else "")
    sample = ", ".join(f"{check[k]} {k}" for k in ("objects", "grips") if k in check)
    return shown + (f" ({sample})" if sample else "")


def _verdict(passed: bool | None) -> str:
    return "not judged" if passed is None else "pass" if passed else "fail"


def _limits(manifest: dict[str, Any], report: dict[str, Any] | None) -> str:
    found = (report or {}).get("retest")
    repeats = (f"repeats at {found['within']:.2f} (within-object retest above), not 1" if found
               else "repeats imperfectly (`grip-env validate --retest K` measures how well)")
    return "\n".join([
        "## Known limits", "",
        "- Planar objects: each is extruded from its outline (meshes from their resting "
        "silhouette) and grasped in one plane; no 3-D grasps.",
        f"- {manifest['trials']} trials a grip: `success_rate` is a binomial estimate of few "
        f"draws, and the ranking of one object's grips {repeats}.",
        "- One simulated hand (the Barrett BH8-280 URDF with compliant pads and worm-gear "
        "stops, BENCHMARKS.md), one friction and mass range: labels are the simulator's, "
        "not a real hand's.",
        "- The label's within-object ranking is bounded by near-equal grips (thumb variants "
        "of one grasp) whose means differ by less than a ramp level.",
        "- The labels belong to one label model; another grip-env warns about them, and a "
        "change of the simulator that moves any outcome needs the dataset regenerated.",
    ])


#: The cross-check recorded with a dataset (``grip-env validate DIR --crosscheck N --report
#: DIR/crosscheck/crosscheck.json``), read by the card and by the study's report.
CROSSCHECK_FILE = Path("crosscheck") / "crosscheck.json"


def recorded_crosscheck(directory: Path, report: dict[str, Any] | None = None,
                        ) -> dict[str, Any] | None:
    """The cross-check of ``report`` (a ``validate --report`` JSON), else the one recorded with
    the dataset in ``directory`` (:data:`CROSSCHECK_FILE`), else None."""
    if report and "crosscheck" in report:
        return report["crosscheck"]
    path = Path(directory) / CROSSCHECK_FILE
    return json.loads(path.read_text()).get("crosscheck") if path.is_file() else None


def _engines(manifest: dict[str, Any], directory: Path, report: dict[str, Any] | None) -> str:
    engine = recorded_engine(manifest)
    head = ["## The engine's share of a label", "",
            f"Labelled in {engine['name']} {engine.get('version') or '(version unrecorded)'}, "
            f"label model `{label_model_of(manifest)}`."]
    found = recorded_crosscheck(directory, report)
    if found is None:
        return "\n".join([*head, "", "Not cross-checked in the other engine yet: `grip-env "
                          f"validate DIR --crosscheck 80 --report DIR/{CROSSCHECK_FILE}`."])
    return "\n".join([*head, "", crosscheck_markdown(found)])


def _figure(group: dict[str, Any], name: str, percent: bool = False) -> str:
    if name not in group:  # a cross-check recorded before the figure existed
        return "–"
    value, (low, high) = group[name], group[f"{name}_interval"]
    if value is None or not np.isfinite(value):
        return "–"
    shown = (lambda v: f"{v:.1%}") if percent else (lambda v: f"{v:.2f}")
    bounds = f" [{shown(low)}, {shown(high)}]" if low is not None and np.isfinite(low) else ""
    return shown(value) + bounds


def crosscheck_tables(found: dict[str, Any]) -> tuple[str, pd.DataFrame, pd.DataFrame]:
    """A ``validate --crosscheck`` result (its report's ``crosscheck``) as what it is, the
    agreement overall, by family, by grips an object and by convex pieces, with each engine's
    retest and mean robustness beside it, and the engines' costs (tables of formatted text)."""
    a, b = found["engine"], found["other"]
    intro = (f"`grip-env validate DIR --crosscheck {found.get('objects', '')} --seed "
             f"{found['seed']}`: every recorded grip of the sampled objects simulated again in "
             f"{a} and in {b} (same grips, draws and protocol; {found['reproduced']} of "
             f"{found['overall']['grips']} grips reproduced their recorded labels in {a}"
             f"{_models(found)}). "
             "Intervals: 95 % bootstrap over objects. Each engine's within-object retest (its "
             "own labels under new draws) is the ceiling of the agreement between them. The "
             "label's shares split the variance of a label between the grips of an object into "
             "the grip (alike in both engines), the engine's own view of it, and the draws its "
             "trials average (`grip_env.dataset.label_shares`). Costs: "
             "the CPU of the run that simulated each engine's trials (a run that resumes "
             "another reads them back), so two engines' rows may come from different loads; "
             "the trials a trustworthy label needs by Spearman-Brown from the retest at the "
             "dataset's trials, and as measured at every label size over splits of each "
             "object's retested trials (`grip_env.dataset.retest_curve`).")
    groups = [("all", found["overall"]), *sorted(found.get("families", {}).items()),
              *found.get("by_grips", {}).items(), *found.get("by_pieces", {}).items()]
    agreement = pd.DataFrame([{
        "objects": name, "n": str(g["objects"]), "success alike": _figure(g, "agreement", True),
        "kappa": _figure(g, "kappa"), "within-object Spearman": _figure(g, "within"),
        f"retest {a}": _figure(g, "retest_own"), f"retest {b}": _figure(g, "retest_other"),
        "pooled Spearman": _figure(g, "pooled"), f"top-1 {a} in {b}": _figure(g, "top1_own", True),
        f"top-1 {b} in {a}": _figure(g, "top1_other", True),
        f"mean robustness {a} / {b} (g)": _robustness(g),
        "label: the grip's share": _figure(g, "share_grip", True),
        "the engine's": _figure(g, "share_engine", True),
        "the draws'": _figure(g, "share_draws", True)} for name, g in groups])
    cost = pd.DataFrame([{
        "engine": c["engine"], "trials": f"{c['trials']:,}",
        "CPU s a trial": f"{c['ms_per_trial'] / 1e3:.3f}", "µs a step": f"{c['us_per_step']:.0f}",
        "trials for retest 0.8 (Spearman-Brown)": f"{c['trials_for_trustworthy']:.1f}",
        "core-s a trustworthy label": f"{c['core_seconds_per_label']:.2f}",
        "retest measured at 1..T trials": _curve(c.get("retest_by_trials")),
        "trials for retest 0.8 (measured)": _count(c.get("trials_measured")),
        "core-s a label (measured)": _count(c.get("core_seconds_measured"), "{:.2f}")}
        for c in found.get("cost", [])])
    return intro, agreement, cost


def _curve(values: list[float] | None) -> str:
    """A retest curve as its values; a dash for a report made before it was recorded."""
    return ", ".join(f"{v:.2f}" for v in values) if values else "–"


def _count(value: float | None, form: str = "{:.0f}") -> str:
    """A figure, or a dash when the report predates it or it was not measured."""
    return form.format(value) if value is not None and np.isfinite(value) else "–"


def _robustness(group: dict[str, Any]) -> str:
    """Each engine's mean robustness over the group's trials (a report made before they were
    recorded shows a dash)."""
    own, other = group.get("robustness_own"), group.get("robustness_other")
    if own is None or other is None or not (np.isfinite(own) and np.isfinite(other)):
        return "–"
    return f"{own:.1f} / {other:.1f}"


def _models(found: dict[str, Any]) -> str:
    models = found.get("label_models") or {}
    return ("; label models " + " and ".join(f"`{models[e]}`" for e in models)) if models else ""


def crosscheck_markdown(found: dict[str, Any]) -> str:
    """:func:`crosscheck_tables` as Markdown."""
    intro, agreement, cost = crosscheck_tables(found)
    return "\n\n".join([intro, *(_markdown(t) for t in (agreement, cost) if len(t))])


def _markdown(table: pd.DataFrame) -> str:
    return "\n".join([f"| {' | '.join(table.columns)} |",
                      f"| {' | '.join('---' for _ in table.columns)} |",
                      *(f"| {' | '.join(row)} |" for row in table.astype(str).to_numpy())])


def _licence() -> str:
    return "\n".join([
        "## Licence and citation", "",
        "The dataset is released under the MIT licence, as grip-env. Its mesh objects are "
        "silhouettes of `pybullet_data` models (zlib licence, the Bullet Physics SDK). Cite "
        "grip-env ([CITATION.cff](../CITATION.cff)) and the paper whose measures its features "
        "are (Chinellato et al., 2005; README).",
    ])


def _share(values: pd.Series) -> str:
    return f"{float(np.mean(values)):.1%}" if len(values) else "n/a"


def _per_object_range(grips: pd.DataFrame) -> str:
    rates = grips.groupby("object_id")["success"].mean()
    if rates.empty:
        return "n/a"
    return f"{rates.min():.0%}–{rates.max():.0%} (median {rates.median():.0%})"


def main() -> None:
    parser = argparse.ArgumentParser(description="Write a dataset's card.")
    parser.add_argument("directory", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--report", type=Path, help="a grip-env validate --report JSON")
    args = parser.parse_args()
    found = json.loads(args.report.read_text()) if args.report else None
    args.out.write_text(dataset_card(args.directory, found), encoding="utf-8")


if __name__ == "__main__":
    main()
