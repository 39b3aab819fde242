"""The label model is frozen: a fixed set of trials gives exactly the recorded outcomes.

A failure here means the code changed some trial outcome. That is a new label model: bump
``grip_env.sim.LABEL_MODEL``, say why in BENCHMARKS.md, renew the recording
(``python -m tests.golden --record``) and regenerate the standard dataset.
"""

from __future__ import annotations

import golden
import pytest


def test_the_recording_is_of_the_code_s_label_model_and_large_enough():
    stored = golden.recording()
    assert stored["label_model"] == golden.LABEL_MODEL
    objects = {grip["object_id"] for grip in stored["grips"]}
    assert len(stored["outcomes"]) >= 24 and len(objects) >= 4
    outcomes = stored["outcomes"]
    assert {o["success"] for o in outcomes} == {True, False}, "pin successes and failures alike"
    assert len({o["robustness"] for o in outcomes}) >= 4, "pin several levels of the ramp"


@pytest.mark.slow
def test_every_golden_trial_gives_its_recorded_outcome():
    lines = golden.differences(golden.recording())
    assert not lines, "a trial outcome moved (a new label model?):\n" + "\n".join(lines)
