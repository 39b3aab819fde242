"""Planning and trials computed where the kernels are portable, whatever the import order.

numpy and OpenBLAS pick their kernels when they load (:mod:`grip_env.portable_math`). When numpy
was loaded before grip_env on an AVX-512 CPU (``import gymnasium, grip_env``), this process's
``arctan2``, ``arccos``, ``exp``, ``power``, ``log1p`` and OpenBLAS's ``dot`` round otherwise than
the x86-64-v3 kernels every label was made with, and planning and a grip's closing amplify that
into other candidates and other outcomes (BENCHMARKS.md, "Import order"). The functions marked
:func:`portable` (:func:`~grip_env.planning.pipeline.candidates`,
:func:`~grip_env.sim.camera.perceive`, :func:`~grip_env.sim.execution.run_trial_outcomes`,
:func:`~grip_env.sim.execution.run_trials`) then run in one worker process held at x86-64-v3,
single-threaded like a dataset worker: started on the first such call, kept for the next ones,
stopped when this process exits. Arguments and results travel pickled; an exception raised there
is raised here with its own type (the worker's traceback as a note), and its warnings are issued
here. In a process whose kernels are portable (grip_env imported first) they run in place, and
so they do where no worker can be started (not POSIX), with a warning.
"""

from __future__ import annotations

import atexit
import contextlib
import contextvars
import functools
import inspect
import os
import socket
import subprocess
import sys
import threading
import traceback
import warnings
from collections.abc import Callable, Iterator
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any, TypeVar

from grip_env.portable_math import math_is_portable

__all__ = ["in_place", "portable", "stop_worker"]

_Function = TypeVar("_Function", bound=Callable[..., Any])
_STOP_SECONDS = 5.0
_SERVE = "import sys; from grip_env.portable_process import serve; serve(int(sys.argv[1]))"
_forced_here = contextvars.ContextVar("grip_env_forced_here", default=False)
_serving = False  # true in the worker itself
_lock = threading.Lock()
_running: _Worker | None = None  # this process's worker, once started


def portable(
    function: _Function | None = None, *, stays_here: tuple[str, ...] = ()
) -> Any:
    """Mark ``function`` (a module-level function) to run where the kernels are portable: here
    when they are, else in the held worker. Arguments named in ``stays_here`` are caches bound
    to this process (a PyBullet world): the worker is passed None for them."""
    if function is None:
        return functools.partial(portable, stays_here=stays_here)
    signature = inspect.signature(function)

    @functools.wraps(function)
    def run(*args: Any, **kwargs: Any) -> Any:
        if _runs_here():
            return function(*args, **kwargs)
        if stays_here:
            bound = signature.bind(*args, **kwargs)
            bound.arguments.update({name: None for name in stays_here if name in bound.arguments})
            args, kwargs = bound.args, bound.kwargs
        return _call(run, args, kwargs)

    return run


@contextlib.contextmanager
def in_place() -> Iterator[None]:
    """Run :func:`portable` functions in this process within the block, whatever its kernels
    (for measuring what the non-portable kernels would give)."""
    token = _forced_here.set(True)
    try:
        yield
    finally:
        _forced_here.reset(token)


def stop_worker() -> None:
    """Stop the held worker if one runs (done at exit; the next portable call starts another)."""
    global _running
    with _lock:
        if _running is not None:
            _running.stop()
            _running = None


def _runs_here() -> bool:
    return _serving or _forced_here.get() or _portable_here()


@functools.cache
def _portable_here() -> bool:
    """Whether this process's kernels are portable (picked at load: they do not change after),
    or no worker can be started here (not POSIX: then it says so, once)."""
    if math_is_portable():
        return True
    if os.name != "posix":  # the worker's socket is passed as an inherited descriptor
        warnings.warn("numpy's kernels beyond x86-64-v3 are live (numpy was imported before "
                      "grip_env) and no held worker runs on this platform: candidates and trial "
                      "outcomes computed here may differ from other machines'; import grip_env "
                      "first", RuntimeWarning, stacklevel=4)
        return True
    return False


class _Worker:
    """One held interpreter serving calls over a socket, one at a time."""

    def __init__(self) -> None:
        mine, theirs = socket.socketpair()
        try:
            self.process = subprocess.Popen(
                [sys.executable, "-c", _SERVE, str(theirs.fileno())], pass_fds=[theirs.fileno()],
                env=_worker_environment(), stdout=_worker_output(),
                start_new_session=True)  # Ctrl-C interrupts the caller, which stops the worker
        finally:
            theirs.close()
        self.pid = os.getpid()
        self.connection = Connection(mine.detach())

    def call(self, function: Callable[..., Any], args: tuple, kwargs: dict) -> Any:
        try:
            self.connection.send((function, args, kwargs))
            reply, caught = self.connection.recv()
        except (EOFError, OSError):
            code = self.process.wait()
            raise RuntimeError(f"the x86-64-v3 worker running {function.__name__} died (exit "
                               f"code {code}); the next call starts another") from None
        for message, category, filename, lineno in caught:
            warnings.warn_explicit(message, category, filename, lineno)
        kind, value, remote = reply
        if kind == "error":
            value.add_note(f"raised in the x86-64-v3 worker (grip_env.portable_process):\n{remote}")
            raise value
        return value

    def alive(self) -> bool:
        return self.process.poll() is None

    def stop(self, kill: bool = False) -> None:
        """Close the worker's input (it exits when idle), killing it after
        :data:`_STOP_SECONDS`, or at once with ``kill``."""
        self.connection.close()
        if kill:
            self.process.kill()
        try:
            self.process.wait(_STOP_SECONDS)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


def _call(function: Callable[..., Any], args: tuple, kwargs: dict) -> Any:
    """``function(*args, **kwargs)`` in the worker, started when none runs for this process. An
    interrupted call kills the worker, so that no stale reply is left for the next call."""
    global _running
    with _lock:
        if _running is None or _running.pid != os.getpid() or not _running.alive():
            _running = _Worker()  # the first call, a forked copy's, or after a lost worker
        worker = _running
        try:
            return worker.call(function, args, kwargs)
        except BaseException as exc:
            if not isinstance(exc, Exception) or not worker.alive():
                worker.stop(kill=True)
                _running = None
            raise


def _worker_output() -> int:
    """Where the worker's own output goes: this process's error stream (so that nothing it
    prints mixes with this process's output), else nowhere."""
    try:
        return sys.__stderr__.fileno()  # type: ignore[union-attr]
    except (AttributeError, OSError, ValueError):
        return subprocess.DEVNULL


def _worker_environment() -> dict[str, str]:
    """This process's environment (held at x86-64-v3 by ``import grip_env``), with grip_env's
    own directory first on the path."""
    package_root = str(Path(__file__).resolve().parents[1])
    path = os.pathsep.join([package_root, *filter(None, [os.environ.get("PYTHONPATH")])])
    return {**os.environ, "PYTHONPATH": path}


def serve(descriptor: int) -> None:
    """The worker's loop: run each call received on socket ``descriptor``, send its reply, until
    the caller closes it."""
    global _serving
    from threadpoolctl import threadpool_limits

    _serving = True
    connection = Connection(descriptor)
    with threadpool_limits(1):  # one core, as a dataset worker
        while True:
            try:
                function, args, kwargs = connection.recv()
            except EOFError:
                return
            reply = _reply(function, args, kwargs)
            try:
                connection.send(reply)
            except OSError:  # the caller is gone
                return
            except Exception as exc:  # a result that does not pickle
                connection.send((("error", picklable(exc), traceback.format_exc()), []))


def _reply(function: Callable[..., Any], args: tuple, kwargs: dict) -> tuple:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            reply: tuple = ("result", function(*args, **kwargs), "")
        except Exception as exc:  # raised again in the caller
            reply = ("error", picklable(exc), traceback.format_exc())
    notes = [(str(w.message), w.category, w.filename, w.lineno) for w in caught]
    return reply, notes


def picklable(exc: Exception) -> Exception:
    """``exc`` if it survives pickling (to be raised again in another process), else a
    RuntimeError with its type and message."""
    import pickle

    try:
        pickle.loads(pickle.dumps(exc))
    except Exception:
        return RuntimeError(f"{type(exc).__name__}: {exc}")
    return exc


atexit.register(stop_worker)
