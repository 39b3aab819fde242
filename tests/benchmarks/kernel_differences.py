"""Which numpy calls on the planning and trial path give other bits under numpy's AVX-512 kernels?
(BENCHMARKS.md, "Import order"). Run by hand, on a CPU with AVX-512:

    python -m tests.benchmarks.kernel_differences --objects 10

A process held at x86-64-v3 (grip_env imported first) plans a seeded sample of the standard
dataset's objects (perception from the render, candidates) and runs one trial of two of each
object's grips, recording every call of numpy's floating-point functions with its arguments and
result. A process with the AVX-512 kernels live (numpy imported first, so nothing is delegated
either: the functions are called unwrapped) replays each recorded call and counts the calls whose
result differs in any bit; it also plans the same objects itself and counts the stages whose
products differ. Calls through operators (``a @ b``, ``x ** y``, ``.sum()``) are not seen one by
one: the stage counts include them. Beforehand, both processes compute each function on 200,000
seeded random inputs, and the results that differ are counted.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import pickle
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

#: numpy functions whose float results could depend on the kernels (transcendentals, roots,
#: reductions, BLAS and LAPACK).
TRACED = ("sin", "cos", "tan", "arcsin", "arccos", "arctan", "arctan2", "sinh", "cosh", "tanh",
          "exp", "expm1", "exp2", "log", "log1p", "log2", "log10", "power", "sqrt", "cbrt",
          "hypot", "degrees", "radians", "sum", "mean", "std", "cumsum", "median", "interp",
          "unwrap", "dot", "matmul", "einsum", "cross", "trace", "linalg.norm", "linalg.det",
          "linalg.eigh", "linalg.eigvalsh", "linalg.matrix_rank", "linalg.solve", "linalg.inv",
          "linalg.svd", "linalg.lstsq")
_KEPT_PER_NAME = 4000


def _probe_results() -> dict[str, bytes]:
    """Each kernel-dependent candidate on seeded random inputs, as bytes."""
    import numpy as np

    rng = np.random.default_rng(0)
    x, u = rng.uniform(-10, 10, 200_000), rng.uniform(-1, 1, 200_000)
    p = rng.uniform(0, 1e3, 200_000)
    sizes = range(1, 3000, 7)
    cases = {
        "sin": lambda: np.sin(x), "cos": lambda: np.cos(x), "tan": lambda: np.tan(x),
        "arcsin": lambda: np.arcsin(u), "arccos": lambda: np.arccos(u),
        "arctan": lambda: np.arctan(x), "arctan2": lambda: np.arctan2(x, u),
        "exp": lambda: np.exp(x), "expm1": lambda: np.expm1(x), "log": lambda: np.log(p),
        "log1p": lambda: np.log1p(p), "power": lambda: np.power(p, u), "cbrt": lambda: np.cbrt(x),
        "sqrt": lambda: np.sqrt(p), "hypot": lambda: np.hypot(x, u), "tanh": lambda: np.tanh(x),
        "sum (1..2994 terms)": lambda: np.array([x[:k].sum() for k in sizes]),
        "dot (1..2994 terms)": lambda: np.array([x[:k] @ u[:k] for k in sizes]),
        "(n, 3) @ (3, 3)": lambda: x[:199_998].reshape(-1, 3) @ u[:9].reshape(3, 3),
        "(n, 2) @ (2, 2)": lambda: x.reshape(-1, 2) @ u[:4].reshape(2, 2),
        "(n, 3) @ (3,)": lambda: x[:199_998].reshape(-1, 3) @ u[:3],
    }
    return {name: case().tobytes() for name, case in cases.items()}


def _count_differing(held: dict[str, bytes], live: dict[str, bytes]) -> dict[str, list[int]]:
    import numpy as np

    counts = {}
    for name, bits in held.items():
        a, b = np.frombuffer(bits), np.frombuffer(live[name])
        counts[name] = [int((a.view(np.uint64) != b.view(np.uint64)).sum()), len(a)]
    return counts


def _target(np, name: str):  # type: ignore[no-untyped-def]
    owner = np.linalg if name.startswith("linalg.") else np
    return owner, name.removeprefix("linalg.")


def _trace(np, calls: list, counts: Counter) -> None:  # type: ignore[no-untyped-def]
    for name in TRACED:
        owner, attribute = _target(np, name)
        original = getattr(owner, attribute)

        def traced(*args, __name=name, __original=original, **kwargs):  # type: ignore[no-untyped-def]
            result = __original(*args, **kwargs)
            counts[__name] += 1
            if counts[__name] <= _KEPT_PER_NAME and "out" not in kwargs:
                with contextlib.suppress(Exception):  # what does not pickle is not replayed
                    calls.append((__name, pickle.dumps((args, kwargs)), pickle.dumps(result)))
            return result

        setattr(owner, attribute, traced)


def _path(objects: int, planned: dict | None = None) -> tuple[dict[str, str], dict]:
    """Plan a sample of standard objects and run a trial of two grips each (the ``planned``
    ones when given, so that the trials' inputs are the same bits); a digest per stage, and the
    grips simulated."""
    import hashlib

    import numpy as np

    from grip_env import datasets
    from grip_env.dataset.jobs import planning_contour
    from grip_env.dataset.resimulation import _sample
    from grip_env.mesh_sets import named_set
    from grip_env.planning.pipeline import candidates
    from grip_env.sim.execution import run_trial_outcomes

    def digest(*arrays) -> str:  # type: ignore[no-untyped-def]
        return hashlib.sha256(b"".join(np.ascontiguousarray(a).tobytes() for a in arrays)
                              ).hexdigest()[:16]

    simulated = {}
    found = {"default set": digest(*[o.contour for o in named_set("default").objects])}
    for check in _sample(datasets.standard_path(), objects * 5, seed=0):
        task, config = check.task, check.task.config
        contour = planning_contour(task)
        table = candidates(contour, config.grasp, config)
        found[f"{task.object_id} perceived"] = digest(contour.contour)
        numeric = table.select_dtypes("number").to_numpy(float)
        found[f"{task.object_id} candidates"] = digest(numeric)
        grips = table.head(2).assign(object_id=task.object_id)
        grips = simulated[task.object_id] = grips if planned is None else planned[task.object_id]
        trials = run_trial_outcomes(task.obj, grips, config, 1, 0)
        found[f"{task.object_id} trials"] = digest(trials.select_dtypes("number").to_numpy(float))
    return found, simulated


def record(objects: int, out: Path) -> None:
    import numpy as np  # after grip_env (tests.benchmarks imports it): held at x86-64-v3

    from grip_env.portable_math import live_beyond_v3

    probe = _probe_results()  # before the tracing: not calls of the path
    calls: list = []
    counts: Counter = Counter()
    _trace(np, calls, counts)
    stages, simulated = _path(objects)
    out.write_bytes(pickle.dumps({"live": live_beyond_v3(), "calls": calls, "counts": counts,
                                  "stages": stages, "simulated": simulated, "probe": probe}))


def replay(objects: int, recorded: Path) -> dict:
    import numpy as np  # first: numpy's AVX-512 kernels live

    from grip_env.portable_math import live_beyond_v3

    held = pickle.loads(recorded.read_bytes())
    probe = _count_differing(held["probe"], _probe_results())
    differing: Counter = Counter()
    replayed: Counter = Counter()
    for name, arguments, result in held["calls"]:
        owner, attribute = _target(np, name)
        args, kwargs = pickle.loads(arguments)
        again = getattr(owner, attribute)(*args, **kwargs)
        replayed[name] += 1
        differing[name] += not _same_bits(pickle.loads(result), again)
    stages = _unwrapped_path(objects, held["simulated"])
    moved = sorted(k for k in held["stages"] if held["stages"][k] != stages.get(k))
    return {
        "held": held["live"], "live": live_beyond_v3(), "probe": probe,
        "calls": {name: {"calls": held["counts"][name], "replayed": replayed[name],
                         "differ": differing[name]} for name in sorted(held["counts"])},
        "stages": len(held["stages"]), "stages differing": moved,
    }


def _unwrapped_path(objects: int, planned: dict) -> dict[str, str]:
    """:func:`_path` in this process whatever its kernels (nothing delegated to a held worker)."""
    try:
        from grip_env import portable_process
    except ImportError:  # before the portable worker existed
        return _path(objects, planned)[0]
    with portable_process.in_place():
        return _path(objects, planned)[0]


def _same_bits(a: object, b: object) -> bool:
    import numpy as np

    if isinstance(a, tuple | list):
        return len(a) == len(b) and all(_same_bits(x, y) for x, y in zip(a, b, strict=True))
    if hasattr(a, "_fields") or type(a).__name__.endswith("Result"):
        return _same_bits(tuple(a), tuple(b))
    x, y = np.asarray(a), np.asarray(b)
    return x.shape == y.shape and x.dtype == y.dtype and x.tobytes() == y.tobytes()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", type=int, default=10, help="standard objects to plan")
    parser.add_argument("--record", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--replay", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.record:
        return record(args.objects, args.record)
    if args.replay:
        return print(json.dumps(replay(args.objects, args.replay)))
    env = {k: v for k, v in os.environ.items()
           if k not in ("NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE")}
    module = [sys.executable, "-m", "tests.benchmarks.kernel_differences"]
    numpy_first = [sys.executable, "-c", "import numpy; from tests.benchmarks.kernel_differences "
                   "import main; main()"]  # (tests.benchmarks imports grip_env)
    with tempfile.TemporaryDirectory() as directory:
        calls = Path(directory) / "calls.pickle"
        subprocess.run([*module, "--objects", str(args.objects), "--record", str(calls)],
                       env=env, check=True)
        done = subprocess.run(
            [*numpy_first, "--objects", str(args.objects), "--replay", str(calls)], env=env,
            check=True, capture_output=True, text=True)
    found = json.loads(done.stdout.strip().splitlines()[-1])
    print(f"held: {found['held'] or 'x86-64-v3'}; live: {', '.join(found['live'])}")
    print("seeded random inputs: results that differ")
    for name, (differ, count) in found["probe"].items():
        print(f"  {name:22} {differ:8} of {count}")
    print("calls on the path (planning and one trial of two grips an object)")
    print(f"{'function':22} {'calls':>8} {'replayed':>8} {'differ':>8}")
    for name, row in found["calls"].items():
        print(f"{name:22} {row['calls']:8} {row['replayed']:8} {row['differ']:8}")
    moved = found["stages differing"]
    print(f"stages whose products differ: {len(moved)} of {found['stages']}: {', '.join(moved)}")


if __name__ == "__main__":
    main()
