"""The study's comparison of grips planned on the true and on the rendered contour."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from classifiers.experiments.perception_effect import (
    COMPARED,
    paired_differences,
    run_perception_effect,
)
from grip_env.config import Config


def test_paired_differences_are_rendered_minus_true_with_an_interval() -> None:
    rows = pd.DataFrame({f"{side}_{name}": values for name in COMPARED
                         for side, values in (("true", [1.0, 2.0, 3.0, 4.0]),
                                              ("render", [1.5, 2.5, 3.5, 4.5]))})
    found = paired_differences(rows, seed=0)
    assert found["Q_C"]["true"] == pytest.approx(2.5) and found["Q_C"]["render"] == 3.0
    assert found["Q_C"]["mean"] == pytest.approx(0.5)
    assert found["Q_C"]["ci"] == pytest.approx([0.5, 0.5])  # every object moves by the same 0.5
    rows["render_S1"] = [1.0, 2.0, 3.0, 14.0]
    low, high = paired_differences(rows, seed=0)["S1"]["ci"]
    assert low < paired_differences(rows, seed=0)["S1"]["mean"] < high


@pytest.mark.slow
def test_the_stage_pairs_each_objects_best_grips(generated_dataset_dir: Path, tmp_path) -> None:
    from grip_env.dataset import load, load_perceived_objects

    config = Config().override(objects={"set": "basic", "procedural_count": 4},
                               dataset={"trials": 2, "max_grips_per_object": 6, "workers": 1})
    result = run_perception_effect(config, generated_dataset_dir, tmp_path / "perception")
    assert json.loads((tmp_path / "perception" / "perception.json").read_text())["objects"] == \
        result["objects"]
    assert result["planned_on"] == "render" and result["objects"] >= 4
    grips = load(generated_dataset_dir)
    assert all(p is not None for p in load_perceived_objects(generated_dataset_dir))
    for pair in result["pairs"]:  # the rendered plan's best is the dataset's best row
        kept = grips[grips["object_id"] == pair["object_id"]]
        assert pair["render_Q_C"] == pytest.approx(kept["Q_C"].min())
        assert 0.0 <= pair["true_success_rate"] <= 1.0
    for name, value in result["differences"].items():
        low, high = value["ci"]
        assert low <= value["mean"] <= high, name
        assert value["mean"] == pytest.approx(value["render"] - value["true"])
    assert set(result["timing_s"]) == {"plan_true_s", "simulate_true_best_s"}
    assert np.isfinite(grips.attrs["manifest"]["perception_seconds"])
    two = run_perception_effect(config.override(dataset={"workers": 2}), generated_dataset_dir,
                                tmp_path / "two")  # fmt: skip
    assert two["pairs"] == result["pairs"] and two["differences"] == result["differences"]


def test_a_dataset_planned_on_the_polygons_has_nothing_to_compare(tmp_path) -> None:
    from grip_env.dataset import generate
    from tests.test_dataset import toy_job

    config = Config().override(perception={"source": "polygon"}, dataset={"trials": 1})
    data = generate(config, tmp_path / "d", objects="basic", workers=1, progress=False,
                    job=toy_job)
    assert run_perception_effect(config, data, tmp_path / "p") == {"planned_on": "polygon",
                                                                   "objects": 0}


def test_a_large_dataset_is_paired_on_a_seeded_sample_of_its_objects():
    from classifiers.experiments.perception_effect import MAX_OBJECTS, sampled_objects

    small = pd.DataFrame({"object_id": [f"o{i}" for i in range(MAX_OBJECTS)] * 2})
    assert sampled_objects(small, seed=0) == set(small["object_id"])  # the default study: all
    large = pd.DataFrame({"object_id": [f"o{i}" for i in range(500)]})
    chosen = sampled_objects(large, seed=3)
    assert len(chosen) == MAX_OBJECTS and chosen <= set(large["object_id"])
    assert sampled_objects(large, seed=3) == chosen != sampled_objects(large, seed=4)
