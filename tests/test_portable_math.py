"""numpy held at x86-64-v3: the labels do not depend on whether the CPU has AVX-512, nor on
whether numpy was imported before grip_env."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from grip_env.portable_math import (
    BEYOND_V3,
    NUMPY_ENVIRONMENT,
    OPENBLAS_ENVIRONMENT,
    live_beyond_v3,
)

PROBE = """
import json, os, sys, warnings
warnings.simplefilter("always")
{first}
with warnings.catch_warnings(record=True) as loading:
    from grip_env.datasets import load_standard
    load_standard()
from grip_env.portable_math import live_beyond_v3, NonPortableMathWarning
from grip_env.dataset.backends import in_this_process
from grip_env.objects import load_object_set
from grip_env.planning.pipeline import candidates
from grip_env.sim import run_trial_outcomes
with warnings.catch_warnings(record=True) as planning:
    box = next(o for o in load_object_set("default") if o.name == "rectangle")
    for _ in range(2):
        run_trial_outcomes(box, candidates(box).head(1), trials=1)
from grip_env import datasets
from grip_env.dataset.resimulation import resimulate
found = resimulate(datasets.standard_path(), {grips}, seed=0, workers=1) if {grips} else None
mine = lambda caught: [str(w.message) for w in caught if w.category is NonPortableMathWarning]
print(json.dumps({{
    "live": live_beyond_v3(), "held": os.environ.get("{env}"), "here": in_this_process(1),
    "loading": mine(loading), "planning": mine(planning),
    "identical": None if found is None else [found.objects, found.candidates_identical,
                                             found.grips, found.outcomes_identical],
}}))
"""


def _probe(first: str, grips: int = 0) -> dict:
    env = {k: v for k, v in os.environ.items()
           if k not in (NUMPY_ENVIRONMENT, OPENBLAS_ENVIRONMENT)}
    script = PROBE.format(first=first, env=NUMPY_ENVIRONMENT, grips=grips)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env,
                          timeout=600, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def _machine_has_avx512_kernels() -> bool:
    done = subprocess.run([sys.executable, "-c", "import json, numpy; from grip_env.portable_math "
                           "import live_beyond_v3; print(json.dumps(live_beyond_v3()))"],
                          capture_output=True, text=True, timeout=120, check=True,
                          env={**os.environ, NUMPY_ENVIRONMENT: "", OPENBLAS_ENVIRONMENT: ""})
    return bool(json.loads(done.stdout.strip().splitlines()[-1]))


def test_the_suite_runs_held_at_v3():
    assert live_beyond_v3() == []


def test_importing_grip_env_first_holds_numpy_at_v3_and_labels_are_made_here():
    found = _probe("import grip_env")
    assert found["live"] == [] and found["here"]
    assert found["loading"] == found["planning"] == []
    assert found["held"] == " ".join(BEYOND_V3)  # child processes inherit it


@pytest.mark.slow
def test_numpy_first_warns_and_the_recorded_labels_are_still_made():
    """``import gymnasium, grip_env`` is how users start: it must work, say once, when it first
    plans or simulates (not when it only loads data), that this process's math is not portable,
    and still give the recorded labels (made in a held worker).
    With numpy's AVX-512 kernels in this process, 0 of 10 standard objects re-plan identically."""
    if not _machine_has_avx512_kernels():
        pytest.skip("this CPU has no AVX-512 kernels for numpy to use")
    found = _probe("import numpy", grips=4)
    assert found["live"] and not found["here"]  # numpy came first: its AVX-512 kernels are live
    assert found["loading"] == []
    assert len(found["planning"]) == 1 and found["planning"][0].startswith(found["live"][0])
    assert NUMPY_ENVIRONMENT in found["planning"][0]
    objects, same_candidates, grips, same_outcomes = found["identical"]
    assert same_candidates == objects and same_outcomes == grips == 4
