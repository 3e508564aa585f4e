"""Helper processes forked when a command starts, that import what a later step needs while the
command works, and then run that step's parts beside each other.

``probecommit calibrate`` spends about 5 s in ``calibrate`` on two busy CPUs, then draws its
report: four figures (the calibration figure saved, then drawn again for the page; the audit
figure at two widths) and their PNGs, about 1.7 CPU s, after importing matplotlib (0.3 CPU s),
all on one thread while the second CPU waits (issue 42, target 3). Figures are Python bound (the
GIL), so threads would not overlap them; processes forked before the work begins do, and import
matplotlib while ``calibrate`` still runs. A job's result is what its function returns (pickled
back), so a figure drawn by a helper is the same bytes as one drawn here.

The helpers are a standard ``concurrent.futures.ProcessPoolExecutor`` (``fork`` context): its
first ``submit`` forks every worker at once, so the pool is started, and the workers forked, from
a process with one Python thread (the command before its work starts); the wrapper adds only
what the command needs around it. Where ``fork`` is missing or another thread runs, or once the
pool is broken (a helper went away), a job runs in the calling process when its result is asked
for: the same function and arguments, so the same result.
"""

from __future__ import annotations

import contextlib
import importlib
import multiprocessing
import signal
import threading
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Callable, Iterator, Sequence


def _warm(names: tuple[str, ...]) -> None:
    """A helper's start: leave Ctrl-C to the command (it ends the helpers), import ``names`` ahead."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for name in names:
        with contextlib.suppress(Exception):  # a job needing it raises the same error, and is reported
            importlib.import_module(name)


class _Job:
    """A submitted call: its future in a helper, or (``future`` None, or the pool broken) the call here."""

    def __init__(self, future: "Future | None", call: tuple) -> None:
        self.future, self.call = future, call

    def result(self) -> Any:
        """The call's return value (its exception raised here); waits for the helper."""
        if self.future is not None:
            with contextlib.suppress(BrokenProcessPool):  # a helper went away: the same call here
                return self.future.result()
        fn, args, kwargs = self.call
        return fn(*args, **kwargs)


class Helpers:
    """Submit module-level calls with picklable arguments to the pool (or run them here when there is none)."""

    def __init__(self, pool: "ProcessPoolExecutor | None", count: int = 0) -> None:
        self._pool, self.count = pool, count  # count: helper processes (0: every job runs here)

    def submit(self, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> _Job:
        """``fn(*args, **kwargs)`` in a helper; ``.result()`` gives what it returned."""
        future = None
        if self._pool is not None:
            with contextlib.suppress(BrokenProcessPool):
                future = self._pool.submit(fn, *args, **kwargs)
        return _Job(future, (fn, args, kwargs))


def can_fork() -> bool:
    """Whether forking is safe here: ``fork`` exists and this process runs one Python thread."""
    return "fork" in multiprocessing.get_all_start_methods() and threading.active_count() == 1


@contextlib.contextmanager
def forked_helpers(count: int, warm: Sequence[str] = ()) -> Iterator[Helpers]:
    """``count`` helper processes, forked now, that import the modules named in ``warm``; ended when the block
    ends (waited for; killed when the block raised, e.g. Ctrl-C or a failed job, so nothing is left running).
    None are forked where :func:`can_fork` is false: the jobs then run in this process."""
    if count < 1 or not can_fork():
        yield Helpers(None)
        return
    before = set(multiprocessing.active_children())
    pool = ProcessPoolExecutor(count, mp_context=multiprocessing.get_context("fork"), initializer=_warm,
                               initargs=(tuple(warm),))
    pool.submit(int)  # a no-op: the first submit forks every worker, before this process starts a thread
    ours = set(multiprocessing.active_children()) - before
    try:
        yield Helpers(pool, count)
    except BaseException:
        for process in ours:  # a job may still be drawing: waiting for it would hold the command
            process.kill()
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=True)
