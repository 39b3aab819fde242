"""A process pool for per-object jobs that can always be stopped and survives a lost worker.

Each worker has its own pipe and runs one object at a time, so the pool knows which object a
worker held when it died (killed, out of memory, crashed): that object is retried once on a
fresh worker, and a second loss raises :class:`WorkerLost` naming it. Leaving the pool on an
exception (an interrupt, a job error) kills the workers at once instead of waiting for them;
a worker whose parent is gone exits by itself.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import threading
from collections import Counter, deque
from collections.abc import Iterable, Iterator
from contextlib import AbstractContextManager, nullcontext, suppress
from dataclasses import dataclass
from multiprocessing.connection import Connection, wait
from types import TracebackType

import pandas as pd

from grip_env.dataset.jobs import ObjectJob, ObjectTask
from grip_env.portable_process import picklable

#: Attempts per object: a worker lost on one is followed by one retry on a fresh worker.
MAX_ATTEMPTS = 2
_JOIN_SECONDS = 2.0

Results = Iterator[tuple[ObjectTask, pd.DataFrame]]


class WorkerLost(RuntimeError):
    """A worker process died (killed, out of memory, crashed) before finishing its object."""


def call_single_threaded(job: ObjectJob, task: ObjectTask) -> pd.DataFrame:
    """Run one job single-threaded: each worker owns one core, so BLAS/OpenMP thread pools
    inside a job would only oversubscribe the machine (measured 1.7x slower on 2 busy cores)."""
    with _one_thread():
        return job(task)


def _one_thread() -> AbstractContextManager[object]:
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        return nullcontext()
    return threadpool_limits(limits=1)


@dataclass
class _Worker:
    process: multiprocessing.process.BaseProcess
    conn: Connection
    alive: Connection
    task: ObjectTask | None = None


class WorkerPool:
    """``size`` worker processes from ``context``; use as a context manager around
    :meth:`results`."""

    def __init__(self, size: int, context: multiprocessing.context.BaseContext) -> None:
        self._context = context
        self._workers = [self._start() for _ in range(size)]

    def __enter__(self) -> WorkerPool:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        if kind is None:
            self.close()
        else:
            self.kill()

    def results(self, job: ObjectJob, tasks: Iterable[ObjectTask]) -> Results:
        """Run ``job`` on every task; yields ``(task, rows)`` in completion order.

        Raises:
            WorkerLost: the same object lost its worker :data:`MAX_ATTEMPTS` times.
            Exception: whatever a job raised, re-raised here.
        """
        queue, retry, attempts = iter(tasks), deque[ObjectTask](), Counter[int]()
        while True:
            for worker in self._workers:
                if worker.task is None:
                    task = retry.popleft() if retry else next(queue, None)
                    if task is None:
                        break
                    self._send(worker, job, task)
            busy = [worker for worker in self._workers if worker.task is not None]
            if not busy:
                return
            ready = set(wait([w.conn for w in busy] + [w.process.sentinel for w in busy]))
            for worker in busy:
                task = worker.task
                if worker.conn in ready and (reply := _receive(worker.conn)) is not None:
                    worker.task = None
                    status, payload = reply
                    if status == "error":
                        raise payload
                    yield task, payload
                elif worker.process.sentinel in ready or worker.conn in ready:
                    attempts[task.index] += 1
                    how = self._replace(worker)
                    if attempts[task.index] >= MAX_ATTEMPTS:
                        raise WorkerLost(
                            f"the worker running object {task.object_id} died {how}, "
                            f"{MAX_ATTEMPTS} times"
                        )
                    retry.append(task)

    def close(self) -> None:
        """Let idle workers exit, then end any that do not."""
        for worker in self._workers:
            try:
                worker.conn.send(None)
            except OSError:
                continue
        for worker in self._workers:
            worker.process.join(_JOIN_SECONDS)
        self.kill()

    def kill(self) -> None:
        """Kill every worker now (their objects are lost) and release the pipes."""
        for worker in self._workers:
            if worker.process.is_alive():
                worker.process.kill()
        for worker in self._workers:
            worker.process.join(_JOIN_SECONDS)
            worker.conn.close()
            worker.alive.close()
        self._workers = []

    def _start(self) -> _Worker:
        ours, theirs = self._context.Pipe(duplex=True)
        watch, alive = self._context.Pipe(duplex=False)
        process = self._context.Process(
            target=_serve, args=(theirs, watch), name="grip-env-worker", daemon=True
        )
        process.start()
        theirs.close()
        watch.close()
        return _Worker(process, ours, alive)

    def _send(self, worker: _Worker, job: ObjectJob, task: ObjectTask) -> None:
        worker.task = task
        with suppress(OSError):  # a dead worker: its sentinel is ready, the task is retried
            worker.conn.send((job, task))

    def _replace(self, worker: _Worker) -> str:
        """Swap a dead worker for a fresh one; returns how it died."""
        if worker.process.is_alive():
            worker.process.kill()
        worker.process.join(_JOIN_SECONDS)
        how = _how_it_ended(worker.process.exitcode)
        worker.conn.close()
        worker.alive.close()
        fresh = self._start()
        worker.process, worker.conn, worker.alive, worker.task = (
            fresh.process, fresh.conn, fresh.alive, None
        )
        return how


def _receive(conn: Connection) -> tuple[str, object] | None:
    """A worker's reply, or None when its pipe broke (the worker died)."""
    try:
        return conn.recv()
    except (EOFError, OSError):
        return None


def _how_it_ended(code: int | None) -> str:
    if code is None:
        return "(still running)"
    if code < 0:
        return f"(killed by {signal.Signals(-code).name})"
    return f"(exit code {code})"


def _serve(conn: Connection, watch: Connection) -> None:
    """A worker's loop: run jobs until told to stop, the pipe closes or the parent is gone."""
    for name in ("SIGINT", "SIGHUP"):  # the parent decides when to stop, and stops us
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_IGN)
    threading.Thread(target=_exit_when_orphaned, args=(watch,), daemon=True).start()
    while True:
        try:
            message = conn.recv()
        except (EOFError, OSError):
            return
        if message is None:
            return
        job, task = message
        try:
            reply = ("ok", call_single_threaded(job, task))
        except Exception as exc:  # the parent re-raises it
            reply = ("error", picklable(exc))
        conn.send(reply)


def _exit_when_orphaned(watch: Connection) -> None:
    """Block until the parent's end of ``watch`` closes (the parent died), then exit now."""
    with suppress(EOFError, OSError):
        watch.recv()
    os._exit(1)


