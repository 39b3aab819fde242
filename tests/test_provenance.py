"""Stage provenance: what each study stage read is hashed, and a rerun recomputes only what
changed (the real reruns are in test_study.py)."""

from __future__ import annotations

import importlib.metadata

import pytest

from classifiers.experiments import stage_code, study
from classifiers.experiments.study import (
    QUICK_OVERRIDES,
    describe_quick,
    quick_overrides,
    stage_key,
    stage_record,
    study_config,
)
from grip_env.config import Config

STAGES = ("classifiers", "ablation", "selector", "calibration")


def test_an_upgrade_of_grip_env_changes_every_stage_key(monkeypatch):
    base = {name: stage_key(name, Config(), "d") for name in STAGES}
    monkeypatch.setattr(study, "package_version", lambda: "99.0")
    assert all(stage_key(name, Config(), "d") != base[name] for name in STAGES)
    assert stage_record("ablation", Config(), "d")["package_version"] == "99.0"


ALL_STAGES = tuple(study.STAGE_RUNS)


def _edited(monkeypatch, module: str) -> None:
    """As if ``module``'s source had been edited (one comment line added)."""
    real = stage_code._source
    monkeypatch.setattr(stage_code, "_source",
                        lambda name: real(name) + (b"# edited\n" if name == module else b""))


@pytest.mark.parametrize(("module", "recomputed"), [
    # the selector's evaluation: the selector, and what reads its scores or its learners' code
    ("classifiers.experiments.selector.evaluation",
     {"classifiers", "selector", "selector_retry", "images", "benchmark"}),
    # the CNN: every learning stage (the model registry names it), not the simulating ones
    ("classifiers.learners.cnn", {"classifiers", "ablation", "selector", "selector_retry",
                                  "images", "benchmark"}),
    ("grip_env.config", set(ALL_STAGES)),  # every stage reads its config
])
def test_an_edit_recomputes_the_stages_whose_code_it_is_and_no_other(monkeypatch, module,
                                                                    recomputed):
    """At the same grip-env version, a stage's key changes exactly when a module it runs does."""
    base = {name: stage_key(name, Config(), "d") for name in ALL_STAGES}
    _edited(monkeypatch, module)
    changed = {name for name in ALL_STAGES if stage_key(name, Config(), "d") != base[name]}
    assert changed == recomputed


def test_a_stage_whose_code_changed_says_so(monkeypatch):
    before = stage_record("selector", Config(), "d")
    _edited(monkeypatch, "classifiers.experiments.selector.training")
    assert study.changed_inputs(before, stage_record("selector", Config(), "d")) == "its code"


def test_the_calibration_stage_covers_the_helpers_it_calls_in_the_study_module():
    """A stage's run function calls helpers of its own module: their imports count too."""
    record = stage_record("calibration", Config(), "d")
    assert record["code_sha256"] == stage_code.stage_code_digest(study.STAGE_RUNS["calibration"])
    assert "grip_env.calibration" in _reached("calibration")
    assert "classifiers.experiments.selector" not in _reached("calibration")


def _reached(name: str) -> set[str]:
    import ast
    import inspect

    tree = ast.parse(inspect.getsource(study))
    functions = stage_code._called_functions(tree, study.STAGE_RUNS[name].__name__)
    return stage_code.reachable_modules(stage_code._imported(
        ast.Module(body=functions, type_ignores=[]), study.__name__, is_package=False))


def test_the_package_version_is_the_installed_one():
    try:
        expected = importlib.metadata.version("grip-env")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("grip-env is not installed")
    assert study.package_version() == expected


def test_adding_a_model_recomputes_the_classifiers_and_the_selector_only():
    base = Config()
    more = base.override(learning={"models": (*base.learning.models, "random")[-3:]})
    changed = {name for name in STAGES
               if stage_key(name, base, "d") != stage_key(name, more, "d")}  # fmt: skip
    assert changed == {"classifiers", "selector"}
    record = stage_record("classifiers", more, "d")
    assert record["inputs"]["learning"]["models"] == list(more.learning.models)
    assert study.changed_inputs(stage_record("selector", base, "d"),
                                stage_record("selector", more, "d")) == "learning.models"


def test_the_calibration_key_tells_quick_from_full():
    assert stage_key("calibration", Config(), "d", quick=True) != stage_key(
        "calibration", Config(), "d", quick=False)


def test_quick_replaces_only_what_the_config_leaves_at_its_default():
    everything = quick_overrides(Config())
    assert everything == QUICK_OVERRIDES
    mine = Config().override(learning={"models": ("svm",)}, dataset={"trials": 6})
    shrunk = study_config(mine, quick=True)
    assert shrunk.learning.models == ("svm",) and shrunk.dataset.trials == 6
    assert shrunk.learning.folds == QUICK_OVERRIDES["learning"]["folds"]
    line = describe_quick(mine)
    assert "learning.folds=2" in line and "keeps dataset.trials, learning.models" in line
    assert "learning.models=" not in line
    assert study_config(mine, quick=False) is mine


def test_the_dataset_identity_ignores_the_learning_sections():
    from grip_env.dataset.manifest import identity_differences, run_identity, without_learning

    base = run_identity(Config(), [])
    other = Config().override(learning={"seed": 5, "models": ("svm",)}, selector={"seed": 3})
    assert run_identity(other, []) == base
    assert "learning" not in base["config"] and "selector" not in base["config"]
    old = {**base, "config": {**base["config"], "learning": {"seed": 1}}}  # an older manifest
    assert identity_differences(without_learning(old), base) == []
    assert identity_differences(run_identity(Config().override(dataset={"seed": 9}), []), base)


def test_the_standard_dataset_stays_the_run_of_its_recorded_config():
    """A setting added since (``synthesis.frictional_closure``), at the value that reproduces the
    recorded planner, leaves the identity as recorded: the dataset resumes and extends as the
    code's run; turned on, it is another run."""
    import json

    from grip_env.dataset.manifest import identity_differences, run_identity, without_learning
    from grip_env.datasets import standard_path

    manifest = json.loads((standard_path() / "manifest.json").read_text(encoding="utf-8"))
    config = Config.model_validate(manifest["config"])
    recorded = without_learning(manifest["identity"])["config"]
    assert identity_differences(recorded, run_identity(config, [])["config"]) == []
    on = config.override(synthesis={"frictional_closure": True})
    assert identity_differences(recorded, run_identity(on, [])["config"]) == [
        "synthesis.frictional_closure: None -> True"]
    palm = config.override(uncertainty={"stratified_palm": True})
    assert identity_differences(recorded, run_identity(palm, [])["config"]) == [
        "uncertainty.stratified_palm: None -> True"]
