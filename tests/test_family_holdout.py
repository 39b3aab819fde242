"""Family holdout: models trained on every object family but one, scored on the one held out."""

from __future__ import annotations

import pandas as pd
import pytest

from classifiers.evaluation.cross_validation import family_holdout_metrics, object_families
from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.learners.models import make_model


@pytest.fixture(scope="module")
def synthetic_grips_table() -> pd.DataFrame:
    return synthetic_grips(n_objects=12, seed=0)


def test_each_family_is_scored_by_models_that_never_saw_it(synthetic_grips_table):
    table = synthetic_grips_table
    families = {str(i): ("mesh" if int(i) % 3 == 0 else "named") for i in table["object_id"]}
    models = {name: make_model(name, 0) for name in ("logreg", "random")}
    result = family_holdout_metrics(table, families, models)["families"]
    assert set(result) == {"mesh", "named"}
    mesh_objects = {i for i, f in families.items() if f == "mesh"}
    assert result["mesh"]["objects"] == len(mesh_objects)
    assert result["mesh"]["grips"] == int(table["object_id"].astype(str).isin(mesh_objects).sum())
    for family in result.values():
        assert set(family["models"]) == {"logreg", "random"}
        assert family["models"]["logreg"]["roc_auc"] > family["models"]["random"]["roc_auc"]


def test_one_family_gives_no_holdout(synthetic_grips_table):
    families = {str(i): "named" for i in synthetic_grips_table["object_id"]}
    result = family_holdout_metrics(synthetic_grips_table, families, {"random": make_model(
        "random", 0)})
    assert result == {"families": {}}


def test_families_come_from_the_manifest(synthetic_grips_table):
    table = synthetic_grips_table.copy()
    table.attrs["manifest"] = {"objects": [{"object_id": "a", "family": "mesh"},
                                           {"object_id": "b"}]}
    assert object_families(table) == {"a": "mesh"}
    assert object_families(synthetic_grips_table.iloc[:0]) == {}


def test_the_report_shows_each_family_held_out():
    from classifiers.report.document import Report
    from classifiers.report.study_report import _family_holdout_table

    report = Report("t")
    scores = {"logreg": {"roc_auc": 0.71, "top1_success": 0.5}}
    _family_holdout_table(report, {"families": {
        "mesh": {"objects": 18, "grips": 300, "models": scores},
        "named": {"objects": 18, "grips": 400, "models": scores},
        "file": {"objects": 2, "grips": 9, "models": {}}}})
    text = report.to_markdown()
    assert "mesh ROC-AUC" in text and "named top-1" in text and "0.71" in text
    assert "file" not in text.split("Family holdout")[0] and "mesh 18 objects" in text
    empty = Report("t")
    _family_holdout_table(empty, {"families": {}})
    assert "Family holdout" not in empty.to_markdown()
