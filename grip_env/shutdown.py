"""Clean shutdown of long commands on SIGINT, SIGTERM and SIGHUP.

A command wraps its work in :func:`stop_on_signals`. The first of these signals raises
:class:`Interrupted` (a ``KeyboardInterrupt``) in the main thread, so ``finally`` blocks and
context managers stop worker pools, Ray and PyBullet on the way out. Then every process this
one started that is still alive is ended, one line is printed and the process exits with
``128 + signal number``: 130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP. A watchdog makes the
whole shutdown take at most :data:`SHUTDOWN_SECONDS`, whatever the work was doing.

Work that must not be cut in two (a shard written and entered in the manifest) runs inside
:func:`deferred_signals`: a signal that arrives there takes effect when the block ends.

The handler raises :class:`Interrupted` wherever the main thread is, and library code that runs
Python from C can lose it there: numpy clears it when it lands in ``npy_ctypes_check``, which
comparing a dtype with pandas' string dtype calls (every ``groupby`` on a string column), and
turns it into a ``ValueError`` when it parses a buffer's format (scikit-learn's gradient boosting,
every tree); scikit-learn's MLP catches it to end training early. The work would then run on
until the watchdog kills it. So a loop of jobs calls :func:`raise_if_signalled` between jobs,
and a signal the work never saw still ends the command with its exit code.

A signal that lands while a module is being imported is held until the import ends: an
extension's import runs Python from C++ (torch's ``_c10d_init``), and an exception raised there
cannot unwind, so the process would abort (SIGABRT) instead of stopping cleanly.

>>> with stop_on_signals("rerun the same command to finish"):   # doctest: +SKIP
...     long_work()
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from types import FrameType

#: Signals a long command stops cleanly on.
SIGNALS: tuple[signal.Signals, ...] = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
)
#: Longest time from the signal to the exit; children still alive then are killed.
SHUTDOWN_SECONDS = 4.0
#: Time children get to end on SIGTERM before they are killed.
CHILD_GRACE_SECONDS = 0.5


def exit_code(signum: int) -> int:
    """The documented exit code after signal ``signum``: ``128 + signum`` (130, 143, 129)."""
    return 128 + int(signum)


class Interrupted(KeyboardInterrupt):
    """The command received a stop signal; raised in the main thread by :func:`stop_on_signals`."""

    def __init__(self, signum: int) -> None:
        self.signum = int(signum)
        super().__init__(signal.Signals(signum).name)

    @property
    def exit_code(self) -> int:
        return exit_code(self.signum)


class _State:
    """What the installed handler knows: whether to defer, and the first signal received."""

    def __init__(self) -> None:
        self.active = False
        self.deferring = 0
        self.pending: int | None = None
        self.stopping = False
        self.held_in_import = False


_STATE = _State()


@contextmanager
def stop_on_signals(advice: str = "") -> Iterator[None]:
    """Run a command's work so that SIGINT, SIGTERM and SIGHUP stop it cleanly.

    On a signal: the work unwinds (its ``finally`` blocks run), child processes still alive are
    ended, ``interrupted by SIGTERM: stopped cleanly; <advice>`` goes to stderr on one line and
    ``SystemExit(128 + signum)`` is raised. Outside the main thread it only runs the work.
    """
    if _STATE.active or threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {signum: signal.getsignal(signum) for signum in SIGNALS}
    _STATE.__init__()
    _STATE.active = True
    for signum in SIGNALS:
        signal.signal(signum, _on_signal)
    try:
        yield
        raise_if_signalled()  # a signal the work lost still ends the command
    except BaseException as exc:
        signum = exc.signum if isinstance(exc, Interrupted) else _STATE.pending
        if signum is None or isinstance(exc, SystemExit):
            raise
        _STATE.stopping = True
        end_children()
        _say(f"interrupted by {signal.Signals(signum).name}: stopped cleanly"
             + (f"; {advice}" if advice else ""))
        raise SystemExit(exit_code(signum)) from None
    finally:
        _STATE.deferring += 1  # a signal from here on is only recorded: the work is over
        # after a signal the watchdog stays armed until the process has exited, so that
        # exit handlers (Ray's shutdown talking to processes the signal killed) cannot hang it
        for signum, handler in previous.items():  # None: installed outside Python
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)
        _STATE.__init__()


@contextmanager
def deferred_signals() -> Iterator[None]:
    """Hold a stop signal until the block ends (no-op outside :func:`stop_on_signals`)."""
    _STATE.deferring += 1
    try:
        yield
    finally:
        _STATE.deferring -= 1
    if _STATE.deferring == 0 and _STATE.pending is not None and not _STATE.stopping:
        _STATE.stopping = True
        raise Interrupted(_STATE.pending)


def raise_if_signalled() -> None:
    """Raise :class:`Interrupted` if a stop signal has come (outside :func:`deferred_signals`).

    A checkpoint for loops of jobs: a signal that library code lost (see the module docstring)
    stops the work at the next job instead of at the watchdog. A no-op without a signal.
    """
    if _STATE.pending is not None and _STATE.deferring == 0:
        _STATE.stopping = True
        raise Interrupted(_STATE.pending)


def _on_signal(signum: int, frame: FrameType | None) -> None:
    if _STATE.pending is None:
        _STATE.pending = signum
        _start_watchdog(exit_code(signum))
    elif not _STATE.held_in_import:
        return  # already stopping: the first signal decides the exit code
    if _STATE.deferring or _STATE.stopping:
        return
    if _importing(frame):
        if not _STATE.held_in_import:
            _STATE.held_in_import = True
            _deliver_after_import(_STATE.pending)
        return
    _STATE.held_in_import = False
    _STATE.stopping = True
    raise Interrupted(_STATE.pending)


def _importing(frame: FrameType | None) -> bool:
    """Whether ``frame`` runs inside an import (below one of importlib's frames)."""
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib"):
            return True
        frame = frame.f_back
    return False


def _deliver_after_import(signum: int) -> None:
    """Send ``signum`` to the main thread again once it has left every import (the watchdog
    still bounds the wait)."""
    main = threading.main_thread().ident

    def watch() -> None:
        while _importing(sys._current_frames().get(main)):  # type: ignore[arg-type]
            time.sleep(0.02)
        with suppress(ProcessLookupError, OSError):  # the main thread already gone
            signal.pthread_kill(main, signum)  # type: ignore[arg-type]

    threading.Thread(target=watch, name="signal-after-import", daemon=True).start()


def _start_watchdog(code: int) -> None:
    """Kill the children and exit with ``code`` if this process still runs after
    :data:`SHUTDOWN_SECONDS` (it is a daemon thread: a process that exits in time ends it)."""

    def watch() -> None:
        time.sleep(SHUTDOWN_SECONDS)
        end_children(grace=0.0)
        _say("interrupted: shutdown took too long, stopped by force")
        os._exit(code)

    threading.Thread(target=watch, name="shutdown-watchdog", daemon=True).start()


def end_children(grace: float = CHILD_GRACE_SECONDS) -> None:
    """End every descendant process still alive: SIGTERM, ``grace`` seconds, then SIGKILL."""
    ended = alive = descendants()
    if grace > 0:
        _send(alive, signal.SIGTERM)
        deadline = time.monotonic() + grace
        while alive and time.monotonic() < deadline:
            time.sleep(0.02)
            _reap(ended)
            alive = [pid for pid in alive if _exists(pid)]
    _send(alive, signal.SIGKILL)
    _reap(ended)


def descendants(root: int | None = None) -> list[int]:
    """Process ids of every descendant of ``root`` (this process by default), still running."""
    root = os.getpid() if root is None else root
    parents = _parent_map()
    if parents is None:
        import multiprocessing

        return [p.pid for p in multiprocessing.active_children() if p.pid is not None]
    found, frontier = [], [root]
    while frontier:
        parent = frontier.pop()
        children = [pid for pid, ppid in parents.items() if ppid == parent]
        found += children
        frontier += children
    return found


def _parent_map() -> dict[int, int] | None:
    """Running (not zombie) process id -> parent id, from /proc; None where there is no /proc."""
    proc = Path("/proc")
    if not (proc / "self" / "stat").exists():
        return None
    parents = {}
    for entry in proc.iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        state, ppid = stat[stat.rindex(")") + 2:].split()[:2]
        if state not in ("Z", "X"):
            parents[int(entry.name)] = int(ppid)
    return parents


def _exists(pid: int) -> bool:
    parents = _parent_map()
    if parents is not None:
        return pid in parents
    try:
        os.kill(pid, 0)
    except OSError:
        return False
    return True


def _send(pids: list[int], signum: int) -> None:
    for pid in pids:
        try:
            os.kill(pid, signum)
        except OSError:
            continue


def _reap(pids: list[int]) -> None:
    """Collect those of ``pids`` that are exited children of this process (no zombie left)."""
    for pid in pids:
        try:
            os.waitpid(pid, os.WNOHANG)
        except (ChildProcessError, OSError):
            continue


def _say(line: str) -> None:
    """``line`` on a line of its own, even after an open progress bar's unfinished one."""
    with suppress(OSError, ValueError):  # the terminal may be gone (SIGHUP)
        start = ""
        if _progress_bar_open():
            start = "\r\033[K" if sys.stderr.isatty() else "\n"
        print(start + line, file=sys.stderr, flush=True)


def _progress_bar_open() -> bool:
    """Whether a tqdm bar is on screen (tqdm is looked at only if something imported it)."""
    module = sys.modules.get("tqdm")
    bars = getattr(getattr(module, "tqdm", None), "_instances", ()) if module else ()
    return any(not getattr(bar, "disable", True) for bar in list(bars))
