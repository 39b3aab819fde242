"""``grip-env validate --crosscheck N``: a dataset's grips in the other engine, the agreement."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from cli_runs import assert_refused, cli

from grip_env.config import Config
from grip_env.dataset import generate
from grip_env.dataset.crosscheck import (
    CrossCheck,
    _by_pieces,
    _first_holds,
    _group_values,
    _kappa,
    _run_key,
    crosscheck,
    trials_for,
)
from grip_env.dataset.manifest import read_manifest, write_manifest
from grip_env.objects import load_object_set

pytest.importorskip("mujoco")

TINY = Config().override(dataset={"trials": 3, "max_grips_per_object": 4, "workers": 1})


@pytest.fixture(scope="module")
def tiny(tmp_path_factory: pytest.TempPathFactory) -> Path:
    objects = [o for o in load_object_set("default") if o.name in ("rectangle", "hexagon")]
    return generate(TINY, tmp_path_factory.mktemp("cross") / "data", objects=objects,
                    progress=False)


@pytest.fixture(scope="module")
def checked(tiny: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[CrossCheck, Path]:
    parts = tmp_path_factory.mktemp("parts") / "cross.crosscheck"
    return crosscheck(tiny, 2, seed=0, parts=parts), parts


@pytest.mark.slow
def test_every_grip_runs_in_both_engines_and_pybullet_reproduces_its_labels(checked):
    found, _ = checked
    overall = found.overall
    assert (found.engine, found.other) == ("pybullet", "mujoco")
    assert overall.objects == 2 and overall.grips == 8 and overall.trials == 24
    assert found.reproduced == overall.grips  # the own engine's run is the recorded labels
    assert set(found.families) == {"named"}
    assert found.families["named"].grips == 8
    assert set(found.by_grips) == {"4 grips"}  # both objects keep TINY's 4 grips
    assert found.by_grips["4 grips"].agreement == overall.agreement  # the same objects
    assert set(found.by_pieces) == {"one convex piece"}  # a rectangle and a hexagon
    assert found.by_pieces["one convex piece"].within == overall.within
    for name in ("agreement", "kappa", "within", "pooled", "top1_own", "top1_other",
                 "retest_own", "retest_other"):
        value, (low, high) = getattr(overall, name), getattr(overall, f"{name}_interval")
        if np.isfinite(value):
            assert low <= value <= high, name
    assert 0.0 <= overall.agreement <= 1.0 and 0.0 <= overall.top1_own <= 1.0
    assert not (overall.retest_own > 1.0 or overall.retest_other > 1.0)  # NaN: tied labels
    shares = [overall.share_grip, overall.share_engine, overall.share_draws]
    assert sum(shares) == pytest.approx(1.0) and min(shares) >= 0.0  # grip, engine, draws
    assert "a label's differences between grips: the grip" in found.summary()


@pytest.mark.slow
def test_each_engine_s_cost_is_counted_on_its_own_trials(checked):
    found, _ = checked
    costs = {cost.engine: cost for cost in found.cost}
    assert set(costs) == {"pybullet", "mujoco"}
    for cost in costs.values():
        assert cost.trials == 48  # 8 grips x 3 trials, for the labels and for the retest
        assert cost.steps > 100 * cost.trials and cost.cpu_seconds > 0
        assert cost.ms_per_trial == pytest.approx(1e3 * cost.cpu_seconds / cost.trials)
        assert cost.us_per_step == pytest.approx(1e6 * cost.cpu_seconds / cost.steps)
        # the retest measured at 1..3 trials from each object's 6, and the label it prices
        assert len(cost.retest_by_trials) == 3
        defined = [v for v in cost.retest_by_trials if np.isfinite(v)]
        assert all(-1.0 <= v <= 1.0 for v in defined)
        if np.isfinite(cost.trials_measured):
            assert cost.trials_measured >= 1
            assert cost.core_seconds_measured == pytest.approx(
                math.ceil(cost.trials_measured) * cost.ms_per_trial / 1e3)


@pytest.mark.slow
def test_a_rerun_takes_each_object_from_its_part_and_remakes_a_stale_one(tiny, checked):
    found, parts = checked
    files = sorted(parts.glob("*.json"))
    assert len(files) == 2
    again = crosscheck(tiny, 2, seed=0, parts=parts)
    assert repr(again) == repr(found)  # seeded, and the parts read back exactly
    stored = json.loads(files[0].read_text())
    stored["draws"]["mujoco"] = stored["draws"]["pybullet"]  # MuJoCo "agrees" everywhere
    files[0].write_text(json.dumps(stored))
    edited = crosscheck(tiny, 2, seed=0, parts=parts)  # the part is read, not simulated
    trials = [24 // 2, 24 // 2]
    alike = round(found.overall.agreement * 24)
    assert edited.overall.agreement > found.overall.agreement or alike == 24
    assert edited.overall.trials == sum(trials)
    stored["key"]["label_models"]["mujoco"] = "an older MuJoCo label model"
    files[0].write_text(json.dumps(stored))
    remade = crosscheck(tiny, 2, seed=0, parts=parts)  # MuJoCo's runs alone made again
    assert remade.overall.agreement == found.overall.agreement
    part = json.loads(files[0].read_text())
    assert part["key"]["label_models"]["mujoco"] != "an older MuJoCo label model"
    assert part["draws"]["pybullet"] == stored["draws"]["pybullet"]  # kept, not re-simulated
    assert part["seconds"]["pybullet"] == stored["seconds"]["pybullet"]
    assert part["draws"]["mujoco"] != stored["draws"]["mujoco"] or alike == 24
    stored = part | {"key": {**part["key"], "grips": "another dataset's grips"}}
    stored["seconds"] = {engine: -1.0 for engine in stored["seconds"]}
    files[0].write_text(json.dumps(stored))
    crosscheck(tiny, 2, seed=0, parts=parts)  # not this dataset's part: both simulated again
    part = json.loads(files[0].read_text())
    assert part["key"]["grips"] != "another dataset's grips"
    assert min(part["seconds"].values()) > 0


def test_a_part_is_keyed_by_the_dataset_s_grips_not_its_label_model(tiny):
    """Regenerated at a new PyBullet label model, a dataset keeps its grips, and the parts keep
    MuJoCo's runs (each engine's own label model decides whether its runs are kept); any other
    change to the run identity is other grips."""
    manifest = read_manifest(tiny)
    key = _run_key(manifest, True)
    relabelled = {**manifest, "identity": {**manifest["identity"], "label_model": "next"}}
    assert _run_key(relabelled, True) == key
    seeded = {**manifest, "identity": {**manifest["identity"], "config": {"another": "config"}}}
    assert _run_key(seeded, True)["grips"] != key["grips"]
    assert _run_key(manifest, False) != key


def test_trials_for_a_trustworthy_label_follow_spearman_brown():
    # retest 0.8 from 3 trials: one trial's reliability 0.8 / (3 - 2 x 0.8) = 4/7, and
    # n = 0.8 (1 - 4/7) / (0.2 x 4/7) = 3 trials give 0.8 again
    assert trials_for(0.8, 3) == pytest.approx(3.0)
    assert trials_for(0.834, 5) == pytest.approx(3.98, abs=0.01)  # BENCHMARKS: 4 trials, 0.8
    assert trials_for(0.5, 1) == pytest.approx(4.0)
    assert trials_for(-0.1, 3) == float("inf") and np.isnan(trials_for(float("nan"), 3))


def test_kappa_is_cohen_s_on_the_pooled_trials():
    # 10 trials: 6 alike; engine a succeeds 5 times, b 5 times: chance 0.5, kappa 0.2
    rows = [{"trials": 4, "alike": 3, "a": 2, "b": 3}, {"trials": 6, "alike": 3, "a": 3, "b": 2}]
    agreement, kappa = _kappa(rows)
    assert agreement == pytest.approx(0.6) and kappa == pytest.approx(0.2)


def test_each_engine_s_mean_robustness_is_over_the_group_s_trials():
    # 3 + 2 trials: own engine 30 + 40 g in all, the other 15 + 10 g; an object with more
    # trials weighs more (a mean over trials, not over objects' means)
    rows = [{"trials": 3, "alike": 3, "a": 1, "b": 1, "sums": (30.0, 15.0),
             "means": (np.array([10.0, 20.0]), np.array([5.0, 6.0]))},
            {"trials": 2, "alike": 1, "a": 1, "b": 0, "sums": (40.0, 10.0),
             "means": (np.array([20.0, 20.0]), np.array([5.0, 5.0]))}]
    for row in rows:
        row.update(spearman=float("nan"), top_own=1.0, top_other=0.0, retest_own=float("nan"),
                   retest_other=float("nan"))
    found = _group_values(rows)
    assert found["robustness_own"] == pytest.approx(70.0 / 5)
    assert found["robustness_other"] == pytest.approx(25.0 / 5)


def test_objects_are_grouped_by_their_simulated_convex_pieces():
    from types import SimpleNamespace

    from grip_env.objects import PlanarObject

    square = PlanarObject.from_polygon([[0, 0], [40, 0], [40, 40], [0, 40]], name="square")
    ell = PlanarObject.from_polygon([[0, 0], [40, 0], [40, 15], [15, 15], [15, 40], [0, 40]],
                                    name="ell")
    checks = [SimpleNamespace(task=SimpleNamespace(obj=o, config=Config()))
              for o in (ell, square, ell)]
    assert _by_pieces(checks) == {"one convex piece": [1], "several convex pieces": [0, 2]}


def test_top_1_counts_the_grips_tied_first_alike_not_the_first_listed():
    # four grips; the first three tie at the ceiling, and in the other engine only the third
    # and the fourth succeed in most trials: a pick among the tied holds 1 time in 3
    ranked = np.array([128.0, 128.0, 128.0, 90.0])
    rates = np.array([0.4, 0.2, 0.8, 1.0])
    assert _first_holds(ranked, rates) == pytest.approx(1 / 3)
    assert _first_holds(ranked[::-1], rates[::-1]) == pytest.approx(1 / 3)  # order-free
    assert _first_holds(np.array([50.0, 60.0]), np.array([1.0, 0.6])) == 1.0
    assert _first_holds(np.array([50.0, 60.0]), np.array([1.0, 0.5])) == 0.0  # half is not most
    levels = [127.99999999999994, 53.81737057623772, 107.63474115247543, 45.25483399593903]
    one, other = levels + [76.1], levels[:3] + [76.1, levels[3]]  # the same trials reordered
    summed = np.array([sum(one) / 5, sum(other) / 5, 60.0])
    assert summed[0] != summed[1]  # a last bit apart
    assert _first_holds(summed, np.array([0.0, 1.0, 1.0])) == pytest.approx(0.5)


@pytest.mark.slow
def test_a_dataset_of_another_label_model_is_refused_in_one_line(tiny, tmp_path):
    copy = tmp_path / "old"
    import shutil

    shutil.copytree(tiny, copy)
    manifest = read_manifest(copy)
    write_manifest(copy, {**manifest, "label_model": "2026.12-crn"})
    report = tmp_path / "cross.json"
    assert_refused(*cli("validate", copy, "--crosscheck", 1, "--report", report),
                   "label model '2026.12-crn'", "cannot cross-check")
    assert not report.exists()


@pytest.mark.slow
def test_the_cli_reports_the_agreement(tiny, tmp_path):
    report = tmp_path / "cross.json"
    code, output = cli("validate", tiny, "--crosscheck", 1, "--workers", 1, "--report", report)
    assert code == 0, output
    assert "pybullet against mujoco" in output and "kappa" in output
    assert json.loads(report.read_text())["crosscheck"]["objects"] == 1


@pytest.mark.slow
def test_the_card_and_the_study_report_show_a_recorded_crosscheck(tiny, checked, tmp_path):
    from classifiers.report.document import Report
    from classifiers.report.study_report import _crosscheck_section
    from grip_env.dataset.card import CROSSCHECK_FILE, dataset_card

    found, _ = checked
    assert "Not cross-checked in the other engine yet" in dataset_card(tiny)
    stored = json.loads(json.dumps({"crosscheck": {"objects": 2, **found.as_dict()}}))
    card = dataset_card(tiny, stored)
    overall = found.overall
    assert f"| all | 2 | {overall.agreement:.1%} [" in card
    assert f"| named | 2 | {found.families['named'].agreement:.1%} [" in card
    assert f"| 4 grips | 2 | {found.by_grips['4 grips'].agreement:.1%} [" in card
    assert f"| one convex piece | 2 | {overall.agreement:.1%} [" in card
    assert f"| {overall.robustness_own:.1f} / {overall.robustness_other:.1f} |" in card
    assert "| mujoco | 48 |" in card and "core-s a trustworthy label" in card
    assert f"{overall.share_engine:.1%} [" in card and "label: the grip's share" in card
    study = tmp_path / "study"
    study.mkdir()
    (study / "data.json").write_text(json.dumps({"dataset": str(tmp_path / "data")}))
    report = Report("study")
    _crosscheck_section(report, study)
    assert not report.blocks  # no cross-check recorded with the dataset: no section
    (tmp_path / "data" / CROSSCHECK_FILE).parent.mkdir(parents=True)
    (tmp_path / "data" / CROSSCHECK_FILE).write_text(json.dumps(stored))
    _crosscheck_section(report, study)
    assert report.blocks[0].content == "Agreement between engines"
    assert any("reproduced their recorded labels" in str(b.content) for b in report.blocks)
    assert [b.kind for b in report.blocks] == ["heading", "text", "table", "table"]


def test_the_shipped_crosscheck_compares_this_code_s_label_models():
    """A change of either engine's label model leaves the shipped cross-check stale: re-run
    ``grip-env validate standard --crosscheck 80 --report ...`` and ship its report (the issue
    asks for at least 40 objects)."""
    from grip_env.dataset.card import recorded_crosscheck
    from grip_env.datasets import standard_path
    from grip_env.label_model import label_model_for

    found = recorded_crosscheck(standard_path())
    assert found is not None
    assert found["label_models"] == {e: label_model_for(e) for e in ("pybullet", "mujoco")}
    assert found["objects"] >= 40 and found["reproduced"] == found["overall"]["grips"]
