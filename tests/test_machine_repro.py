"""The same objects, shapes and contours on another x86-64 CPU (the same dataset on any machine).

A second process stands in for an older CPU: numpy without its AVX2/FMA kernels
(``NPY_DISABLE_CPU_FEATURES``) and OpenBLAS on its SSE kernel (``OPENBLAS_CORETYPE``). Before
label model 2026.12-xm the ellipse's simulated shape kept other vertices there (a BLAS product
broke the ties of its symmetric distances) and a mesh's outline moved by its last bits.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from grip_env.config import Config
from grip_env.mesh_sets import mesh_object, random_urdf_meshes
from grip_env.objects import load_object_set
from grip_env.sim.camera import perceive

OLDER_CPU = {"NPY_DISABLE_CPU_FEATURES": "X86_V3", "OPENBLAS_CORETYPE": "Nehalem"}


def _digest(values: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(values, dtype=float).tobytes()).hexdigest()


def digests() -> dict[str, str]:
    """Hashes of what differed across CPUs: simulated shapes, a render's contour, a mesh outline."""
    config = Config()
    named = {o.name: o for o in load_object_set("default")}
    found = {f"{name} shape": _digest(np.vstack(named[name].simulated_shape().pieces))
             for name in ("ellipse", "bean", "disc")}
    found["ellipse perceived"] = _digest(perceive(named["ellipse"], config.perception).contour)
    mesh = next(p for p in random_urdf_meshes() if p.stem == "459")
    found["urdf_459 outline"] = _digest(mesh_object(mesh, 120.0).contour)
    return found


def _cpu_features() -> dict[str, bool]:
    from numpy._core._multiarray_umath import __cpu_features__

    return {name: bool(on) for name, on in __cpu_features__.items()}


def test_shapes_and_contours_do_not_depend_on_the_cpu_s_vector_kernels():
    if not _cpu_features().get("X86_V3"):
        pytest.skip("this CPU has no X86_V3 (AVX2, FMA) kernels to turn off")
    script = ("import json; from test_machine_repro import digests, _cpu_features; "
              "print(json.dumps([digests(), _cpu_features()['X86_V3']]))")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          env={**os.environ, **OLDER_CPU}, cwd=os.path.dirname(__file__),
                          timeout=300, check=True)
    other, v3 = json.loads(done.stdout.strip().splitlines()[-1])
    assert v3 is False  # the second process really ran on the older kernels
    assert other == digests()
