"""A step run in a fresh process of its own, waited for, so that its working memory leaves with it (issue 42).

A reproduction target runs in one process; a step whose arrays and frames are held only while it runs (a study's
units, a whole run's replays) would otherwise set that process's peak for the whole target, and glibc keeps much of
what it freed. In a spawned process the step's peak is its own, above the imports only (about 145 MB), and all of
it is given back when the process exits. The step's result is what it returns (pickled back); it must be a
module-level function of picklable arguments. Numbers are unchanged: the function and its arguments are.
"""

from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from typing import Any, Callable


def in_own_process(fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """``fn(*args, **kwargs)`` in a fresh spawned process (no fork of a process that may hold threads), waited for:
    its result, or its exception raised here. Engine answers are shared within that process, as in the target's
    own (``report.schedule.run_target``)."""
    with ProcessPoolExecutor(max_workers=1, max_tasks_per_child=1,
                             mp_context=multiprocessing.get_context("spawn")) as pool:
        return pool.submit(_with_shared_answers, fn, args, kwargs).result()


def _with_shared_answers(fn: Callable[..., Any], args: tuple, kwargs: dict) -> Any:
    from probecommit.tasks.base import shared_engine_answers

    with shared_engine_answers():
        return fn(*args, **kwargs)
