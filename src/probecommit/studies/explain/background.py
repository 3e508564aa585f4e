"""Explain steps that run in a process of their own while the later steps go on (issue 42).

The GRU step retrains seed 0 twice (PyTorch, its own thread count) and the rig step simulates
and sweeps 30 rig sessions: minutes of CPU each, that read nothing the other steps write and
fill result groups nobody else fills. In a process of their own (one after the other) they
overlap the rest of the target (the reproduction's critical path, often with a CPU to spare at
its end), and PyTorch is never imported into the explain process (about 220 MB less held
through every later step). Their keys are the same: the functions and their arguments are.
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import Future, ProcessPoolExecutor
from typing import Any, Callable


class Background:
    """Functions run one at a time in one spawned process (inline where there is one CPU); results by name."""

    def __init__(self) -> None:
        self._pool: ProcessPoolExecutor | None = None
        self._pending: list[tuple[Future, Callable[[Any], None]]] = []

    def submit(self, then: Callable[[Any], None], fn: Callable[..., Any], *args: Any) -> None:
        """Start ``fn(*args)`` (a module-level function of picklable arguments); :meth:`finish` hands its
        result to ``then`` (in this process: it puts the keys where the step would have)."""
        if self._pool is None and (os.cpu_count() or 1) < 2:
            then(fn(*args))  # one CPU: nothing to overlap
            return
        if self._pool is None:  # spawned: no fork of a process that may hold threads
            self._pool = ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"))
        self._pending.append((self._pool.submit(fn, *args), then))

    def finish(self) -> None:
        """Wait for every submitted function and hand each result on, in submission order (a failure is raised)."""
        while self._pending:
            future, then = self._pending.pop(0)
            then(future.result())

    def close(self) -> None:
        """End the process (what has not started is cancelled): after :meth:`finish`, or when a step failed."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
