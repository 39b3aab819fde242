"""Label-validity calibration: its statistics, its checks, and ``grip-env calibrate --quick``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats
from typer.testing import CliRunner

from classifiers.evaluation.synthetic import synthetic_grips
from grip_env.calibration import (
    BOXES_MM,
    WITHIN_SCORED,
    CalibrationSettings,
    box_objects,
    choose_objects,
    cone_check,
    decile_check,
    design_config,
    icc1,
    icc_check,
    outside_cone,
    retest_check,
    spearman_bootstrap,
    spread_subset,
    within_object_check,
)
from grip_env.cli import _register_commands, app
from grip_env.config import Config
from grip_env.objects import load_object_set


def test_icc1_matches_the_anova_definition_and_its_interval_brackets_it():
    rng = np.random.default_rng(0)
    grips, trials = 40, 6
    values = rng.normal(0, 2.0, size=(grips, 1)) + rng.normal(0, 1.0, size=(grips, trials))
    result = icc1(values)
    # from scipy's one-way ANOVA F over the same table
    f_value = stats.f_oneway(*values).statistic
    assert result["value"] == pytest.approx((f_value - 1) / (f_value + trials - 1))
    assert result["ci"][0] < result["value"] < result["ci"][1]
    # population ICC is 4 / (4 + 1) = 0.8: the 95% interval covers it about 95% of the time
    covered = []
    for seed in range(300):
        rng = np.random.default_rng(seed)
        draw = rng.normal(0, 2.0, size=(grips, 1)) + rng.normal(0, 1.0, size=(grips, trials))
        low, high = icc1(draw)["ci"]
        covered.append(low < 0.8 < high)
    assert 0.91 <= np.mean(covered) <= 0.99


def test_icc1_is_near_zero_when_the_class_explains_nothing():
    values = np.random.default_rng(1).normal(size=(60, 8))
    result = icc1(values)
    assert abs(result["value"]) < 0.1 and result["ci"][0] < 0 < result["ci"][1]
    with pytest.raises(ValueError, match="1x8"):
        icc1(values[:1])


def test_spearman_bootstrap_interval_contains_the_estimate():
    rng = np.random.default_rng(2)
    a = rng.normal(size=100)
    result = spearman_bootstrap(a, a + rng.normal(0, 0.5, size=100), resamples=300)
    assert result["ci"][0] < result["value"] < result["ci"][1] and result["value"] > 0.7
    assert spearman_bootstrap(a[:2], a[:2])["value"] is None


def test_outside_cone_flags_a_force_beyond_arctan_mu():
    row = {f"{k}{i}_{a}": 0.0 for k in "fn" for i in "123" for a in "xy"}
    for i in "123":
        row[f"n{i}_x"] = row[f"f{i}_x"] = 1.0
    inside = pd.DataFrame([row])
    tilted = dict(row, f2_x=np.cos(0.5), f2_y=np.sin(0.5))  # 0.5 rad > arctan(0.4) = 0.38
    frame = pd.concat([inside, pd.DataFrame([tilted])], ignore_index=True)
    assert outside_cone(frame, 0.4).tolist() == [False, True]
    assert outside_cone(frame, 0.6).tolist() == [False, False]  # arctan(0.6) = 0.54 > 0.5


def test_design_config_removes_pose_error_and_fixes_friction():
    config = design_config(Config())
    u = config.uncertainty
    assert u.position_std_mm == 0 and u.yaw_std_rad == 0 and u.mass_rel_std == 0
    assert u.friction_range == (config.grasp.mu, config.grasp.mu)


def test_objects_cover_the_boxes_and_enough_retest_grips():
    boxes = box_objects()
    assert [b.name for b in boxes] == [f"box_{w:.0f}x{h:.0f}" for w, h in BOXES_MM]
    assert boxes[0].area == pytest.approx(90 * 55)
    plan = choose_objects(Config(), CalibrationSettings())
    assert sum("retest" in parts for parts in plan.values()) == 6  # 6 x 16 = 96 grips >= 90
    assert sum("cone" in parts for parts in plan.values()) == CalibrationSettings().cone_objects
    within = [name for name, parts in plan.items() if "within_object" in parts]
    default = [obj.name for obj in load_object_set("default")]
    assert len(within) == 14 and within == [n for n in default if n in within][:14]


def _trials(part: str, grips: dict[str, float], n: int, rng: np.random.Generator,
            obj: str = "o") -> pd.DataFrame:
    rows = [{"object_id": obj, "grip": g, "part": part, "end": end, "Q_C": 1.0, "Q_G": 1.0,
             "trial": k, "robustness": max(level + rng.normal(0, 0.3), 0.0),
             "success": level >= 4.0, "friction": 0.4, "mass_kg": 0.2}
            for g, (end, level) in grips.items() for k in range(n)]  # fmt: skip
    return pd.DataFrame(rows)


def test_cone_and_retest_checks_pass_on_separated_grips_and_fail_on_noise():
    rng = np.random.default_rng(3)
    cone = pd.concat([_trials("cone", {f"{o}/a": ("best", 6.0), f"{o}/b": ("outside", 2.0)}, 4,
                              rng, obj=o) for o in "uvw"])  # fmt: skip
    assert cone_check(cone)["passed"] and cone_check(cone)["measured"] == pytest.approx(-4, 0.1)
    differences = cone[cone["end"] == "outside"].groupby("object_id")["robustness"].mean() - \
        cone[cone["end"] == "best"].groupby("object_id")["robustness"].mean()
    expected = stats.t.ppf(0.975, 2) * differences.std(ddof=1) / np.sqrt(3)
    assert cone_check(cone)["half_width"] == pytest.approx(expected)
    levels = {f"g{i}": ("best", float(i)) for i in range(30)}
    settings = CalibrationSettings(trials_per_set=4, bootstrap=200)
    assert retest_check(_trials("retest", levels, 8, rng), settings)["passed"]
    flat = {f"g{i}": ("best", 3.0) for i in range(30)}
    assert not retest_check(_trials("retest", flat, 8, rng), settings)["passed"]


def test_decile_check_sees_a_monotone_trend_and_its_absence():
    table = synthetic_grips(n_objects=30, seed=4)
    result = decile_check(table, "Q_C", resamples=200)
    assert result["measured"] < -0.8 and result["passed"]
    assert len(result["deciles"]) == 10 and sum(d["grips"] for d in result["deciles"]) == len(table)
    shuffled = table.assign(robustness_mean=np.random.default_rng(5).permutation(
        table["robustness_mean"].to_numpy()))  # fmt: skip
    assert abs(decile_check(shuffled, "Q_C", resamples=200)["measured"]) < 0.8
    assert decile_check(table, "Q_G", resamples=200)["passed"] is None
    with pytest.raises(ValueError, match="robustness_mean"):
        decile_check(table.drop(columns="robustness_mean"), "Q_C")


def test_icc_check_reports_how_much_the_friction_draw_decides():
    rng = np.random.default_rng(7)
    rows = []
    for g in range(20):
        for k in range(8):
            friction = rng.uniform(0.4, 0.9)
            rows.append({"object_id": "o", "grip": f"g{g}", "part": "retest", "end": "best",
                         "Q_C": 1.0, "Q_G": 1.0, "trial": k, "success": True, "mass_kg": 0.2,
                         "friction": friction, "robustness": g + 40 * friction})  # fmt: skip
    frame = pd.DataFrame(rows)
    check = icc_check(frame)
    assert check["friction_residual_spearman"] > 0.9  # the residual is the friction's doing
    assert check["grips"] == 20 and check["trials"] == 8
    unrelated = frame.assign(robustness=frame["grip"].str[1:].astype(float)
                             + rng.normal(0, 1, len(frame)))  # fmt: skip
    assert abs(icc_check(unrelated)["friction_residual_spearman"]) < 0.2


def test_settings_reject_bad_sizes():
    with pytest.raises(ValueError, match="grips_per_end"):
        CalibrationSettings(grips_per_end=0)
    with pytest.raises(ValueError, match="within_grips"):
        CalibrationSettings(within_grips=2)
    assert CalibrationSettings(within_objects=0).within_objects == 0


def _within_trials(sets: dict[str, tuple[list[float], list[float]]], n: int = 2) -> pd.DataFrame:
    """Within-object trials: per object, each grip's robustness on set A and on set B."""
    rows = [{"object_id": obj, "grip": f"{obj}/{g}", "part": "within_object", "end": "kept",
             "Q_C": float(g), "Q_G": 1.0, "trial": k + n * side, "robustness": level,
             "success": True, "friction": 0.4, "mass_kg": 0.2}
            for obj, levels in sets.items() for side, values in enumerate(levels)
            for g, level in enumerate(values) for k in range(n)]  # fmt: skip
    return pd.DataFrame(rows)


def test_within_object_check_is_one_for_the_same_ranking_and_minus_one_reversed():
    up = [1.0, 3.0, 2.0, 5.0, 4.0]
    names = [f"o{i}" for i in range(WITHIN_SCORED)]
    same = _within_trials({o: (up, [2 * v for v in up]) for o in names})
    check = within_object_check(same, 2, resamples=200)
    assert check["measured"] == pytest.approx(1.0) and check["ci"] == pytest.approx([1.0, 1.0])
    assert check["passed"] and check["objects"] == WITHIN_SCORED and check["grips"] == 60
    assert check["trials_per_set"] == 2 and check["skipped"] == 0
    assert [r["spearman"] for r in check["per_object"]] == pytest.approx([1.0] * WITHIN_SCORED)
    reversed_ = _within_trials({o: (up, [-v for v in up]) for o in names})
    assert within_object_check(reversed_, 2, resamples=200)["measured"] == pytest.approx(-1.0)
    assert within_object_check(reversed_, 2, resamples=200)["passed"] is False
    few = _within_trials({o: (up, up) for o in names[:3]})
    assert within_object_check(few, 2, resamples=200)["passed"] is None  # too few for a verdict


def test_within_object_interval_resamples_objects():
    up = [1.0, 3.0, 2.0, 5.0, 4.0]
    mixed = _within_trials({"a": (up, up), "b": (up, [-v for v in up])})
    check = within_object_check(mixed, 2, resamples=500)
    # two objects at +1 and -1: resampled means are -1, 0 or +1, whatever the grips
    assert check["measured"] == pytest.approx(0.0) and check["ci"] == pytest.approx([-1.0, 1.0])
    many = _within_trials({f"o{i}": (up, up if i % 4 else up[::-1]) for i in range(40)})
    low, high = within_object_check(many, 2, resamples=500)["ci"]
    assert low < within_object_check(many, 2)["measured"] < high < 1.0


def test_within_object_skips_and_counts_objects_with_a_constant_side():
    up = [1.0, 3.0, 2.0, 5.0]
    table = _within_trials({"a": (up, up), "flat": (up, [0.0] * 4), "b": (up, up)})
    check = within_object_check(table, 2, resamples=100)
    assert check["skipped"] == 1 and check["objects"] == 2 and check["measured"] == 1.0
    spearman = {r["object_id"]: r["spearman"] for r in check["per_object"]}
    assert spearman["flat"] is None and check["grips"] == 12
    assert within_object_check(table.iloc[:0], 2)["measured"] is None
    only_flat = within_object_check(_within_trials({"flat": (up, [0.0] * 4)}), 2)
    assert only_flat["passed"] is None and only_flat["skipped"] == 1


def test_spread_subset_keeps_both_ends_of_the_ranking():
    grips = pd.DataFrame({"Q_C": np.arange(30.0)})
    assert spread_subset(grips, 4)["Q_C"].tolist() == [0.0, 10.0, 19.0, 29.0]
    assert len(spread_subset(grips, 0)) == 30 and len(spread_subset(grips.head(3), 4)) == 3


def test_calibrate_quick_writes_a_report_from_real_trials(tmp_path: Path):
    """A tiny real run: planning, PyBullet trials through the public sim API, the report."""
    _register_commands()
    out = tmp_path / "cal"
    config = tmp_path / "one_trial.yaml"  # dataset.trials = 1: within-object sets of one trial
    config.write_text("dataset:\n  trials: 1\n")
    result = CliRunner().invoke(app, ["calibrate", "--quick", "--out", str(out), "--workers", "1",
                                      "--cone-objects", "2", "--cone-trials", "1",
                                      "--config", str(config)])
    assert result.exit_code == 0, result.output
    assert "design_hold" in result.output
    saved = json.loads((out / "calibration.json").read_text())
    assert set(saved["checks"]) == {"design_hold", "cone", "retest", "icc", "within_object"}
    trials = pd.read_parquet(out / "calibration_trials.parquet")
    assert set(trials["part"]) == {"design", "cone", "retest", "within_object"}
    within = saved["checks"]["within_object"]
    assert np.isfinite(within["measured"]) and within["trials_per_set"] == 1
    assert within["objects"] + within["skipped"] == 3 and within["grips"] == 12
    kept = trials[trials["part"] == "within_object"]
    assert kept.groupby("grip")["trial"].nunique().eq(2).all()  # sets A and B of dataset.trials
    assert trials["robustness"].ge(0).all()
    cone = trials[trials["part"] == "cone"]
    assert cone["object_id"].nunique() == 2 and cone["trial"].eq(0).all()  # the flags' sizes
    assert saved["settings"]["cone_objects"] == 2 and saved["settings"]["cone_trials"] == 1
    retest = trials[trials["part"] == "retest"]
    assert retest.groupby("grip")["trial"].nunique().eq(4).all()  # two disjoint sets of 2
    text = (out / "calibration.md").read_text()
    assert "Label validity" in text and "figures/calibration_retest.png" in text
    assert "within_object: within one object: do two sets of trials rank" in text
    assert "figures/calibration_within_object.png" in text
    assert "Decile checks" in text and "not run" in text  # no --data given
    assert (out / "figures" / "calibration_design.png").is_file()
    for name in ("design_hold", "retest", "icc", "within_object"):
        assert name in text
    bad = CliRunner().invoke(app, ["calibrate", "--quick", "--workers", "0"])
    assert bad.exit_code == 2
    a_file = tmp_path / "taken"
    a_file.write_text("x")
    refused = CliRunner().invoke(app, ["calibrate", "--quick", "--out", str(a_file)])
    assert refused.exit_code == 2 and "existing file" in refused.output  # before any trial


def test_friction_ceiling_holds_the_weight_and_the_push_with_mu_times_the_pad_forces():
    from grip_env.calibration import box_objects, friction_ceiling_g, friction_for_level
    from grip_env.config import Config

    config = Config()
    box = next(b for b in box_objects() if b.name == "box_90x55")
    weight_n = 0.090 * 0.055 * 0.030 * 500.0 * 9.81  # 500 kg/m³, W = 1
    # friction must carry m g (down) and m a g (along the faces): (1 + a²) (m g)² <= (mu 45 N)²
    ceiling = friction_ceiling_g(box, config)
    assert (1 + ceiling**2) * weight_n**2 == pytest.approx((0.4 * 3 * 15.0) ** 2)
    assert 24.0 < ceiling < 25.0  # about 25 g: the 45 g reference is out of reach at mu = 0.4
    assert friction_for_level(box, config, ceiling) == pytest.approx(0.4)
    assert friction_for_level(box, config, 45.0) == pytest.approx(np.hypot(45, 1) * weight_n / 45)
    heavy = config.override(objects={"density_kg_m3": 20_000.0})  # 3 kg: 18 N cannot lift it
    assert friction_ceiling_g(box, heavy) == 0.0


def _design_trials(levels: dict[str, float], reference: float = 45.0) -> pd.DataFrame:
    return pd.DataFrame([{"object_id": name, "grip": f"{name}/g", "part": "design", "end": "best",
                          "Q_C": 1.0, "Q_G": 1.0, "trial": k, "robustness": level,
                          "success": level >= reference, "friction": 0.4, "mass_kg": 0.07}
                         for name, level in levels.items() for k in range(2)])  # fmt: skip


def test_gear_ceiling_adds_the_worm_gears_stop_to_the_squeeze():
    from grip_env.calibration import friction_ceiling_g, gear_ceiling_g

    box = box_objects()[0]
    config = Config()
    ratio = 0.4 * 3 * 15.0 * (1 + 5.0) / (0.090 * 0.055 * 0.030 * 500.0 * 9.81)
    assert gear_ceiling_g(box, config, 5.0) == pytest.approx(np.sqrt(ratio**2 - 1))
    assert gear_ceiling_g(box, config, 5.0) > 45.0 > friction_ceiling_g(box, config)


def test_a_stop_that_holds_any_load_has_no_gear_ceiling(monkeypatch):
    """An unbounded stop: the ceiling is infinite, the design check records none (strict JSON)
    and its verdict says the stop holds any load."""
    import json

    import grip_env.sim.hand as hand
    from classifiers.report.calibration import design_verdict_text
    from grip_env.calibration import design_check, gear_ceiling_g

    assert gear_ceiling_g(box_objects()[0], Config(), float("inf")) == float("inf")
    monkeypatch.setattr(hand, "HOLD_FACTOR", float("inf"))
    check = design_check(_design_trials({box.name: 38.0 for box in box_objects()}), 64.0)
    assert [row["gear_ceiling_g"] for row in check["per_object"]] == [None, None, None]
    json.dumps(check, allow_nan=False)
    assert check["well_posed"] is True
    assert "its stop holds any load" in design_verdict_text(check, 64.0)


def test_design_check_says_what_its_verdict_means_physically(monkeypatch):
    """With a stop of 5 times the motor (a bounded gear, whose ceiling can be below a
    reference)."""
    import grip_env.sim.hand as hand
    from classifiers.report.calibration import design_verdict_text, summary_table
    from grip_env.calibration import design_check

    monkeypatch.setattr(hand, "HOLD_FACTOR", 5.0)
    names = [b.name for b in box_objects()]
    # 45 g: above the squeeze's ceiling (about 25 g at mu = 0.4), below the gear's: well-posed
    check = design_check(_design_trials(dict.fromkeys(names, 45.25)), 45.0, Config())
    assert check["passed"] and check["well_posed"] and check["beyond_squeeze"]
    rows = {r["object_id"]: r for r in check["per_object"]}
    assert all(24 < r["friction_ceiling_g"] < 26 < 45 < r["gear_ceiling_g"]
               and 0.6 < r["mu_for_reference"] < 0.8 for r in rows.values())  # fmt: skip
    text = design_verdict_text(check, 45.0)
    assert "box_90x55 45.2 g" in text and "24.7–25.5 g" in text and "worm gear" in text
    assert summary_table({"design_hold": check}).loc["design_hold", "verdict"] == "pass"
    # a reference above even the gear's ceiling: no faithful grip can pass, and it says why
    beyond = design_check(_design_trials(dict.fromkeys(names, 128.0), 200.0), 200.0, Config())
    assert beyond["passed"] is False and beyond["well_posed"] is False
    assert "ill-posed at mu = 0.4" in beyond["reason"] and "below the 200 g" in beyond["reason"]
    assert "not tuned" in design_verdict_text(beyond, 200.0)
    assert summary_table({"design_hold": beyond}).loc["design_hold", "verdict"] == \
        "FAIL (ill-posed)"
    # a reference inside the squeeze's ceiling needs no gear: neither remark
    fair = design_check(_design_trials(dict.fromkeys(names, 26.9), 20.0), 20.0, Config())
    assert fair["well_posed"] and not fair["beyond_squeeze"] and fair["reason"] is None
    assert "worm gear" not in design_verdict_text(fair, 20.0)
    short = design_check(_design_trials({names[0]: 26.9}, 20.0), 20.0, Config())
    assert short["passed"] is False  # a box without a feasible grip fails the check


def test_cone_objects_continue_the_procedural_sequence_when_the_config_has_few():
    config = Config().override(objects={"procedural_count": 0})
    settings = CalibrationSettings(retest_objects=0, cone_objects=30)
    plan = choose_objects(config, settings)
    cone = [name for name, parts in plan.items() if "cone" in parts]
    assert len(cone) == 30 and any(name.startswith("proc_0_") for name in cone)
    # the study's procedural objects come first, in the same order (object i depends on i only)
    from grip_env.calibration import candidate_objects

    few = [o.name for o in candidate_objects(Config().override(objects={"procedural_count": 3}))]
    many = [o.name for o in candidate_objects(Config(), settings)]
    assert few[:len(BOXES_MM) + 18 + 3] == many[:len(BOXES_MM) + 18 + 3]


def test_calibration_runs_on_the_configured_backend(monkeypatch):
    seen = {}

    def fake_run_jobs(job, tasks, workers, backend="process", address=None):
        seen.update(backend=backend, workers=workers, tasks=len(list(tasks)))
        return iter(())

    monkeypatch.setattr("grip_env.dataset.backends.run_jobs", fake_run_jobs)
    from grip_env.calibration import run_calibration_trials

    config = Config().override(dataset={"backend": "ray"})
    run_calibration_trials(config, CalibrationSettings.quick(workers=2))
    assert seen["backend"] == "ray" and seen["workers"] == 2 and seen["tasks"] >= len(BOXES_MM)


def test_calibration_trials_come_in_the_plan_s_order_whatever_order_workers_finish(monkeypatch):
    def last_first(job, tasks, workers, backend="process", address=None):
        for task in reversed(list(tasks)):  # as workers finishing in another order give them
            yield task, pd.DataFrame({"object_id": [task.object_id] * 2, "trial": [0, 1]})

    monkeypatch.setattr("grip_env.dataset.backends.run_jobs", last_first)
    from grip_env.calibration import choose_objects, run_calibration_trials

    settings = CalibrationSettings.quick(workers=2)
    trials = run_calibration_trials(Config(), settings)
    assert list(dict.fromkeys(trials["object_id"])) == list(choose_objects(Config(), settings))
    assert trials["trial"].tolist() == [0, 1] * (len(trials) // 2)


def test_the_study_recomputes_its_calibration_when_the_calibration_sizes_change(monkeypatch):
    import functools

    from classifiers.experiments.study import stage_key

    before = stage_key("calibration", Config(), "0" * 64)
    assert stage_key("calibration", Config(), "0" * 64) == before
    assert stage_key("calibration", Config(), "0" * 64, quick=True) != before
    monkeypatch.setattr("grip_env.calibration.CalibrationSettings",
                        functools.partial(CalibrationSettings, cone_objects=50))
    assert stage_key("calibration", Config(), "0" * 64) != before


def test_retest_where_no_object_ranks_its_grips_has_no_within_mean_and_no_warning():
    """Every grip of every object held nothing in both sets (a quick study's few trials): no
    object ranks its grips, so there is no within-object mean, not NaN with a RuntimeWarning."""
    import warnings

    rng = np.random.default_rng(5)
    grips = {f"g{i}": ("best", -10.0) for i in range(6)}  # clipped to robustness 0 everywhere
    trials = pd.concat([_trials("retest", grips, 4, rng, obj=o) for o in "uv"])
    assert (trials["robustness"] == 0).all()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = retest_check(trials, CalibrationSettings(trials_per_set=2, bootstrap=50))
    assert result["within_object_mean"] is None
