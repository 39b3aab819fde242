"""One progress display for every long job: a rich bar on stderr, or nothing.

Library calls show nothing unless asked; the CLI's long commands turn bars on with
:func:`shown`, and a job then opens one with :func:`progress_bar`. A bar opened inside another
(a cross-validation inside the ablation, say) stays silent, so a command shows one bar at a time.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any

_SHOWN: ContextVar[bool] = ContextVar("grip_env_progress_shown", default=False)
_OPEN: ContextVar[bool] = ContextVar("grip_env_progress_open", default=False)


#: Seconds between the plain progress lines written when stderr is not a terminal (a log file).
LOG_SECONDS = 30.0


class Bar:
    """A handle on an open bar: ``advance`` it as work completes (a no-op when not shown).

    On a terminal the bar redraws in place; into a file or pipe, where rich draws only the
    final state, a plain line is written at most every ``LOG_SECONDS``.
    """

    def __init__(self, progress: Any = None, task: Any = None) -> None:
        self._progress, self._task = progress, task
        self._logged = time.monotonic()

    def advance(self, steps: int = 1, info: str | None = None) -> None:
        """Count ``steps`` more done; ``info`` replaces the text after the bar (e.g. a rate)."""
        if self._progress is None:
            return
        fields = {} if info is None else {"info": info}
        self._progress.update(self._task, advance=steps, **fields)
        console = self._progress.console
        if not console.is_terminal and time.monotonic() - self._logged >= LOG_SECONDS:
            self._logged = time.monotonic()
            task = self._progress.tasks[0]
            console.print(f"{task.description}: {task.completed:g}/{task.total:g} "
                          f"{task.fields.get('info', '')}".rstrip(), highlight=False)


@contextmanager
def shown(enabled: bool = True) -> Iterator[None]:
    """Show the bars that jobs inside this block open (the CLI's long commands use it)."""
    token = _SHOWN.set(enabled)
    try:
        yield
    finally:
        _SHOWN.reset(token)


@contextmanager
def progress_bar(total: int, description: str, done: int = 0,
                 enabled: bool | None = None) -> Iterator[Bar]:
    """A bar of ``total`` steps (``done`` of them already done) on stderr.

    ``enabled`` overrides :func:`shown`; a bar inside another open bar is never shown.
    """
    if not (_SHOWN.get() if enabled is None else enabled) or _OPEN.get():
        yield Bar()
        return
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
               TimeElapsedColumn(), TimeRemainingColumn(), TextColumn("{task.fields[info]}"))
    token = _OPEN.set(True)
    try:
        with Progress(*columns, console=Console(stderr=True)) as progress:
            task = progress.add_task(description, total=total, completed=done, info="")
            yield Bar(progress, task)
    finally:
        _OPEN.reset(token)
