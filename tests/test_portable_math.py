"""numpy held at x86-64-v3: the labels do not depend on whether the CPU has AVX-512."""

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
import json, sys
{first}
from grip_env.portable_math import live_beyond_v3
from grip_env.objects import load_object_set
from grip_env.planning.pipeline import candidates
from grip_env.sim import run_trial_outcomes
import os
box = next(o for o in load_object_set("default") if o.name == "rectangle")
try:
    run_trial_outcomes(box, candidates(box).head(1), trials=1)
    refused = ""
except RuntimeError as exc:
    refused = str(exc)
print(json.dumps([live_beyond_v3(), os.environ.get("{env}"), refused]))
"""


def _probe(first: str) -> tuple[list[str], str | None, str]:
    env = {k: v for k, v in os.environ.items()
           if k not in (NUMPY_ENVIRONMENT, OPENBLAS_ENVIRONMENT)}
    done = subprocess.run([sys.executable, "-c", PROBE.format(first=first, env=NUMPY_ENVIRONMENT)],
                          capture_output=True, text=True, env=env, timeout=300, check=True)
    live, value, refused = json.loads(done.stdout.strip().splitlines()[-1])
    return live, value, refused


def _machine_has_avx512_kernels() -> bool:
    done = subprocess.run([sys.executable, "-c", "import json, numpy; from grip_env.portable_math "
                           "import live_beyond_v3; print(json.dumps(live_beyond_v3()))"],
                          capture_output=True, text=True, timeout=120, check=True,
                          env={**os.environ, NUMPY_ENVIRONMENT: "", OPENBLAS_ENVIRONMENT: ""})
    return bool(json.loads(done.stdout.strip().splitlines()[-1]))


def test_the_suite_runs_held_at_v3():
    assert live_beyond_v3() == []


def test_importing_grip_env_first_holds_numpy_at_v3_and_labels_are_made():
    live, value, refused = _probe("import grip_env")
    assert live == [] and refused == ""
    assert value == " ".join(BEYOND_V3)  # child processes inherit it


@pytest.mark.slow
def test_labels_are_refused_when_numpy_s_avx512_kernels_are_live():
    if not _machine_has_avx512_kernels():
        pytest.skip("this CPU has no AVX-512 kernels for numpy to use")
    live, _, refused = _probe("import numpy")
    assert live  # numpy came first: its AVX-512 kernels are in use
    assert refused.startswith(live[0]) and NUMPY_ENVIRONMENT in refused
