"""The cross-check of the standard dataset, resumable (run by hand; issue 45).

    python -m tests.benchmarks.crosscheck_resumable --workers 2 --out runs/crosscheck-40
    python -m tests.benchmarks.crosscheck_resumable --out runs/crosscheck-40 --report R.json

``grip-env validate standard --crosscheck N`` keeps every object's outcomes in memory until the
last is done: stopped early, it leaves nothing. This runs the same work (the same seeded sample,
``grip_env.dataset.crosscheck``'s ``_both_engines`` on every object) but writes each object's
outcomes in both engines to ``OUT`` as soon as it is done, skips objects already there, and with
``--report`` computes the cross-check's figures (its ``_figures``) on the longest finished prefix
of the sample, which is exactly the sample ``--crosscheck`` draws for that many objects.
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse
import dataclasses
import json
from concurrent.futures import ProcessPoolExecutor, as_completed
from datetime import UTC, datetime
from pathlib import Path

import pandas as pd

from grip_env.dataset.backends import worker_context
from grip_env.dataset.crosscheck import _both_engines, _figures, check_crosscheckable
from grip_env.dataset.resimulation import _retest_sample
from grip_env.datasets import standard_path
from grip_env.label_model import ENGINE_LABEL_MODELS


def _files(out: Path, k: int) -> tuple[Path, Path]:
    return out / f"{k:03d}_own.parquet", out / f"{k:03d}_other.parquet"


def run(objects: int, seed: int, workers: int, out: Path) -> None:
    """Simulate every object of the sample not yet in ``out``, saving each as it finishes."""
    directory = standard_path()
    check_crosscheckable(directory)
    checks = _retest_sample(directory, objects, seed)
    out.mkdir(parents=True, exist_ok=True)
    todo = [k for k in range(len(checks)) if not _files(out, k)[1].exists()]
    print(f"{len(checks) - len(todo)} of {len(checks)} objects done; running {len(todo)}",
          flush=True)
    with ProcessPoolExecutor(workers, mp_context=worker_context()) as pool:
        futures = {pool.submit(_both_engines, checks[k]): k for k in todo}
        for future in as_completed(futures):
            k = futures[future]
            own, other = future.result()
            own_file, other_file = _files(out, k)
            own.to_parquet(own_file)
            other.to_parquet(other_file)  # written last: its presence marks the object done
            print(f"{datetime.now(UTC):%H:%M:%S} object {k} ({checks[k].task.object_id}): "
                  f"{len(own)} trials", flush=True)


def report(objects: int, seed: int, out: Path, path: Path) -> None:
    """The cross-check's figures on the longest finished prefix of the sample, as JSON."""
    directory = standard_path()
    engine = check_crosscheckable(directory)
    checks = _retest_sample(directory, objects, seed)
    done = 0
    while done < len(checks) and _files(out, done)[1].exists():
        done += 1
    runs = [tuple(pd.read_parquet(f) for f in _files(out, k)) for k in range(done)]
    figures = _figures(checks[:done], runs, engine, seed)
    found = {"crosscheck": dataclasses.asdict(figures), "summary": figures.summary(),
             "objects_sampled": len(checks), "objects_done": done,
             "object_ids": [c.task.object_id for c in checks[:done]],
             "label_models": ENGINE_LABEL_MODELS, "seed": seed,
             "written": f"{datetime.now(UTC):%Y-%m-%d %H:%M} UTC"}
    path.write_text(json.dumps(found, indent=2, default=float) + "\n")
    print(figures.summary())
    print(f"{done} of {len(checks)} objects")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--report", type=Path, default=None,
                        help="write the figures of the finished objects instead of running")
    args = parser.parse_args()
    if args.report is not None:
        report(args.objects, args.seed, args.out, args.report)
    else:
        run(args.objects, args.seed, args.workers, args.out)


if __name__ == "__main__":
    main()
