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
import json, os
{first}
from grip_env.portable_math import live_beyond_v3
from grip_env.dataset.backends import in_this_process
from grip_env.datasets import load_standard
load_standard()
print(json.dumps({{"live": live_beyond_v3(), "held": os.environ.get("{env}"),
                  "here": in_this_process(1)}}))
"""

#: The public API, with numpy (and gymnasium) imported before grip_env: standard objects
#: perceived and planned again, some of their recorded grips simulated again, compared bit for
#: bit with the recorded rows; and a live GripSelect-v0 episode, digested for comparison with a
#: process held at x86-64-v3.
REPLAY = """
import json, hashlib, sys
{first}
import gymnasium
import numpy as np
import grip_env
from grip_env import datasets
from grip_env.dataset.resimulation import OUTCOME_COLUMNS, retest_sample, same_candidates
from grip_env.dataset.sampling import keep_grips
from grip_env.objects.meshes import execution_height_mm
from grip_env.pipeline import candidates
from grip_env.portable_math import live_beyond_v3
from grip_env.sim import run_trials
from grip_env.sim.camera import perceive

sample = retest_sample(datasets.standard_path(), {objects}, seed=3)
found = {{"live": live_beyond_v3(), "objects": [], "grips": 0, "candidates_identical": 0,
          "outcomes_identical": 0}}
for task, recorded in sample if {replay} else []:
    config = task.config
    seen = perceive(task.obj, config.perception, config.objects.thickness_mm,
                    seed=task.child_seeds()[0])
    table = candidates(seen, config.grasp, config,
                       height_mm=execution_height_mm(task.obj, config.objects))
    kept = keep_grips(table, config.dataset, task.sampling_seed())
    found["objects"].append(task.object_id)
    found["candidates_identical"] += same_candidates(kept, recorded)
    grips = recorded.head({grips}).assign(object_id=task.object_id)
    outcome = run_trials(task.obj, grips, config, config.dataset.trials, config.dataset.seed)
    same = np.ones(len(grips), dtype=bool)
    for name in OUTCOME_COLUMNS:
        same &= np.asarray(outcome[name]) == grips[name].to_numpy()
    found["grips"] += len(grips)
    found["outcomes_identical"] += int(same.sum())
task = sample[0][0]
env = gymnasium.make("GripSelect-v0", objects=[task.obj], config=task.config)
observation, _ = env.reset(seed=0)
after, reward, *_ , info = env.step(int(np.argmax(observation["mask"])))
planned = env.unwrapped.backend.candidates(task.object_id).select_dtypes("number")
env.close()
digest = hashlib.sha256(b"".join(np.ascontiguousarray(part).tobytes() for part in (
    *observation.values(), *after.values(), planned.to_numpy(float)))).hexdigest()
found["env"] = [digest, reward, info["grip_id"], float(info["Q_C"]).hex()]
print(json.dumps(found))
"""


def _run(script: str) -> dict:
    """``script`` in a fresh interpreter with no kernel hold inherited; its last output line."""
    env = {k: v for k, v in os.environ.items()
           if k not in (NUMPY_ENVIRONMENT, OPENBLAS_ENVIRONMENT)}
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env,
                          timeout=600, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def _probe(first: str) -> dict:
    return _run(PROBE.format(first=first, env=NUMPY_ENVIRONMENT))


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
    assert found["held"] == " ".join(BEYOND_V3)  # child processes inherit it


@pytest.mark.slow
def test_numpy_first_plans_simulates_and_steps_as_the_recorded_labels():
    """``import numpy, gymnasium`` before grip_env is ordinary Python style: candidates, trials
    and a live environment must still give the recorded bits (the same as a held process).
    With numpy's AVX-512 kernels computing them in this process, 0 of 10 standard objects
    re-planned identically, nor did trials of identical grips (BENCHMARKS.md, "Import order")."""
    if not _machine_has_avx512_kernels():
        pytest.skip("this CPU has no AVX-512 kernels for numpy to use")
    found = _run(REPLAY.format(first="import numpy, gymnasium", objects=2, grips=2, replay=True))
    assert found["live"]  # numpy came first: its AVX-512 kernels are live in the process
    assert found["candidates_identical"] == len(found["objects"]) == 2
    assert found["outcomes_identical"] == found["grips"] == 4
    held = _run(REPLAY.format(first="import grip_env", objects=2, grips=2, replay=False))
    assert held["live"] == []
    assert found["env"] == held["env"]
