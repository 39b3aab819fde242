"""``grip-env validate --crosscheck N``: a dataset's grips in the other engine, the agreement."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from cli_runs import assert_refused, cli

from grip_env.config import Config
from grip_env.dataset import generate
from grip_env.dataset.crosscheck import crosscheck
from grip_env.dataset.manifest import read_manifest, write_manifest
from grip_env.objects import load_object_set

pytest.importorskip("mujoco")

TINY = Config().override(dataset={"trials": 3, "max_grips_per_object": 4, "workers": 1})


@pytest.fixture(scope="module")
def tiny(tmp_path_factory: pytest.TempPathFactory) -> Path:
    objects = [o for o in load_object_set("default") if o.name in ("rectangle", "hexagon")]
    return generate(TINY, tmp_path_factory.mktemp("cross") / "data", objects=objects,
                    progress=False)


@pytest.mark.slow
def test_every_grip_runs_in_both_engines_and_pybullet_reproduces_its_labels(tiny):
    found = crosscheck(tiny, 2, seed=0)
    assert (found.engine, found.other) == ("pybullet", "mujoco")
    assert found.objects == 2 and found.grips == 8 and found.trials == 24
    assert found.reproduced == found.grips  # the own engine's run is the recorded labels
    assert 0.0 <= found.agreement <= 1.0
    low, high = found.agreement_interval
    assert low <= found.agreement <= high
    assert set(found.families) == {"named"}
    assert repr(crosscheck(tiny, 2, seed=0)) == repr(found)  # seeded: the same figures again


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
