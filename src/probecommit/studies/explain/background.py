"""An explain step that runs in a process of its own while the later steps go on (issue 42).

The GRU step retrains seed 0 twice (PyTorch, its own thread count): minutes of CPU that read
nothing the other steps write and write one result group nobody else fills. In a process of its
own it overlaps the rest of the target (the reproduction's critical path, often with a CPU to
spare at its end), and PyTorch is never imported into the explain process (about 220 MB less
held through every later step). Its keys are the same: the function and its arguments are.
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
        self._pending: dict[str, Future] = {}
        self._done: dict[str, Any] = {}

    def submit(self, name: str, fn: Callable[..., Any], *args: Any) -> None:
        """Start ``fn(*args)`` (a module-level function of picklable arguments) under ``name``."""
        if (os.cpu_count() or 1) < 2:
            self._done[name] = fn(*args)
            return
        if self._pool is None:  # spawned: no fork of a process that may hold threads
            self._pool = ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"))
        self._pending[name] = self._pool.submit(fn, *args)

    def results(self) -> dict[str, Any]:
        """Every submitted function's result, in submission order, once all are done (a failure is raised)."""
        for name, future in self._pending.items():
            self._done[name] = future.result()
        self._pending.clear()
        return dict(self._done)

    def close(self) -> None:
        """End the process (what has not started is cancelled): after :meth:`results`, or when a step failed."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
