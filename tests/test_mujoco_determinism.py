"""MuJoCo's labels are a function of (seed, object, grip, trial) alone: the same bits in any order,
on any number of worker processes, in a fresh process, and with other CPU kernels.

The grips are the golden ones of two objects (``tests/golden.py``). Every outcome field is
compared through ``float.hex``: bit for bit, not close. The last test stands in for another
machine the way ``tests/test_machine_repro.py`` does (numpy's kernels below x86-64-v3, OpenBLAS on
its SSE kernel), and for an AVX-512 process whose numpy kernels are live. What it cannot cover:
glibc's libm picks FMA variants of ``sin``, ``cos``, ``exp``, ``pow`` on CPUs with FMA and AVX2
(x86-64-v3), and with them turned off (``GLIBC_TUNABLES=glibc.cpu.hwcaps=-FMA``: a pre-2013 CPU)
both engines' outcomes move (``python -m tests.benchmarks.engine_machines``; BENCHMARKS.md).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pandas as pd
import pytest

pytest.importorskip("mujoco")

from grip_env.config import Config
from grip_env.dataset.backends import worker_context
from grip_env.objects import load_object_set
from grip_env.sim import OUTCOME_COLUMNS, run_trial_outcomes

HERE = Path(__file__).parent
OBJECTS = ("rectangle", "hexagon")
TRIALS = 2
SEED = 7
#: Another machine's vector kernels: numpy's and OpenBLAS's below x86-64-v3.
OTHER_CPU = {"NPY_DISABLE_CPU_FEATURES": "X86_V3", "OPENBLAS_CORETYPE": "Nehalem"}


def golden_grips() -> pd.DataFrame:
    """The golden grips of ``OBJECTS`` (their stored plans)."""
    stored = json.loads((HERE / "data" / "golden_outcomes.json").read_text())
    grips = pd.DataFrame(stored["grips"])
    return grips[grips["object_id"].isin(OBJECTS)].reset_index(drop=True)


def outcomes(order: list[int] | None = None) -> dict[str, list[str]]:
    """Every (grip, trial)'s outcome in MuJoCo, as hex strings, keyed ``grip_id/trial``; the
    grips run object by object in ``order`` (positions in :func:`golden_grips`)."""
    grips = golden_grips()
    grips = grips if order is None else grips.iloc[order]
    found: dict[str, list[str]] = {}
    for name, group in grips.groupby("object_id", sort=False):
        found.update(_object_outcomes(str(name), group))
    return dict(sorted(found.items()))


def _object_outcomes(name: str, grips: pd.DataFrame) -> dict[str, list[str]]:
    obj = next(o for o in load_object_set("default") if o.name == name)
    config = Config().override(sim={"engine": "mujoco"})
    table = run_trial_outcomes(obj, grips, config, trials=TRIALS, seed=SEED)
    return {f"{grips.loc[row.grip, 'grip_id']}/{row.trial}":
            [float(getattr(row, c)).hex() for c in OUTCOME_COLUMNS[2:]]
            for row in table.itertuples(index=False)}


def _one_grip(position: int) -> dict[str, list[str]]:
    grips = golden_grips().iloc[[position]]
    return _object_outcomes(str(grips["object_id"].iloc[0]), grips)


def _in_a_fresh_process(environment: dict[str, str | None],
                        before: str = "") -> tuple[dict[str, list[str]], list[str]]:
    """:func:`outcomes` in a new Python process with ``environment`` changed (None: unset), and
    the kernels above x86-64-v3 live there."""
    script = (f"{before}import json; from test_mujoco_determinism import outcomes; "
              "from grip_env.portable_math import live_beyond_v3; "
              "print(json.dumps([outcomes(), live_beyond_v3()]))")
    changed = {**os.environ, **environment}
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=HERE,
                          env={k: v for k, v in changed.items() if v is not None}, timeout=600,
                          check=True)
    found, live = json.loads(done.stdout.strip().splitlines()[-1])
    return found, live


@pytest.fixture(scope="module")
def reference() -> dict[str, list[str]]:
    return outcomes()


@pytest.mark.slow
def test_mujoco_outcomes_do_not_depend_on_the_grips_order(reference):
    backwards = list(range(len(golden_grips())))[::-1]
    assert outcomes(backwards) == reference
    assert len(reference) == len(golden_grips()) * TRIALS


@pytest.mark.slow
@pytest.mark.parametrize("workers", [1, 2])
def test_mujoco_outcomes_do_not_depend_on_the_worker_processes(reference, workers):
    with ProcessPoolExecutor(workers, mp_context=worker_context()) as pool:
        parts = list(pool.map(_one_grip, range(len(golden_grips()))))
    assert {key: value for part in parts for key, value in part.items()} == reference


@pytest.mark.slow
def test_mujoco_outcomes_repeat_in_a_fresh_process(reference):
    assert _in_a_fresh_process({})[0] == reference


@pytest.mark.slow
def test_mujoco_outcomes_do_not_depend_on_the_cpu_s_kernels(reference):
    """Another machine, as far as one machine can stand in for it: older numpy and OpenBLAS
    kernels, and (second run) numpy's AVX-512 kernels live in a process that imported numpy
    before grip_env, its trials then run in place instead of in the held x86-64-v3 worker."""
    older, _ = _in_a_fresh_process(OTHER_CPU)
    assert older == reference
    if "avx512f" not in Path("/proc/cpuinfo").read_text():
        pytest.skip("no AVX-512 on this CPU")
    first = ("import numpy, grip_env; from grip_env.portable_process import in_place; "
             "in_place().__enter__(); ")
    wide, live = _in_a_fresh_process({"NPY_DISABLE_CPU_FEATURES": None,
                                      "OPENBLAS_CORETYPE": None}, first)
    assert live, "numpy's AVX-512 kernels were not live in the second process"
    assert wide == reference
