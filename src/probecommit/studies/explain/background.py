"""Explain steps that run in processes of their own while the later steps go on (issue 42).

The GRU step retrains seed 0 twice (PyTorch, its own thread count), the rig step simulates and
sweeps 30 rig sessions, and the steps ``Explain.aside`` sets aside (engine runs and replays that
read only stored inputs) take minutes of CPU each, read nothing the other steps write and fill
result groups nobody else fills. Beside the main process they use the CPU its single-threaded
summaries leave idle (the reproduction's critical path, alone at its end), and what they hold
(PyTorch, about 220 MB; a MuJoCo pool's engine answers, about 750 MB) never enters the explain
process: each function runs in a fresh process, whose memory is given back when it returns.
Their keys are the same: the functions and their arguments are.
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import Future, ProcessPoolExecutor
from typing import Any, Callable

#: Processes at once (where there are that many CPUs): the main process's own runs use the CPUs too, but
#: its summaries and replays are single-threaded, so one more keeps a 2-core machine busy.
PROCESSES = 2


class Background:
    """Functions run in spawned processes, each in a fresh one, at most ``processes`` at once (inline where
    there is one CPU); their results handed on in submission order."""

    def __init__(self, processes: int = PROCESSES) -> None:
        self.processes = processes
        self._pool: ProcessPoolExecutor | None = None
        self._pending: list[tuple[Future, Callable[[Any], None]]] = []

    def submit(self, then: Callable[[Any], None], fn: Callable[..., Any], *args: Any) -> Future:
        """Start ``fn(*args)`` (a module-level function of picklable arguments); :meth:`finish` hands its
        result to ``then`` (in this process: it puts the keys where the step would have). Returns its future
        (already done when it ran inline), for :meth:`finish`'s ``until``."""
        cpus = os.cpu_count() or 1
        if self._pool is None and cpus < 2:
            then(fn(*args))  # one CPU: nothing to overlap
            done: Future = Future()
            done.set_result(None)
            return done
        if self._pool is None:  # spawned: no fork of a process that may hold threads; fresh per function
            self._pool = ProcessPoolExecutor(max_workers=min(self.processes, cpus), max_tasks_per_child=1,
                                             mp_context=multiprocessing.get_context("spawn"))
        future = self._pool.submit(fn, *args)
        self._pending.append((future, then))
        return future

    def finish(self, until: Future | None = None) -> None:
        """Wait for every submitted function (``until``: up to and including that one) and hand each result on,
        in submission order (a failure is raised)."""
        if until is not None and all(future is not until for future, _ in self._pending):
            return  # handed on already (or run inline)
        while self._pending:
            future, then = self._pending.pop(0)
            then(future.result())
            if future is until:
                return

    def close(self) -> None:
        """End the processes (what has not started is cancelled): after :meth:`finish`, or when a step failed."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

