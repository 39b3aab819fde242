"""Assembling ``report.md`` / ``report.html`` of a study folder from its stages' results."""

from __future__ import annotations

import functools
import json
import platform
import shutil
import subprocess
from collections.abc import Callable
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path
from typing import Any

import pandas as pd
import yaml

from classifiers.learners.grip_images import attach_contours
from classifiers.report import analysis, figures
from classifiers.report.answer_figures import ALT_TEXT, draw_answer_figures
from classifiers.report.answers import (
    answer_sentences,
    answers_preamble,
    read_answers,
    strong_methods,
)
from classifiers.report.document import Report, frame_of_intervals
from classifiers.report.grip_images import choose_grips, draw_grip_images
from classifiers.report.image_section import image_section
from classifiers.report.judge import (
    FEW_OBJECTS,
    SPANS,
    difference_verdict,
    leaderboard_caution,
    unjudgeable,
)
from classifiers.report.leaderboard import (
    attempts_caption,
    leaderboard_frames,
    retry_lines,
    split_line,
    verdict_sentence,
)
from classifiers.report.power import power_section
from classifiers.report.selector_diagnosis import (
    DIAGNOSIS_FOLDER,
    FIGURE,
    FIGURE_ALT,
    diagnosis_markdown,
    source_root,
    study_diagnosis,
)
from grip_env.config import Config
from grip_env.objects import PlanarObject, procedural_objects

STAGE_RECORD = "stage.json"
_PACKAGES = ("numpy", "pandas", "scikit-learn", "torch", "pybullet", "gymnasium",
             "stable-baselines3", "sb3-contrib")


def write_report(out: Path, config: Config, table: pd.DataFrame,
                 quick: bool | None = None) -> Path:
    """Write the report of the study in ``out`` and return the Markdown path.

    ``quick``: whether the study ran the ``--quick`` toy profile (None: read from the stage
    records in ``out``, see :func:`ran_quick`); a toy or small study says so at the top.
    """
    fig_dir = out / "figures"
    report = Report("grip-env study")
    _size_banner(report, config, table, ran_quick(out) if quick is None else quick)
    report.text(
        "Candidate Barrett BH8-280 grips of planar objects, characterised by the paper's twelve "
        "visual quality measures and labelled by simulated execution in PyBullet under "
        "positioning, friction and mass uncertainty. Everything below was produced by "
        "`grip-env study` from the configuration listed at the end."
    )
    report.text(f"Written {datetime.now(UTC):%Y-%m-%d %H:%M} UTC from commit {source_commit()}.")
    _answers_section(report, out, fig_dir)
    objects = _study_objects(config)
    _dataset_section(report, table, objects, fig_dir, config)
    _feature_section(report, table, fig_dir)
    _rank_section(report, objects, config)
    _calibration_section(report, out, fig_dir)
    _crosscheck_section(report, out)
    _perception_section(report, out, table)
    _classifier_section(report, out)
    _regression_section(report, out)
    _ablation_section(report, out)
    image_section(report, out, fig_dir)
    _selector_section(report, out)
    _benchmark_section(report, out)
    power_section(report, out)
    _provenance_section(report, out, config)
    md, _ = report.write(out)
    return md


def _selector_diagnosis(report: Report, out: Path, answers: dict[str, Any],
                        fig_dir: Path) -> None:  # fmt: skip
    """Why the RL selector falls short of the best supervised method, from the committed
    curves (a study of the standard dataset whose selector fell short only), the curve beside."""
    found = study_diagnosis(out, answers)
    if found is None:
        return
    figure = source_root() / DIAGNOSIS_FOLDER / FIGURE
    sentence, _ = diagnosis_markdown(out, found)
    report.text(sentence)
    if figure.is_file():
        fig_dir.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(figure, fig_dir / "selector_curve.png")
        report.figure(_rel(fig_dir / "selector_curve.png", out), FIGURE_ALT + ".")


# ---------------------------------------------------------------------------------- sections
def _stage_section(title: str, result_file: str) -> Callable[[Callable[..., None]],
                                                              Callable[..., None]]:
    """A section drawn from one stage's JSON result (``result_file``, relative to the study
    folder): the decorated ``body(report, out, result, *rest)`` is called as
    ``section(report, out, *rest)``, under ``title``, and "Not run." stands in for it when the
    stage wrote no result."""
    def decorate(body: Callable[..., None]) -> Callable[..., None]:
        @functools.wraps(body)
        def section(report: Report, out: Path, *rest: Any) -> None:
            report.heading(title)
            result = _json(out / result_file)
            if result is None:
                report.text("Not run.")
                return
            body(report, out, result, *rest)
        return section
    return decorate


def ran_quick(out: Path) -> bool:
    """Whether the study in ``out`` ran ``--quick``, as its calibration stage's record says (the
    stage records the flag among its inputs, since its sizes depend on it)."""
    record = _json(out / "calibration" / STAGE_RECORD) or {}
    return bool(record.get("inputs", {}).get("quick"))


def _answers_section(report: Report, out: Path, fig_dir: Path) -> None:
    """The study's questions answered in one sentence each, then the figures that show them."""
    report.heading("Answers")
    answers = read_answers(out)
    if answers is None:
        report.text("Not run.")
        return
    for sentence in answer_sentences(answers):
        report.text(sentence)
    _selector_diagnosis(report, out, answers, fig_dir)
    report.text(answers_preamble(answers))
    for name, path in draw_answer_figures(out, strong_methods(answers), fig_dir).items():
        report.figure(_rel(path, out), ALT_TEXT[name] + ".")


def _size_banner(report: Report, config: Config, table: pd.DataFrame, quick: bool) -> None:
    """At the top: a toy profile, or a study too small for verdicts, says so."""
    objects = table["object_id"].nunique()
    learning = config.learning
    if quick:
        report.text(
            "**Toy profile (`grip-env study --quick`).** This study ran the quick profile, which "
            f"checks that every stage runs end to end: {objects} objects, "
            f"{config.dataset.trials} trials per grip, {learning.folds}-fold cross-validation × "
            f"{learning.repeats} repeat(s), {config.selector.timesteps} selector timesteps and "
            "the calibration at its quick sizes. Its numbers show that the stages run, not what "
            "they measure: the intervals below are wide or of zero width, no winner is declared "
            "from them, and checks on too small a sample say so. Run `grip-env study` without "
            "`--quick` for results."
        )
    elif objects < FEW_OBJECTS:
        report.text(
            f"**Small study: {objects} objects.** With fewer than {FEW_OBJECTS} objects the "
            "intervals below are indicative only, and no winner is declared from them."
        )


def _dataset_section(report: Report, table: pd.DataFrame, objects: list[PlanarObject],
                     fig_dir: Path, config: Config) -> None:
    report.heading("Dataset")
    per_object = table.groupby("object_id").size()
    summary = pd.DataFrame(
        {
            "value": [
                table["object_id"].nunique(), len(table), f"{per_object.mean():.1f}",
                f"{per_object.min()}–{per_object.max()}", int(table["trials"].sum()),
                f"{table['success_rate'].mean():.3f}", f"{table['success'].mean():.3f}",
                f"{table['two_finger'].mean():.3f}",
            ]
        },
        index=["objects", "grips (configurations)", "grips per object (mean)",
               "grips per object (range)", "simulated trials", "mean success rate",
               f"fraction labelled success (holds {config.sim.reference_level_g:g} g in at "
               "least half its trials)", "fraction two-finger grips"],
    ).rename_axis("quantity")
    if "robustness_mean" in table.columns:
        robustness = table["robustness_mean"]
        summary.loc["mean robustness (g), median [IQR]"] = (
            f"{robustness.mean():.2f}, {robustness.median():.2f} "
            f"[{robustness.quantile(0.25):.2f}, {robustness.quantile(0.75):.2f}]"
        )
    report.table(summary)
    path = _gallery(table, objects, fig_dir / GALLERY_FILE, fig_dir.parent)
    report.figure(_rel(path, report_root=fig_dir.parent),
                  "Drawn shapes and meshes with their best grip by Q_C (opaque) and worst "
                  "(faint); above each, the share of trials holding the reference level and "
                  "the mean robustness. Axes in mm. Dots: contacts; arrows: real finger forces; "
                  "dashed: finger lines to their spread axes; square: palm centre; × C_G, * C_C "
                  "(paper's Fig. 15).")
    path = _grip_images(table, fig_dir / GRIP_IMAGES_FILE, fig_dir.parent)
    if path is not None:
        report.figure(_rel(path, report_root=fig_dir.parent),
                      "What the image evaluator sees: eight grips (four labelled success, four "
                      "failure, each of another object) drawn in their hand's frame, the palm at "
                      "the centre and the thumb's force up; grey: the silhouette the grips were "
                      "planned on, blue: the fingers' approach, red: the contacts.")


#: The gallery's file in the report's figures folder.
GALLERY_FILE = "gallery.png"
#: The figure of grips' images, beside it.
GRIP_IMAGES_FILE = "grip_images.png"


def _grip_images(table: pd.DataFrame, path: Path, out: Path) -> Path | None:
    """Eight of the study's grips as the image evaluator sees them, when its dataset's objects
    table is found (``out/data.json`` names the dataset); else None."""
    from grip_env.dataset.catalog import read_objects

    found = _json(out / "data.json") or {}
    folder = Path(found.get("dataset", out / "dataset"))
    if not (folder / "objects.parquet").is_file():
        return None
    objects = read_objects(folder)
    present = table[table["object_id"].isin(set(objects["object_id"]))]
    if present.empty:
        return None
    return draw_grip_images(attach_contours(choose_grips(present, 8, seed=0), objects), path)


def _gallery(table: pd.DataFrame, objects: list[PlanarObject], path: Path, out: Path) -> Path:
    """The gallery of the study's dataset: drawn shapes beside meshes, from the dataset's own
    objects (``out/data.json`` names it); the named objects of the config without it."""
    from grip_env.dataset.catalog import load_objects, read_objects

    found = _json(out / "data.json") or {}
    folder = Path(found.get("dataset", out / "dataset"))
    if not (folder / "objects.parquet").is_file():
        present = set(table["object_id"])
        return figures.grip_gallery([o for o in objects if o.name in present][:16], table, path)
    catalog = read_objects(folder)
    if "family" not in catalog.columns:
        catalog = catalog.assign(family="named")
    chosen = figures.gallery_choice(catalog, table)
    loaded = {o.name: o for o in load_objects(folder) if o.name in set(chosen["object_id"])}
    return figures.grip_gallery([loaded[name] for name in chosen["object_id"]], table, path,
                                kinds=list(chosen["kind"]), title=_kind_shares(table, catalog))


def _kind_shares(table: pd.DataFrame, catalog: pd.DataFrame) -> str:
    """One line: how many of the objects with grips are meshes, and how often each kind's grips
    are labelled success."""
    mesh_ids = set(catalog.loc[catalog["family"] == "mesh", "object_id"])
    is_mesh = table["object_id"].isin(mesh_ids)
    objects, meshes = table["object_id"].nunique(), table.loc[is_mesh, "object_id"].nunique()
    rates = [f"{kind} {table.loc[mask, 'success'].mean():.0%}"
             for kind, mask in (("drawn shapes", ~is_mesh), ("meshes", is_mesh)) if mask.any()]
    return (f"{meshes} of {objects} objects are meshes ({meshes / objects:.0%}); grips labelled "
            f"success: {', '.join(rates)}")


def _feature_section(report: Report, table: pd.DataFrame, fig_dir: Path) -> None:
    report.heading("Features and outcomes")
    root = fig_dir.parent
    path = figures.feature_distributions(table, fig_dir / "feature_distributions.png")
    report.figure(_rel(path, root), "Share of the grips that held (green) and slipped (red) "
                  "per bin of each feature; symlog x axis, so no value is cut.")
    correlations = analysis.feature_correlations(table, "spearman")
    pearson = analysis.feature_correlations(table, "pearson")
    constant = analysis.constant_columns(table, analysis.CORRELATION_COLUMNS)
    note = _constant_note(constant)
    path = figures.correlation_heatmap(correlations, fig_dir / "correlations.png")
    report.figure(_rel(path, root), "Spearman rank correlations of the features and Q_C over "
                  "all grips" + (f"; {note}" if note else "") + ".")
    shown = correlations.round(2).assign(**{"Q_C (Pearson)": pearson["Q_C"].round(2)})
    report.table(undefined_as_dash(shown), caption="Spearman rank correlations, with Pearson's r "
                 "against Q_C in the last column (the paper's table in section VI-B, Pearson, "
                 "has Q_C correlating most with C4 (.86) and C1 (.68))"
                 + (f"; {note}" if note else "") + ".")
    for column in ("Q_C", "Q_G"):
        bins = analysis.success_by_decile(table, column)
        path = figures.success_by_bin(bins, fig_dir / f"success_by_{column}.png", column)
        report.figure(_rel(path, root), f"Simulated success rate per {column} decile, 95% "
                      "intervals from a bootstrap over objects; n = grips per decile.")
    bins = analysis.success_by_decile(table, "Q_C")
    trend = bins["success_rate"].iloc[:3].mean() - bins["success_rate"].iloc[-3:].mean()
    report.text(
        f"The best three Q_C deciles hold {bins['success_rate'].iloc[:3].mean():.1%} of the time, "
        f"the worst three {bins['success_rate'].iloc[-3:].mean():.1%} (difference {trend:+.1%}); "
        "the paper expects lower Q_C to hold more often."
    )


def _constant_note(constant: dict[str, float]) -> str:
    """What a dash in the correlations means, naming the constant features ("" if none)."""
    if not constant:
        return ""
    named = ", ".join(f"{name} (every grip {value:g})" for name, value in constant.items())
    verb = "is" if len(constant) == 1 else "are"
    return f"{named} {verb} constant on this dataset: no correlation with it is defined (—)"


_UNDEFINED_NOTE = (" —: undefined on these objects (a ROC-AUC or balanced accuracy needs grips "
                   "that held and grips that slipped among them).")


def undefined_as_dash(frame: pd.DataFrame) -> pd.DataFrame:
    """``frame`` with every undefined (NaN) number shown as "—"."""
    return frame.astype(object).where(frame.notna(), "—")


#: The most objects the rank comparison plans again (every grasp and configuration, not only the
#: dataset's kept grips): the named ones, then the procedural ones in their (seeded) order. The
#: paper compared 8; planning the standard recipe's 338 took a minute of the report.
RANK_OBJECTS = 40


def _rank_section(report: Report, objects: list[PlanarObject], config: Config) -> None:
    from grip_env.planning.pipeline import candidates

    report.heading("Grasp ranks against configuration ranks (paper, section VII-A)")
    comparisons = []
    for obj in objects[:RANK_OBJECTS]:
        table = candidates(obj, config.grasp, config)
        if table["grasp_id"].nunique() >= 3:
            comparisons.append(analysis.compare_ranks(table))
    if not comparisons:
        report.text("No object had three or more grasps; nothing to compare.")
        return
    summary = analysis.rank_summary(comparisons)
    example = max(comparisons, key=lambda c: len(c.table))
    shown = example.table.head(10).assign(
        config_ranks=lambda t: t["config_ranks"].map(lambda r: ", ".join(map(str, r)))
    )[["grasp_rank", "Q_G", "config_ranks"]]
    report.table(shown, caption=f"Table I for {example.object_id}: the ten best grasps by Q_G and "
                 "the Q_C ranks of the configurations each generates.")
    report.table(summary.round(2), caption="Per object: Spearman correlation of the grasp rank "
                 "with its best configuration's rank and with its configurations' mean rank.")
    top3 = int(summary["best_config_from_top3_grasp"].sum())
    top6 = int(summary["best_grasp_config_in_top6"].sum())
    report.text(
        f"Rank correlations: best-configuration {summary['rho_best_config'].median():.2f} (median; "
        f"range {summary['rho_best_config'].min():.2f}–{summary['rho_best_config'].max():.2f}), "
        f"mean-configuration {summary['rho_mean_config'].median():.2f} (range "
        f"{summary['rho_mean_config'].min():.2f}–{summary['rho_mean_config'].max():.2f}); the "
        f"paper found 0.6–0.8. The best configuration comes from one of the three best grasps "
        f"for {top3} of {len(summary)} objects (paper: 7 of 8), and the best grasp's best "
        f"configuration is among the six best for {top6} of {len(summary)} (paper: 7 of 8)."
    )


@_stage_section("Classifiers (grouped cross-validation by object)", "classifiers/metrics.json")
def _classifier_section(report: Report, out: Path, metrics: dict[str, Any]) -> None:
    models = metrics["models"]
    names = ["roc_auc", "balanced_accuracy", "accuracy", "f1", "brier", "top1_success"]
    report.table(frame_of_intervals(models, names),
                 caption="Mean and 95% interval over folds × repeats.")
    objects = metrics.get("cv", {}).get("n_objects")
    best = _best(models, "roc_auc")
    if best:
        top = _best(models, "top1_success")
        report.text(_sentence(
            _winner("ROC-AUC", best, models[best]["roc_auc"], objects, SPANS["roc_auc"]),
            _winner("top-1 (does the model's top-ranked grip on a test object hold)", top,
                    models[top]["top1_success"], objects, SPANS["top1_success"])))
    sampled = metrics.get("sampled") or {}
    if sampled:
        report.text("Fitted on a seeded sample of their training grips (a kernel machine's cost "
                    "grows with the square of its grips): " + ", ".join(
                        f"{name} at most {grips:,} of {metrics['dataset']['rows']:,}"
                        for name, grips in sampled.items()) + ".")
    _held_out_table(report, metrics.get("held_out"))
    _family_holdout_table(report, metrics.get("family_holdout"))
    _stage_figures(report, out, "classifiers")


def _winner(metric: str, name: str, value: dict[str, Any], objects: int | None,
            span: tuple[float, float] | None = None) -> str:
    """The best model by ``metric``: bold when its interval can carry the claim, otherwise the
    highest mean and why it is not declared best."""
    problem = unjudgeable(value, objects, span)
    if problem is None:
        return f"best {metric}: **{name}** ({_fmt(value)})"
    return f"highest mean {metric}: {name} ({_fmt(value)}), not declared best: {problem}"


def _sentence(*clauses: str) -> str:
    """Clauses joined by semicolons into one sentence."""
    text = "; ".join(clauses)
    return text[:1].upper() + text[1:] + "."


def _held_out_table(report: Report, held_out: dict[str, Any] | None, rows: str = "model",
                    what: str = "") -> None:
    """Each model trained on the split's training objects, scored on its held-out objects."""
    if not held_out or not held_out.get("models"):
        return
    shown = ["roc_auc", "balanced_accuracy", "brier", "top1_success"]
    frame = pd.DataFrame(held_out["models"]).T.reindex(columns=shown).rename_axis(rows)
    split = held_out["split"]
    few = (f" {len(split['test'])} held-out objects are too few to read anything into."
           if len(split["test"]) < FEW_OBJECTS else "")
    frame = frame.astype(float).round(3)
    report.table(undefined_as_dash(frame),
                 caption=f"{what}Trained on the {len(split['train'])} training objects, scored on "
                 f"the {len(split['test'])} held-out objects the RL selector is scored on "
                 f"(test_fraction {split['test_fraction']:g}, seed {split['seed']}): one split, "
                 f"so no interval; the cross-validated table above is the estimate.{few}"
                 + _UNDEFINED_NOTE * bool(frame.isna().any().any()))


def _family_holdout_table(report: Report, holdout: dict[str, Any] | None) -> None:
    """Each model trained on all object families but one, scored on the family held out."""
    families = (holdout or {}).get("families") or {}
    scored = {name: entry for name, entry in families.items() if entry.get("models")}
    if not scored:
        return
    shown = {"roc_auc": "ROC-AUC", "top1_success": "top-1"}
    columns = {}
    for family, entry in scored.items():
        for metric, label in shown.items():
            columns[f"{family} {label}"] = {model: values.get(metric)
                                            for model, values in entry["models"].items()}
    frame = pd.DataFrame(columns).rename_axis("model").astype(float).round(3)
    counts = ", ".join(f"{name} {entry['objects']} objects" for name, entry in scored.items())
    report.table(undefined_as_dash(frame), caption="Family holdout: trained on every other "
                 f"object family, scored on the family named in the column ({counts}); one split "
                 "per family, so no interval. Does what is learnt on drawn shapes transfer to "
                 "real silhouettes?" + _UNDEFINED_NOTE * bool(frame.isna().any().any()))


def _calibration_section(report: Report, out: Path, fig_dir: Path) -> None:
    from classifiers.report.calibration import RESULT_FILE, TRIALS_FILE, calibration_section

    result = _json(out / "calibration" / RESULT_FILE)
    if result is None:
        report.heading("Label validity (calibration)")
        report.text("Not run.")
        return
    trials_path = out / "calibration" / TRIALS_FILE
    trials = pd.read_parquet(trials_path) if trials_path.exists() else None
    calibration_section(report, result, trials, fig_dir, out)


def _crosscheck_section(report: Report, out: Path) -> None:
    """The dataset's cross-check in the other engine, when one is recorded with it
    (``grip_env.dataset.card.CROSSCHECK_FILE``); nothing otherwise."""
    from grip_env.dataset.card import crosscheck_tables, recorded_crosscheck

    recorded = _json(out / "data.json") or {}  # the study's record of its dataset
    found = recorded_crosscheck(Path(recorded.get("dataset", out / "dataset")))
    if found is None:
        return
    intro, agreement, cost = crosscheck_tables(found)
    report.heading("Agreement between engines")
    report.text(intro)
    report.table(agreement)
    if len(cost):
        report.table(cost, caption="Each engine's cost in the same run (CPU of the workers)")


@_stage_section("Planning on the rendered contour against the true one",
                "perception/perception.json")
def _perception_section(report: Report, out: Path, result: dict[str, Any],
                        table: pd.DataFrame) -> None:
    if result["planned_on"] != "render":
        report.text("The dataset's grips were planned on the true polygons "
                    "(`perception.source: polygon`): there is no rendered plan to compare.")
        return
    manifest = table.attrs.get("manifest", {})
    timing = result["timing_s"]
    report.text(
        "The dataset's grips were planned on the contour segmented from each object's top-down "
        "render and executed on the true body. Here the same objects are planned a second time "
        "on their true contours; per object, the best grip by Q_C of each plan is paired (the "
        "true plan's simulated on the true body with the dataset's trials), and the table gives "
        "the mean over objects on each plan and the mean paired difference, rendered − true, "
        f"with a 95 % bootstrap interval over the {result['objects']} objects"
        + (" (a seeded sample of the dataset's objects)." if result.get("sampled") else ".")
    )
    rows = {name: {"true plan": value["true"], "rendered plan": value["render"],
                   "difference": {"mean": value["mean"], "ci": value["ci"]}}
            for name, value in result["differences"].items()}
    shown = frame_of_intervals({n: {"difference": r["difference"]} for n, r in rows.items()},
                               ["difference"])
    shown.insert(0, "rendered plan", [f"{rows[n]['rendered plan']:.4g}" for n in shown.index])
    shown.insert(0, "true plan", [f"{rows[n]['true plan']:.4g}" for n in shown.index])
    report.table(shown.rename_axis("best grip's"), caption="Best grip per object planned on the "
                 "true and on the rendered contour: features, Q_C, success rate and robustness.")
    render_s = manifest.get("perception_seconds")
    report.text(
        "Cost: rendering and segmenting every object "
        + (f"{render_s:.1f} s" if render_s is not None else "(not recorded)")
        + f"; planning them again on the true contours {timing['plan_true_s']:.1f} s; "
        f"simulating the true plans' best grips {timing['simulate_true_best_s']:.1f} s."
    )


_REGRESSION_SHOWN = ["spearman", "spearman_object", "top1_robustness", "r2", "mae"]


def _regression_section(report: Report, out: Path) -> None:
    report.heading("Regressors of robustness (grouped cross-validation by object)")
    result = _json(out / "classifiers" / "regression.json")
    if result is None:
        report.text("Not run (the dataset has no graded outcome).")
        return
    models = result["models"]
    report.table(frame_of_intervals(models, _REGRESSION_SHOWN),
                 caption="Target robustness_mean (g). spearman: rank correlation over a test "
                 "fold's grips; spearman_object: mean within-object rank correlation; "
                 "top1_robustness: mean robustness of each test object's top-predicted grip. "
                 "Mean and 95% corrected interval over folds × repeats (same folds as the "
                 "classifiers).")
    paired = {f"{name} − {versus.removeprefix('vs_')}": block
              for name, blocks in result["paired_difference"].items()
              for versus, block in blocks.items()}  # fmt: skip
    if paired:
        report.table(frame_of_intervals(paired, ["spearman", "spearman_object",
                                                 "top1_robustness"]),
                     caption="Paired differences to the rank baselines (same folds and seeds).")
    learned = {k: v for k, v in models.items() if k not in ("rank_qc", "rank_qg", "random")}
    best = _best(learned, "spearman_object")
    versus = result["paired_difference"].get(best or "", {}).get("vs_rank_qc")
    if best and versus:
        objects = result.get("cv", {}).get("n_objects")
        report.text(_sentence(
            _winner("learned regressor within objects (Spearman)", best,
                    models[best]["spearman_object"], objects, SPANS["spearman_object"]),
            f"against ranking by Q_C {_fmt(versus['spearman_object'])} paired "
            f"({difference_verdict(versus['spearman_object'], objects, (-2.0, 2.0))})",
            f"pooled Spearman {_fmt(models[best]['spearman'])} against Q_C's "
            f"{_fmt(models['rank_qc']['spearman'])} and Q_G's "
            f"{_fmt(models['rank_qg']['spearman'])}"))


@_stage_section("Ablation: what the hand features add", "ablation/ablation.json")
def _ablation_section(report: Report, out: Path, ablation: dict[str, Any]) -> None:
    model, reference = ablation["model"], ablation["reference"]
    sets = ablation["feature_sets"]
    scores = {name: block["models"][model] for name, block in sets.items()}
    differences = {
        name: block["paired_difference"][model]
        for name, block in sets.items() if name != reference
    }
    shown = ["roc_auc", "balanced_accuracy", "brier", "top1_success"]
    report.table(frame_of_intervals(scores, shown),
                 caption=f"Model {model} on each feature set (grouped CV, mean and 95% interval).")
    report.table(frame_of_intervals(differences, shown),
                 caption=f"Paired difference against {reference} (same folds and seeds).")
    hand = differences.get("without_hand", {}).get("roc_auc")
    if hand is not None:
        verdict = difference_verdict(hand, ablation.get("cv", {}).get("n_objects"), (-1.0, 1.0))
        report.text(
            f"Removing the six hand features (C1–C6) changes ROC-AUC by {_fmt(hand)} "
            f"against all twelve; {verdict}."
        )
    constant = _constant_scores(scores, "roc_auc")
    if constant is not None:
        chance = " (chance: it learnt nothing on this dataset)" if constant == 0.5 else ""
        report.text(f"Model {model} scores ROC-AUC {constant:.3f} on every feature set and fold, "
                    f"with no spread{chance}, so the differences above say nothing about the "
                    "features.")
    _held_out_table(report, ablation.get("held_out"), "feature set", f"Model {model}. ")
    _regression_ablation(report, ablation.get("regression"))
    importance = ablation.get("permutation_importance", {})
    if importance:
        report.table(frame_of_intervals({k: {"drop in ROC-AUC": v} for k, v in importance.items()},
                                        ["drop in ROC-AUC"]),
                     caption="Permutation importance of each feature on held-out objects.")
    _stage_figures(report, out, "ablation")


def _regression_ablation(report: Report, regression: dict[str, Any] | None) -> None:
    if not regression:
        return
    model, reference = regression["model"], regression["reference"]
    sets = regression["feature_sets"]
    shown = ["spearman", "spearman_object", "top1_robustness"]
    report.table(frame_of_intervals({n: b["models"][model] for n, b in sets.items()}, shown),
                 caption=f"Regression task: {model} of robustness_mean on each feature set.")
    differences = {n: b["paired_difference"][model] for n, b in sets.items() if n != reference}
    report.table(frame_of_intervals(differences, shown),
                 caption=f"Regression task: paired difference against {reference}.")
    hand = differences.get("without_hand", {}).get("spearman_object")
    if hand is not None and hand["mean"] is not None:
        verdict = difference_verdict(hand, regression.get("cv", {}).get("n_objects"),
                                     (-2.0, 2.0))
        report.text(
            f"Regression task: removing the hand features changes the within-object Spearman "
            f"by {_fmt(hand)}; {verdict}."
        )


@_stage_section("RL selector on held-out objects", "selector/selector.json")
def _selector_section(report: Report, out: Path, selector: dict[str, Any]) -> None:
    policies = selector["policies"]
    metrics = sorted({m for v in policies.values() for m in v if isinstance(v.get(m), dict)})
    report.table(frame_of_intervals(policies, metrics),
                 caption="First-pick success rate on the held-out objects, mean and 95% interval.")
    scoring = selector.get("attempts") or {"note": "attempts taken as independent, 1 - prod(1 - "
                                                   "p): the run predates shared-draw scoring"}
    report.text(f"Success within {selector.get('max_attempts')} attempts and expected attempts: "
                f"{scoring['note']}.")
    _stage_figures(report, out, "selector")


@_stage_section("Leaderboard: the grip each method picks", "benchmark/leaderboard.json")
def _benchmark_section(report: Report, out: Path, board: dict[str, Any]) -> None:
    """The leaderboard: every method's pick on the held-out objects, against best-Q_C."""
    if not board.get("methods"):
        report.text(f"No leaderboard: {board.get('skipped', 'no method was scored')}.")
        return
    main, attempts = leaderboard_frames(board)
    report.text(
        "Each method picks one grip per held-out object (its highest score; ties count as a "
        "uniformly random pick among them). Top-1 success and robustness are the recorded "
        "success rate and robustness of that pick, regret is the oracle's success rate minus the "
        "pick's, NDCG@5 grades the top five by success rate. The normalised score is (method - "
        "random) / (oracle - random) per object, random being the exact mean over the "
        "candidates. " + split_line(board)
    )
    few = leaderboard_caution(board)
    if few:
        main = main.assign(verdict="not judged")
    report.table(main.set_index("method"), caption="Leaderboard, sorted by the interquartile "
                 "mean of the normalised score; intervals: " + board["interval"] + ".")
    report.text(few or "**" + verdict_sentence(board) + "**")
    report.table(attempts.set_index("method"), caption="Success within k attempts "
                 "(GripSelect-v0 with max_attempts = k; GripAccept-v0 executing those k). "
                 + attempts_caption(board))
    for line in retry_lines(board, heading=False):
        if line:
            report.text(line)
    _stage_figures(report, out, "benchmark")


def _provenance_section(report: Report, out: Path, config: Config) -> None:
    report.heading("Parameters and versions")
    params = pd.DataFrame({"value": config.grasp.model_dump()}).rename_axis("parameter")
    report.table(params, caption="Grasping parameters (GraspParams).", float_format="{:g}")
    versions = {"python": platform.python_version(), "machine": platform.platform(),
                "commit": source_commit()}  # fmt: skip
    for name in ("grip-env", *_PACKAGES):
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not installed"
    report.table(pd.DataFrame({"version": versions}).rename_axis("package"))
    _stage_table(report, out)
    timings = _json(out / "timings.json") or {}
    if timings:
        report.table(pd.DataFrame({"seconds": timings}).rename_axis("stage"),
                     caption="Wall time of the stages computed in the latest run.")
    report.text("Configuration (`--config` YAML; every section):")
    report.code(yaml.safe_dump(config.model_dump(mode="json"), sort_keys=False), "yaml")


def _stage_table(report: Report, out: Path) -> None:
    """Each stage's record: the key of what it read, the grip-env version, when it was written."""
    rows = {}
    for folder in ("classifiers", "ablation", "selector", "calibration"):
        record = _json(out / folder / STAGE_RECORD)
        if record:
            rows[folder] = {"key": str(record.get("key", ""))[:12],
                            "grip-env": record.get("package_version", "?"),
                            "dataset": str(record.get("dataset_sha256", ""))[:12],
                            "written": record.get("written", "?"),
                            "inputs": ", ".join(record.get("inputs", {}))}  # fmt: skip
    if rows:
        report.table(pd.DataFrame(rows).T.rename_axis("stage"),
                     caption="Stage provenance (stage.json): a rerun recomputes a stage only "
                     "when the hash of its inputs, the dataset and the grip-env version changes.")


# ---------------------------------------------------------------------------------- helpers
def source_commit() -> str:
    """The source checkout's commit (``+dirty`` with local changes), or "unknown"."""
    root = Path(__file__).resolve().parents[2]
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True, timeout=10, check=True)
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "-uno"],
                               capture_output=True, text=True, timeout=10, check=True)
    except (OSError, subprocess.SubprocessError):
        return "unknown (not a git checkout)"
    return head.stdout.strip() + ("+dirty" if dirty.stdout.strip() else "")  # fmt: skip


def _study_objects(config: Config) -> list[PlanarObject]:
    from grip_env.mesh_sets import named_set

    objects = named_set(config.objects.set, config.dataset.seed, config.objects).objects
    if config.objects.procedural_count:
        objects += procedural_objects(
            config.objects.procedural_count, config.dataset.seed, config.objects.procedural_size_mm
        )
    return objects


def _constant_scores(scores: dict[str, dict[str, Any]], metric: str) -> float | None:
    """The one value every row scores on ``metric`` with a zero-width interval, or None."""
    blocks = [block.get(metric) or {} for block in scores.values()]
    values = {(b.get("mean"), *(b.get("ci") or [None, None])) for b in blocks}
    if len(values) != 1:
        return None
    mean, low, high = next(iter(values))
    return mean if mean is not None and mean == low == high else None


#: Every figure a stage draws, per stage folder, in the order shown, with its caption (a stage
#: that did not draw one, such as the regression ablation without a graded outcome, skips it).
STAGE_FIGURES: dict[str, tuple[tuple[str, str], ...]] = {
    "classifiers": (
        ("roc.png", "ROC curves of the pooled out-of-fold predictions of grouped cross-validation "
                    "(first repeat): every grip is scored by a model that never saw its object."),
        ("calibration.png", "Reliability of the predicted success probabilities (same "
                            "out-of-fold predictions), with the number of grips in each "
                            "probability bin below."),
    ),
    "ablation": (
        ("ablation.png", "Classification: ROC-AUC of each feature set (left) and its paired "
                         "difference to all twelve features (right), mean and 95% corrected "
                         "interval."),
        ("ablation_regression.png", "Regression: Spearman of predicted and simulated "
                                    "robustness for each feature set (left) and its paired "
                                    "difference (right)."),
    ),
    "benchmark": (
        ("performance_profile.png", "Performance profiles (rliable): fraction of held-out "
                                    "objects x runs whose normalised score exceeds tau."),
        ("attempts.png", "Success against the number of attempts allowed."),
    ),
    "selector": (
        ("learning_curve.png", "Selector episode reward while training, with the expected "
                               "reward of random, best-Q_C and oracle picks on the training "
                               "objects."),
        ("held_out_curve.png", "Held-out top-1 success of each selector seed (faint) and their "
                               "mean against training steps, the policy scored after every "
                               "rollout, with best-Q_C's and the classifiers' first picks on "
                               "the same objects."),
    ),
}


def _stage_figures(report: Report, out: Path, folder: str) -> None:
    for name, caption in STAGE_FIGURES[folder]:
        if (out / folder / name).exists():
            report.figure(f"{folder}/{name}", caption)


def _json(path: Path) -> dict[str, Any] | None:
    return json.loads(path.read_text()) if path.exists() else None


def _best(models: dict[str, dict[str, Any]], metric: str) -> str | None:
    scored = {k: v[metric]["mean"] for k, v in models.items() if metric in v}
    return max(scored, key=scored.get) if scored else None  # type: ignore[arg-type]


def _fmt(value: dict[str, Any]) -> str:
    return f"{value['mean']:.3f} [{value['ci'][0]:.3f}, {value['ci'][1]:.3f}]"


def _rel(path: Path, report_root: Path) -> str:
    return str(Path(path).relative_to(report_root))
