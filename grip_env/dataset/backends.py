"""Running per-object jobs: in-process, on a local process pool, or as Ray tasks.

Every backend yields ``(task, rows)`` pairs as jobs finish, keeping only a bounded number of
jobs in flight, so the caller can store each result as soon as it arrives. Leaving a backend
early (an interrupt, an error) stops its processes before the exception goes on.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
from collections.abc import Iterable, Iterator
from contextlib import contextmanager

import pandas as pd

from grip_env.dataset.jobs import ObjectJob, ObjectTask
from grip_env.dataset.pool import WorkerLost, WorkerPool, call_single_threaded
from grip_env.portable_math import math_is_portable

BACKENDS = ("process", "ray")
_IN_FLIGHT_PER_WORKER = 2
_PRELOAD = (
    "grip_env.dataset.jobs", "grip_env.dataset.pool", "grip_env.planning.pipeline", "grip_env.sim",
    "pyarrow",
)
#: Ray re-runs a task whose worker process died this many times before giving up.
RAY_TASK_RETRIES = 2
_RAY_POLL_SECONDS = 0.5
#: The environment variable naming the Ray cluster to join (Ray's own convention).
RAY_ADDRESS_VARIABLE = "RAY_ADDRESS"

Results = Iterator[tuple[ObjectTask, pd.DataFrame]]

__all__ = ["BACKENDS", "WorkerLost", "check_backend", "in_this_process", "ray_address", "run_jobs",
           "worker_context"]


def check_backend(backend: str, workers: int) -> None:
    """Raise ``ValueError`` for an unknown backend, backend ``"ray"`` without Ray installed, or
    a worker count below 1: before a run writes anything."""
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r}; choose from {', '.join(BACKENDS)}")
    if backend == "ray":
        _import_ray()
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")


def run_jobs(
    job: ObjectJob, tasks: Iterable[ObjectTask], workers: int, backend: str = "process",
    address: str | None = None,
) -> Results:
    """Run ``job`` on every task; yields ``(task, rows)`` in completion order.

    ``backend="process"`` with one worker runs in this process (unless its math is not
    portable: :func:`in_this_process`); with more it uses a
    :class:`~grip_env.dataset.pool.WorkerPool` of 'forkserver' (or 'spawn') processes, each
    with its own PyBullet client. ``backend="ray"`` submits Ray tasks to the cluster at
    ``address`` (else ``$RAY_ADDRESS``; a local Ray instance with ``workers`` CPUs when neither
    is set) and keeps ``2 x max(workers, the cluster's CPUs)`` in flight; Ray re-runs a task
    whose worker died up to :data:`RAY_TASK_RETRIES` times.

    Raises:
        WorkerLost: an object lost its worker on every attempt.
    """
    check_backend(backend, workers)
    if backend == "ray":
        return _ray_results(job, tasks, workers, address)
    if in_this_process(workers):
        return ((task, call_single_threaded(job, task)) for task in tasks)
    return _pool_results(job, tasks, workers)


def in_this_process(workers: int) -> bool:
    """Whether labels for ``workers`` workers are made in this process: for one worker, when
    this process computes with x86-64-v3 kernels (:mod:`grip_env.portable_math`); else one
    worker process, held at x86-64-v3, makes them, so that they are every machine's labels."""
    return workers == 1 and math_is_portable()


def worker_context() -> multiprocessing.context.BaseContext:
    """'forkserver' (workers fork from a clean server with the heavy imports done) where it
    exists, else 'spawn'. Neither copies a live PyBullet client, nor numpy's kernels, into a
    worker: each starts a fresh interpreter that imports grip_env first."""
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(list(_PRELOAD))
    return context


def _pool_results(job: ObjectJob, tasks: Iterable[ObjectTask], workers: int) -> Results:
    with WorkerPool(workers, worker_context()) as pool:
        yield from pool.results(job, tasks)


def _ray_results(
    job: ObjectJob, tasks: Iterable[ObjectTask], workers: int, address: str | None
) -> Results:
    ray = _import_ray()
    started_here = not ray.is_initialized()
    try:
        if started_here:
            _start_ray(ray, workers, address)
        capacity = max(workers, int(ray.cluster_resources().get("CPU", workers)))
        remote_job = ray.remote(num_cpus=1, max_retries=RAY_TASK_RETRIES)(call_single_threaded)
        queue = iter(tasks)
        running: dict[object, ObjectTask] = {}
        while True:
            for task in _take(queue, capacity * _IN_FLIGHT_PER_WORKER - len(running)):
                running[remote_job.remote(job, task)] = task
            if not running:
                return
            # with a timeout, so that a stop signal is acted on between waits
            done, _ = ray.wait(list(running), num_returns=1, timeout=_RAY_POLL_SECONDS)
            for ref in done:
                task = running.pop(ref)
                yield task, _ray_get(ray, ref, task)
    finally:
        if started_here and ray.is_initialized():
            ray.shutdown()


def _ray_get(ray, ref: object, task: ObjectTask) -> pd.DataFrame:  # type: ignore[no-untyped-def]
    try:
        return ray.get(ref)
    except (ray.exceptions.WorkerCrashedError, ray.exceptions.NodeDiedError) as exc:
        raise WorkerLost(
            f"the Ray worker running object {task.object_id} died "
            f"{RAY_TASK_RETRIES + 1} times ({type(exc).__name__})"
        ) from None


def _take(queue: Iterator[ObjectTask], count: int) -> list[ObjectTask]:
    taken = []
    for _ in range(max(count, 0)):
        task = next(queue, None)
        if task is None:
            break
        taken.append(task)
    return taken


def _import_ray():  # type: ignore[no-untyped-def]
    try:
        import ray
    except ImportError:
        raise ValueError(
            "backend 'ray' needs Ray: pip install 'grip-env[cluster]'"
        ) from None
    return ray


def ray_address(address: str | None) -> str | None:
    """The cluster to join: ``address``, else the ``RAY_ADDRESS`` environment variable, else
    None (a new local instance). ``grip-env study`` and ``calibrate`` reach a cluster this way."""
    return address or os.environ.get(RAY_ADDRESS_VARIABLE) or None


def _start_ray(ray, workers: int, address: str | None) -> None:  # type: ignore[no-untyped-def]
    options = {"include_dashboard": False, "log_to_driver": False, "configure_logging": False}
    # ray.init(num_cpus=...) refuses to join the cluster RAY_ADDRESS names: join it explicitly
    address = ray_address(address)
    try:
        with _signal_handlers_kept():
            if address is None:
                ray.init(num_cpus=workers, **options)
            else:
                ray.init(address=address, **options)
    except (ConnectionError, RuntimeError, ValueError) as exc:
        where = address or "a local instance"
        raise ValueError(f"cannot start Ray on {where}: {exc}") from None


@contextmanager
def _signal_handlers_kept() -> Iterator[None]:
    """Undo the SIGTERM handler ``ray.init`` installs (it exits without stopping the run)."""
    signals = [getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n)]
    kept = {signum: signal.getsignal(signum) for signum in signals}
    try:
        yield
    finally:
        for signum, handler in kept.items():
            if handler is not None:
                signal.signal(signum, handler)
