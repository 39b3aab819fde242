"""Each engine's label model is frozen: a fixed set of trials gives exactly the recorded outcomes.

A failure here means the code changed some trial outcome in that engine. That is a new label
model: bump its id (``grip_env.label_model``: ``LABEL_MODEL`` for PyBullet,
``MUJOCO_LABEL_MODEL`` for MuJoCo), say why in BENCHMARKS.md, renew the recording
(``python -m tests.golden [--engine mujoco] --record``) and regenerate the datasets it labelled.
"""

from __future__ import annotations

import importlib.util

import golden
import pytest

from grip_env.label_model import LABEL_MODEL, label_model_for

ENGINES = ["pybullet", pytest.param("mujoco", marks=pytest.mark.skipif(
    importlib.util.find_spec("mujoco") is None, reason="mujoco not installed"))]


@pytest.mark.parametrize("engine", ENGINES)
def test_the_recording_is_of_the_code_s_label_model_and_large_enough(engine):
    stored = golden.recording(engine)
    assert stored["label_model"] == label_model_for(engine)
    objects = {grip["object_id"] for grip in stored["grips"]}
    assert len(stored["outcomes"]) >= 24 and len(objects) >= 4
    outcomes = stored["outcomes"]
    assert {o["success"] for o in outcomes} == {True, False}, "pin successes and failures alike"
    assert len({o["robustness"] for o in outcomes}) >= 4, "pin several levels of the ramp"


def test_pybullet_s_recording_is_of_the_standard_label_model():
    assert golden.recording()["label_model"] == LABEL_MODEL


def test_every_engine_s_recording_pins_the_same_grips_and_names_its_engine():
    pybullet = golden.recording("pybullet")
    mujoco = golden.recording("mujoco")
    assert mujoco["grips"] == pybullet["grips"]
    assert (mujoco["seed"], mujoco["trials"]) == (pybullet["seed"], pybullet["trials"])
    assert [(o["grip_id"], o["trial"]) for o in mujoco["outcomes"]] == [
        (o["grip_id"], o["trial"]) for o in pybullet["outcomes"]]
    assert mujoco["engine"]["name"] == "mujoco" and mujoco["engine"]["version"]


@pytest.mark.slow
@pytest.mark.parametrize("engine", ENGINES)
def test_every_golden_trial_gives_its_recorded_outcome(engine):
    lines = golden.differences(golden.recording(engine), engine)
    assert not lines, "a trial outcome moved (a new label model?):\n" + "\n".join(lines)
