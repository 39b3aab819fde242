"""The label-validity section, shared by ``grip-env calibrate`` and the study report.

:func:`calibration_section` adds the checks of :func:`grip_env.calibration.calibrate` (and the
dataset decile checks) to a :class:`~classifiers.report.document.Report` with their figures;
:func:`write_calibration` writes the standalone ``calibration.md`` / ``.html``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from classifiers.report.document import Report
from classifiers.report.judge import FEW_OBJECTS
from grip_env.drawing import save_figure

#: What the within-object check asks, in one line.
WITHIN_GLOSS = ("within one object: do two sets of trials rank that object's grips alike (what a "
                "robot choosing among them needs)")
#: Grips below which the retest and ICC checks are too small to judge (the default run scores
#: 6 objects x 16 grips; the quick one 8 grips).
MIN_GRIPS = 20
RESULT_FILE = "calibration.json"
TRIALS_FILE = "calibration_trials.parquet"


def write_calibration(out: Path, result: dict[str, Any], trials: pd.DataFrame) -> Path:
    """Write ``calibration.json``, the trials, the figures and ``calibration.md``; returns it."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / RESULT_FILE).write_text(json.dumps(result, indent=2, default=_plain))
    trials.to_parquet(out / TRIALS_FILE, index=False)
    report = Report("grip-env calibration: do the labels measure the grip?")
    calibration_section(report, result, trials, out / "figures", out, level=2)
    md, _ = report.write(out, stem="calibration")
    return md


def calibration_section(report: Report, result: dict[str, Any], trials: pd.DataFrame | None,
                        fig_dir: Path, root: Path, level: int = 2) -> None:
    """The checks as a pass/fail table, then one sub-section per check with its figure."""
    settings = result.get("settings")
    checks = {name: {**check, **assess(check, settings)}
              for name, check in result["checks"].items()}
    report.heading("Label validity (calibration)", level)
    report.text(
        f"Measured, never tuned: reference level {result['reference_level_g']:g} g, design "
        f"friction mu = {result['mu']:g}, {result['trials']} simulated calibration trials in "
        f"{_engine(result.get('config'))}{_conditions(result.get('config'))}. Each check "
        "states its target, the sample it was measured on and whether the measured figure meets "
        "it."
    )
    if result.get("recorded_with"):
        report.text(f"Recorded with the dataset `{result['recorded_with']}` (label model "
                    f"`{result.get('label_model')}`): measured once on its recipe, not by this "
                    "run, whose replication stage shows that this code still makes its labels.")
    report.table(summary_table(checks, settings), caption="Checks against their targets.")
    small = {name: check["too_small"] for name, check in checks.items() if check["too_small"]}
    if small:
        report.text("Too small to judge: " + "; ".join(f"{n}, {why}" for n, why in small.items())
                    + ". Their figures are shown as measured; a pass or a FAIL on such a sample "
                    "says nothing about the labels.")
    if "within_object" in checks:
        report.text(f"within_object: {WITHIN_GLOSS}.")
    sub = level + 1
    if "design_hold" in checks:
        _design(report, checks["design_hold"], result["reference_level_g"], fig_dir, root, sub)
    if "cone" in checks:
        _cone(report, checks["cone"], fig_dir, root, sub)
    if "retest" in checks:
        _retest(report, checks, trials, result, fig_dir, root, sub)
    if "within_object" in checks:
        _within_object(report, checks["within_object"], fig_dir, root, sub)
    deciles = [checks[k] for k in ("decile_Q_C", "decile_Q_G") if k in checks]
    if deciles:
        _deciles(report, deciles, fig_dir, root, sub)
    else:
        report.text("Decile checks (Q_C and Q_G decile against mean robustness): not run, no "
                    "dataset with the graded outcome was given (`grip-env calibrate --data DIR`, "
                    "or the study's calibration stage).")


def summary_table(checks: dict[str, dict[str, Any]],
                  settings: dict[str, Any] | None = None) -> pd.DataFrame:
    """One row per check: measured figure, interval, target, the sample it was measured on,
    verdict (see :func:`assess`; ``settings``: the run's ``CalibrationSettings`` as a dict)."""
    rows = {}
    for name, check in checks.items():
        measured = check["measured"]
        judged = {**check, **assess(check, settings)}
        rows[name] = {
            "measured": _number(measured) if not isinstance(measured, dict)
            else ", ".join(f"{k} {_number(v)}" for k, v in measured.items()),
            "95% interval": _ci(check.get("ci")),
            "target": check["target"],
            "sample": judged["sample"],
            "verdict": _judged(judged)
            + (" (ill-posed)" if check.get("well_posed") is False else ""),
        }
    return pd.DataFrame(rows).T.rename_axis("check")


def assess(check: dict[str, Any], settings: dict[str, Any] | None = None) -> dict[str, Any]:
    """``{"sample": what the check was measured on, "too_small": why that cannot carry a
    verdict, or None}``.

    Too small: the check rests on fewer objects, or grips, than a verdict needs
    (:data:`~classifiers.report.judge.FEW_OBJECTS` objects for the cone and decile checks, whose
    intervals resample objects; :data:`MIN_GRIPS` grips for the retest and ICC; the
    within-object check's own ``WITHIN_SCORED``), or its interval has zero width. The design
    check has no sample to grow: three boxes, without pose error, at fixed friction.
    """
    from grip_env.calibration import WITHIN_SCORED

    settings = settings or {}
    name, objects, grips = check.get("name", ""), check.get("objects"), check.get("grips")
    per_object = check.get("per_object") or []
    sample = {
        "design_hold": f"{len(per_object)} boxes × {settings.get('design_trials', '?')} trial(s)",
        "cone": f"{len(per_object)} object(s) × {settings.get('cone_trials', '?')} trial(s) a "
                "grip",
        "retest": f"{grips} grips on {objects} object(s), 2 × {check.get('trials_per_set')} "
                  "trials",
        "icc": f"{grips} grips × {check.get('trials')} trials",
        "within_object": f"{objects} object(s) scored ({check.get('skipped')} skipped), "
                         f"{grips} grips",
    }.get(name, f"{objects} objects, {grips} grips")
    floor = {"cone": ("object(s)", len(per_object), FEW_OBJECTS),
             "retest": ("grips", grips, MIN_GRIPS), "icc": ("grips", grips, MIN_GRIPS),
             "within_object": ("object(s) scored", objects, WITHIN_SCORED)}.get(
        name, ("objects", objects, FEW_OBJECTS) if name.startswith("decile_") else None)
    why = None
    if floor and floor[1] is not None and floor[1] < floor[2]:
        why = f"{floor[1]} {floor[0]} (a verdict needs {floor[2]})"
    ci = check.get("ci")
    if why is None and ci and ci[0] is not None and ci[0] == ci[1]:
        why = "an interval of zero width"
    return {"sample": sample, "too_small": why}


# ------------------------------------------------------------------------------- sub-sections
def _design(report: Report, check: dict[str, Any], reference: float, fig_dir: Path, root: Path,
            level: int) -> None:
    report.heading("Best grip of three boxes at the design friction", level)
    rows = pd.DataFrame(check.get("per_object", []))
    if rows.empty:
        report.text("No box had a feasible grip.")
        return
    shown = rows.set_index("object_id")
    if "gear_ceiling_g" in shown:
        shown["gear_ceiling_g"] = shown["gear_ceiling_g"].astype(object).where(
            shown["gear_ceiling_g"].notna(), "none")
    report.table(shown, caption="No pose error, friction = mu, nominal "
                 "mass; robustness is the highest level held (g), held the share of trials "
                 "holding the reference level; friction_ceiling_g = sqrt((mu x 3 x finger force "
                 "/ (m g))² - 1), the most three pads at the commanded squeeze hold by friction "
                 "against the weight and an in-plane push along their faces; gear_ceiling_g, "
                 "the same with each pad at the motor plus the worm gear's stop (none: the "
                 "stop holds any load); "
                 "mu_for_reference, the friction at which the squeeze's ceiling reaches the "
                 "reference.")
    report.text(design_verdict_text(check, reference))
    _figure(report, save_figure(design_figure(rows, reference), fig_dir / "calibration_design.png"),
            root, "Robustness of each box's best grip by Q_C against the reference level.")


def design_figure(rows: pd.DataFrame, reference: float) -> Figure:
    """Each box's robustness (bars) against the reference level (dashed) and the squeeze's
    friction ceiling; the legend sits beside the axes, clear of the reference line."""
    fig = Figure(figsize=(7.5, 3.4))
    ax = fig.subplots()
    ax.bar(rows["object_id"], rows["robustness"], color="tab:blue")
    ax.axhline(reference, color="tab:red", linestyle="--", label=f"reference {reference:g} g")
    if "friction_ceiling_g" in rows:
        ax.scatter(rows["object_id"], rows["friction_ceiling_g"], marker="_", s=900,
                   color="black", label="squeeze's friction\nceiling at mu", zorder=3)  # fmt: skip
    ax.set_ylabel("robustness (g)")
    ax.set_title("Best-Q_C grip at friction mu, no pose error")
    _legend_beside(ax, markerscale=0.3)
    fig.tight_layout()
    return fig


def _legend_beside(ax: Any, markerscale: float = 1.0) -> None:
    """The legend to the right of the axes, where it hides no line or bar."""
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0,
              markerscale=markerscale)


def design_verdict_text(check: dict[str, Any], reference: float) -> str:
    """The design check in words: the measured levels against the friction ceilings, and what
    the verdict means physically (no faithful grip can pass; or passing relies on the gear)."""
    rows = pd.DataFrame(check.get("per_object", []))
    held = ", ".join(f"{r.object_id} {r.robustness:.1f} g" for r in rows.itertuples())
    text = (f"Measured at the design friction: {held}, against the {reference:g} g reference "
            f"({_judged(check)}).")
    if check.get("squeeze_text"):
        text += f" At the commanded squeeze, {check['squeeze_text']}."
    if check.get("well_posed") is False:
        return text + (f" The check is {check['reason']}. No grip of a faithful hand can meet "
                       "it, so its failure measures the reference level, not the labels; the "
                       "physics is not tuned to pass.")
    if check.get("beyond_squeeze"):
        text += (" The reference is above that: a grip holds it only with normal forces above "
                 "the commanded squeeze, which the non-backdrivable worm gear allows (it keeps "
                 "the squeeze the fingers reached and resists being pushed back, "
                 f"{_gear_bound(rows)}). The check is well-posed for this hand, and it tests the "
                 "gear's hold as well as the squeeze.")
    return text


def _gear_bound(rows: pd.DataFrame) -> str:
    """How far the worm gear's stop resists, in words: up to the boxes' gear ceilings, or any
    load (no ceiling recorded: the stop is unbounded)."""
    gear = rows["gear_ceiling_g"].dropna() if "gear_ceiling_g" in rows else pd.Series(dtype=float)
    if not len(gear):
        return "its stop holds any load"
    return f"up to its stop (at most {gear.min():.0f}–{gear.max():.0f} g)"


def _cone(report: Report, check: dict[str, Any], fig_dir: Path, root: Path, level: int) -> None:
    report.heading("A finger force outside the friction cone (C1's k = 3)", level)
    rows = pd.DataFrame(check.get("per_object", []))
    if rows.empty:
        report.text("No object had both a grip inside and one outside the friction cone.")
        return
    report.text(
        f"Per object, the best grip by Q_C whose finger force leaves the cone against the best "
        f"grip inside it, at friction mu: mean robustness difference "
        f"{_number(check['measured'])} g, "
        f"95% t-interval over {len(rows)} objects {_ci(check['ci'])}, half-width "
        f"{_number(check.get('half_width'))} g ({_judged(check)}). The spread of the "
        "difference is between objects, so the interval narrows as 1/sqrt(objects) and hardly "
        "with trials per grip; `grip-env calibrate --cone-objects N --cone-trials K` resizes it."
    )
    report.table(rows.set_index("object_id"), caption="Mean robustness (g) and share of trials "
                 "holding the reference level.")
    fig = Figure(figsize=(5.5, 3.6))
    ax = fig.subplots()
    for _, row in rows.iterrows():
        ax.plot([0, 1], [row["best_g"], row["outside_g"]], marker="o", color="tab:gray")
        ax.annotate(str(row["object_id"]), (1.02, row["outside_g"]), fontsize=7)
    ax.set_xticks([0, 1], ["best inside the cone", "best outside the cone"])
    ax.set_xlim(-0.2, 1.5)
    ax.set_ylabel("mean robustness (g)")
    ax.set_title("Paired by object, friction = mu")
    fig.tight_layout()
    _figure(report, save_figure(fig, fig_dir / "calibration_cone.png"), root,
            "Each line joins an object's best grip to its best outside-cone grip.")


def _retest(report: Report, checks: dict[str, Any], trials: pd.DataFrame | None,
            result: dict[str, Any], fig_dir: Path, root: Path, level: int) -> None:
    from grip_env.calibration import retest_table

    retest, icc = checks["retest"], checks.get("icc", {})
    report.heading("Test-retest and intra-class correlation", level)
    report.text(
        f"Per-grip mean robustness from two disjoint sets of {retest.get('trials_per_set')} "
        f"trial seeds over {retest.get('grips')} grips (best and worst by Q_C on "
        f"{retest.get('objects')} default objects): Spearman {_number(retest['measured'])} "
        f"{_ci(retest['ci'])} ({_judged(retest)}); within one object, over these "
        f"grips only, the mean Spearman is {_number(retest.get('within_object_mean'))} (the "
        "within-object check uses all kept grips at the dataset's trials). ICC(1) of per-trial "
        f"robustness with the grip as class: {_number(icc.get('measured'))} "
        f"{_ci(icc.get('ci'))} ({_judged(icc)}). Within a grip, the trial's "
        f"friction draw against its robustness residual has Spearman "
        f"{_number(icc.get('friction_residual_spearman'))}: how far the draw orders one grip's "
        "trials (0: not at all; a grip that holds by friction holds in proportion to it)."
    )
    if trials is None or trials.empty:
        return
    table = retest_table(trials, result["settings"]["trials_per_set"])
    if not {"A", "B"} <= set(table.columns):
        return
    fig = Figure(figsize=(9.5, 4))
    left, right = fig.subplots(1, 2)
    for end, colour in (("best", "tab:green"), ("worst", "tab:red")):
        mine = table[table["end"] == end]
        left.scatter(mine["A"], mine["B"], s=14, alpha=0.7, color=colour, label=f"{end} by Q_C")
    top = float(np.nanmax(table[["A", "B"]].to_numpy())) if len(table) else 1.0
    left.plot([0, top], [0, top], color="grey", linestyle=":", linewidth=1)
    left.set(xlabel="mean robustness, seed set A (g)", ylabel="seed set B (g)",
             title="Test-retest per grip")  # fmt: skip
    left.legend(fontsize=8)
    rows = trials[trials["part"] == "retest"]
    stats = rows.groupby("grip")["robustness"].agg(["mean", "std"]).sort_values("mean")
    right.errorbar(np.arange(len(stats)), stats["mean"], yerr=stats["std"], fmt="o",
                   markersize=3, elinewidth=0.8, color="tab:blue")  # fmt: skip
    right.set(xlabel="grip (sorted by mean)", ylabel="robustness (g), mean ± sd over trials",
              title="Between-grip against within-grip spread")  # fmt: skip
    fig.tight_layout()
    _figure(report, save_figure(fig, fig_dir / "calibration_retest.png"), root,
            "Left: grip means on two disjoint seed sets. Right: every grip's trial spread.")


def _within_object(report: Report, check: dict[str, Any], fig_dir: Path, root: Path,
                   level: int) -> None:
    from grip_env.calibration import RETEST_TARGET

    report.heading("Within-object test-retest at the dataset's trials", level)
    n = int(check["trials_per_set"])
    report.text(
        f"Per object, Spearman of its kept grips' mean robustness over trials 0..{n - 1} (set "
        f"A) against {n}..{2 * n - 1} (set B), n = dataset.trials: mean "
        f"{_number(check['measured'])} over {check['objects']} objects, 95% bootstrap interval "
        f"over objects {_ci(check['ci'])}; target >= {RETEST_TARGET}: "
        f"{_judged(check)}. {check['grips']} grips on "
        f"{check['objects'] + check['skipped']} objects were run; {check['skipped']} object(s) "
        "skipped, where a set gives all the object's grips one robustness (it ranks nothing)."
    )
    rows = pd.DataFrame(check.get("per_object", []))
    if rows.empty:
        return
    shown = rows.assign(spearman=rows["spearman"].astype(object).where(rows["spearman"].notna(),
                                                                         "skipped"))
    report.table(shown.set_index("object_id"), caption="Per object: kept grips run and the "
                 "Spearman of their set-A against set-B means (skipped: a set ranks nothing).")
    scored = rows.dropna(subset=["spearman"]).sort_values("spearman")
    fig = Figure(figsize=(7.5, 3.4))
    ax = fig.subplots()
    ax.bar(scored["object_id"].astype(str), scored["spearman"], color="tab:blue")
    if check["measured"] is not None:
        ax.axhline(check["measured"], color="black", label=f"mean {check['measured']:.2f}")
    ax.axhline(RETEST_TARGET, color="tab:red", linestyle="--", label="target")
    ax.set(ylabel="Spearman, set A vs set B", ylim=(-1.05, 1.05),
           title="Within-object test-retest")  # fmt: skip
    ax.tick_params(axis="x", labelrotation=60, labelsize=7)
    _legend_beside(ax)
    fig.tight_layout()
    _figure(report, save_figure(fig, fig_dir / "calibration_within_object.png"), root,
            "Each object's Spearman between two disjoint sets of its grips' trials.")


def _deciles(report: Report, checks: list[dict[str, Any]], fig_dir: Path, root: Path,
             level: int) -> None:
    report.heading("Mean robustness by quality-index decile (the study's dataset)", level)
    fig = Figure(figsize=(5.2 * len(checks), 3.8))
    axes = np.atleast_1d(fig.subplots(1, len(checks)))
    for ax, check in zip(axes, checks, strict=True):
        column = check["name"].removeprefix("decile_")
        bins = pd.DataFrame(check["deciles"])
        errors = np.vstack([bins["robustness_mean"] - bins["ci_low"],
                            bins["ci_high"] - bins["robustness_mean"]]).clip(min=0)
        ax.bar(bins["bin"], bins["robustness_mean"], yerr=errors, capsize=3, color="tab:blue")
        for _, row in bins.iterrows():
            ax.annotate(f"n={int(row['grips'])}", (row["bin"], 0), ha="center", va="bottom",
                        fontsize=6, color="white")  # fmt: skip
        ax.set_xticks(bins["bin"])
        ax.set(xlabel=f"{column} decile (1 = best, lowest {column})",
               ylabel="mean robustness (g)",
               title=f"Spearman {_number(check['measured'])} {_ci(check['ci'])}")  # fmt: skip
        report.text(
            f"{column}: Spearman between decile and mean robustness {_number(check['measured'])}"
            f" {_ci(check['ci'])} (object-cluster bootstrap over {check['objects']} objects, "
            f"{check['grips']} grips), {check['target']}: {_judged(check)}; "
            f"over single grips the Spearman is {_number(check['pooled_grip_spearman'])}."
        )
    fig.tight_layout()
    _figure(report, save_figure(fig, fig_dir / "calibration_deciles.png"), root,
            "Mean robustness per decile with 95% object-bootstrap intervals and grip counts.")


# ------------------------------------------------------------------------------------ helpers
def _engine(config: dict[str, Any] | None) -> str:
    """The physics engine the trials ran in (a config from before engines: PyBullet)."""
    return {"pybullet": "PyBullet", "mujoco": "MuJoCo"}.get(
        ((config or {}).get("sim") or {}).get("engine", "pybullet"), "an unknown engine")


def _conditions(config: dict[str, Any] | None) -> str:
    if not config:
        return ""
    u, objects = config.get("uncertainty", {}), config.get("objects", {})
    parts = []
    if "density_kg_m3" in objects:
        parts.append(f"density {objects['density_kg_m3']:g} kg/m³")
    if "thickness_mm" in objects:
        parts.append(f"thickness {objects['thickness_mm']:g} mm")
    if "friction_range" in u:
        parts.append(f"friction drawn in [{u['friction_range'][0]:g}, {u['friction_range'][1]:g}]")
    if "position_std_mm" in u:
        parts.append(f"pose error {u['position_std_mm']:g} mm, {u.get('yaw_std_rad', 0):g} rad")
    return f" ({'; '.join(parts)})" if parts else ""


def _figure(report: Report, path: Path, root: Path, caption: str) -> None:
    report.figure(str(Path(path).relative_to(root)), caption)


def _number(value: Any) -> str:
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return "n/a"
    return f"{float(value):.3f}"


def _ci(ci: Any) -> str:
    if not ci or ci[0] is None:
        return "[n/a]"
    return f"[{float(ci[0]):.3f}, {float(ci[1]):.3f}]"


def _verdict(passed: bool | None) -> str:
    return {True: "pass", False: "FAIL", None: "-"}[passed]


def _judged(check: dict[str, Any]) -> str:
    """The check's verdict, or "too small to judge" with what was measured (see :func:`assess`;
    a check not assessed is judged as measured)."""
    verdict = _verdict(check.get("passed"))
    if not check.get("too_small"):
        return verdict
    return "too small to judge" + (f"; measured {verdict}" if verdict != "-" else "")


def _plain(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON-able: {type(value).__name__}")
