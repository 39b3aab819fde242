"""Why the RL selector stops short of lambdarank: one sentence read from the committed curves,
stated for a study of the standard dataset whose selector fell short, never typed."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

from classifiers.report.selector_diagnosis import (
    DIAGNOSIS_FOLDER,
    FIGURE,
    diagnosis,
    diagnosis_sentence,
    falls_short,
    measured_on_standard,
    study_diagnosis,
)

ROOT = Path(__file__).resolve().parents[1]


def _curves(folder: Path) -> None:
    """Two seeds: seed means 0.40 at 1,000 steps (before the plateau is read), then 0.55, 0.56,
    0.54 at 10,000, 100,000 and 1,000,000 (seed 0 alone there); a robustness variant ignored."""
    rows = [("success", 0, 1000, 0.40), ("success", 1, 1000, 0.40),
            ("success", 0, 10000, 0.56), ("success", 1, 10000, 0.54),
            ("success", 0, 100000, 0.57), ("success", 1, 100000, 0.55),
            ("success", 0, 1000000, 0.54), ("robustness", 0, 10000, 0.99)]  # fmt: skip
    frame = pd.DataFrame(rows, columns=["variant", "seed", "timesteps", "held_out_success"])
    frame.assign(train_reward=0.5, seconds=1.0).to_csv(folder / "curves.csv", index=False)


def _ceiling(folder: Path) -> None:
    """Lambdarank 0.58, 0.59 (written twice, as each command run writes it); two neural
    configurations: at the last iteration (800) seed means 0.545 and 0.565; the best
    checkpoint 0.60 at iteration 400."""
    columns = ["encoding", "objective", "target", "activation", "hidden", "seed", "iteration",
               "train_top1", "held_out_top1", "seconds"]  # fmt: skip
    rows = [("trees", "lambdarank", "success_count", None, None, 0, None, 0.7, 0.58, 1),
            ("trees", "lambdarank", "success_count", None, None, 1, None, 0.7, 0.59, 1),
            ("trees", "lambdarank", "success_count", None, None, 0, None, 0.7, 0.58, 1),
            ("log", "policy", "success", "tanh", "64-64", 0, 400, 0.6, 0.50, 1),
            ("log", "policy", "success", "tanh", "64-64", 0, 800, 0.6, 0.54, 1),
            ("log", "policy", "success", "tanh", "64-64", 1, 800, 0.6, 0.55, 1),
            ("log", "pairwise", "success", "tanh", "64-64", 0, 400, 0.6, 0.60, 1),
            ("log", "pairwise", "success", "tanh", "64-64", 0, 800, 0.6, 0.56, 1),
            ("log", "pairwise", "success", "tanh", "64-64", 1, 800, 0.6, 0.57, 1)]  # fmt: skip
    pd.DataFrame(rows, columns=columns).to_csv(folder / "ceiling.csv", index=False)


def test_the_figures_are_read_from_the_curves_by_hand(tmp_path: Path) -> None:
    _curves(tmp_path)
    _ceiling(tmp_path)
    found = diagnosis(tmp_path)
    assert found["plateau"] == pytest.approx([0.54, 0.56])
    assert found["plateau_steps"] == [10000, 1000000] and found["curve_seeds"] == 2
    assert found["ceiling"] == pytest.approx([0.545, 0.565])
    assert found["ceiling_best"] == pytest.approx(0.60) and found["ceiling_iterations"] == 800
    assert found["ceiling_configurations"] == 2
    assert found["lambdarank"] == pytest.approx([0.58, 0.59])
    sentence = diagnosis_sentence(found, 382)
    for text in ("0.540–0.560 from 10,000 to 1,000,000 steps", "2 configurations",
                 "0.545–0.565 after 800 iterations", "best single checkpoint 0.600",
                 "0.580–0.590", "382 training objects"):  # fmt: skip
        assert text in sentence
    (tmp_path / "ceiling.csv").unlink()
    assert diagnosis(tmp_path) is None


def _answers(high: float) -> dict:
    return {"best_supervised": "ranker_lambdarank",
            "picks": {"rl - ranker_lambdarank": {"estimate": -0.05, "ci": [-0.08, high]}}}


def test_only_a_selector_below_the_best_method_is_explained() -> None:
    assert falls_short(_answers(-0.02))
    assert not falls_short(_answers(0.01))  # not shown to be worse
    assert not falls_short({"best_supervised": None, "picks": {}}) and not falls_short(None)
    other = {"best_supervised": "regressor_svr",  # the ceilings speak of lambdarank only
             "picks": {"rl - regressor_svr": {"estimate": -0.05, "ci": [-0.08, -0.02]}}}
    assert not falls_short(other)


def _study(out: Path, dataset: Path, generated: bool = False) -> Path:
    out.mkdir(parents=True)
    (out / "data.json").write_text(json.dumps({"dataset": str(dataset), "generated": generated}))
    return out


def test_only_a_study_of_the_standard_dataset_is_explained(tmp_path: Path) -> None:
    standard, other, copy = tmp_path / "standard", tmp_path / "mine", tmp_path / "copy"
    for folder, manifest in ((standard, "A"), (other, "B"), (copy, "A")):
        folder.mkdir()
        (folder / "manifest.json").write_text(manifest)
    assert measured_on_standard(_study(tmp_path / "s1", copy), standard)  # another checkout
    assert not measured_on_standard(_study(tmp_path / "s2", other), standard)
    assert not measured_on_standard(_study(tmp_path / "s3", copy, generated=True), standard)
    assert not measured_on_standard(tmp_path / "nothing", standard)
    _curves(tmp_path)
    _ceiling(tmp_path)
    root = tmp_path / "repo"
    (root / DIAGNOSIS_FOLDER).mkdir(parents=True)
    for name in ("curves.csv", "ceiling.csv"):
        (root / DIAGNOSIS_FOLDER / name).write_bytes((tmp_path / name).read_bytes())
    on_standard = tmp_path / "s1"
    assert study_diagnosis(on_standard, _answers(-0.02), root, standard) == diagnosis(tmp_path)
    assert study_diagnosis(on_standard, _answers(0.01), root, standard) is None
    assert study_diagnosis(tmp_path / "s2", _answers(-0.02), root, standard) is None


def test_the_readme_block_and_the_report_state_it_from_the_committed_curves(tmp_path):
    """The committed curves give the sentence (their figures, not typed ones) in the README's
    results block and in the report, the curve figure beside it."""
    from test_report import _stored_run

    from classifiers.report.document import Report
    from classifiers.report.readme import results_block
    from classifiers.report.study_report import _selector_diagnosis
    from grip_env.datasets import SHIPPED

    found = diagnosis(ROOT / DIAGNOSIS_FOLDER)
    assert found is not None and found["lambdarank"][0] > found["ceiling"][1]
    out = tmp_path / "run"
    table = _stored_run(out)
    (out / "data.json").write_text(json.dumps({"dataset": str(SHIPPED), "generated": False}))
    block = results_block(out, table, "abc1234", "0.1.0", diagnosis=found)
    sentence = diagnosis_sentence(found, 3)  # the stored run's selector split: no train list
    assert diagnosis_sentence(found, None) in block
    assert f"{found['plateau'][0]:.3f}–{found['plateau'][1]:.3f}" in sentence
    assert f"]({DIAGNOSIS_FOLDER}/{FIGURE})" in block
    assert "Why the RL selector" not in results_block(out, table, "abc1234", "0.1.0")
    report = Report("study")
    _selector_diagnosis(report, out, _answers(-0.02), out / "figures")
    md, _ = report.write(out)
    text = md.read_text()
    assert diagnosis_sentence(found, None) in text and "](figures/selector_curve.png)" in text
    assert (out / "figures" / "selector_curve.png").read_bytes() == (
        ROOT / DIAGNOSIS_FOLDER / FIGURE).read_bytes()
    report = Report("study")
    _selector_diagnosis(report, out, _answers(0.01), out / "figures")
    md, _ = report.write(tmp_path / "not_short")
    assert "Why the RL selector" not in md.read_text()
