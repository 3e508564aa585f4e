"""A chunk's commit split by budget over two threads (calibrate and gates, issue 42 target 3).

Why: a calibration commits every budget of a chunk in turn (``runner.inference.commit``), and each
budget's retained set, scores and belief summary depend only on that budget's beliefs. The
compiled kernels and NumPy's large operations release the GIL, so the budgets committed in two
threads (each budget by whichever thread is free) use two CPUs where one thread left the second
idle (the trace-ahead thread of ``RunBeliefs`` is busy only part of a pass). The table is the same
bits: each budget's part is ``commit`` itself on the same trace and cache, with the threshold of
that budget (a mapping ``{k: t}`` commits exactly the budgets it names, as a float does every
budget), and the parts' columns are interleaved back into the canonical row order (episode by
episode, budgets inside) as ``commit`` interleaves its own. The simulator is shared behind a lock, so each engine query is
asked and counted once, as in one thread; only which thread asks first may differ.
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING, Any, Callable, Iterable, Mapping, Sequence

import numpy as np

from probecommit.runner.inference import BeliefTrace, _commit_plan, commit

if TYPE_CHECKING:
    import pandas as pd

#: Threads a chunk's commit is split over (the machines this targets have two CPUs or more).
COMMIT_THREADS = 2


class LockedSimulator:
    """A simulator whose engine calls (``execute``, ``prefetch``, ``probe``) run one at a time.

    Two threads committing parts of a chunk share its simulator; its answer cache and call
    counts are plain Python state, so the calls that may ask the engine are serialized. Every
    other attribute is the simulator's own.
    """

    _LOCKED = ("execute", "prefetch", "probe", "probe_batch", "execute_batch", "realized_many")

    def __init__(self, simulator: Any) -> None:
        self._simulator = simulator
        self._lock = threading.Lock()

    def __getattr__(self, name: str) -> Any:
        value = getattr(self._simulator, name)
        if name not in self._LOCKED or not callable(value):
            return value

        def locked(*args: Any, **kwargs: Any) -> Any:
            with self._lock:
                return value(*args, **kwargs)

        return locked


def _budget_groups(trace: BeliefTrace, executors: Sequence[Any], thresholds: Any) -> list[list[int]] | None:
    """The budgets committed as one unit of work each (``in_threads`` gives each unit to whichever
    thread is free, so a plain set's cheap budget and a grown set's dear one keep both CPUs busy),
    or None when one thread commits: fewer than two CPUs or budgets, or a blind executor (its prior
    commit is not a budget of the thresholds)."""
    from probecommit.tasks.base import engine_threads

    if engine_threads() < 2 or any(executor.on_prior for executor in executors):
        return None
    budgets = [k for _, k in _commit_plan(trace, executors, thresholds)]
    if len(executors) != 1 or len(budgets) < 2:
        return None
    return [[k] for k in budgets]


def commit_in_threads(trace: BeliefTrace, model: Any, simulator: Any, executors: Sequence[Any],
                      thresholds: float | Mapping[int, float], margin: float | None = None,
                      cache: dict | None = None, columns: Sequence[str] | None = None,
                      **_: Any) -> pd.DataFrame:
    """``runner.inference.commit`` (its calling convention, a ``RunBeliefs.commit`` request's
    ``via``), the budgets split over :data:`COMMIT_THREADS` threads: the same table, bit for bit.

    One executor committing after every budget is split; anything else (a blind executor, one
    budget, one CPU) is ``commit`` in this thread.
    """
    cache = {} if cache is None else cache
    groups = _budget_groups(trace, executors, thresholds)
    if groups is None:
        return commit(trace, model, simulator, executors, thresholds, margin, cache, columns)
    shared = LockedSimulator(simulator)

    def part(budgets: list[int]) -> dict[str, Any]:
        mine = {k: (thresholds[k] if isinstance(thresholds, Mapping) else thresholds) for k in budgets}
        return commit(trace, model, shared, executors, mine, margin, cache, columns, as_columns=True)

    parts: list[Any] = [None] * len(groups)

    def run(i: int) -> None:
        parts[i] = part(groups[i])

    in_threads(run, range(len(groups)), COMMIT_THREADS)
    import pandas as pd

    return pd.DataFrame(_interleave(parts, groups, [k for _, k in _commit_plan(trace, executors, thresholds)],
                                    trace.batch.n_episodes))


def in_threads(work: Callable[[int], None], items: Iterable[int], threads: int | None = None) -> None:
    """``work(item)`` for every item over ``threads`` threads (default :data:`COMMIT_THREADS`, one
    with a single CPU), this one among them; every thread is joined before this returns, and the
    first error is raised here (no item is started after it).

    Each thread takes the next item not yet taken, in order, when it is free: items of unequal
    cost (a chunk's plain and grown sets, a summary's bootstraps) keep both CPUs busy, where a
    fixed share of the items each left one thread idle at the end. ``work`` writes its item's own
    result, so the results do not depend on which thread ran an item.
    """
    from probecommit.tasks.base import engine_threads

    items = list(items)
    threads = min(len(items), COMMIT_THREADS if threads is None else threads, engine_threads())
    if threads < 2:
        for item in items:
            work(item)
        return
    errors: list[BaseException] = []
    upcoming = iter(items)
    lock = threading.Lock()
    done = object()

    def run() -> None:
        while not errors:
            with lock:
                item = next(upcoming, done)
            if item is done:
                return
            try:
                work(item)
            except BaseException as exc:  # noqa: BLE001 - raised again in the calling thread
                errors.append(exc)

    helpers = [threading.Thread(target=run, name="probecommit-commit") for _ in range(1, threads)]
    for thread in helpers:
        thread.start()
    try:
        run()
    finally:
        for thread in helpers:
            thread.join()
    if errors:
        raise errors[0]


def _interleave(parts: list[dict[str, Any]], groups: list[list[int]], budgets: list[int],
                n_episodes: int) -> dict[str, np.ndarray]:
    """One table's columns from each thread's (rows ``e * P_i + i`` of its budgets), in the order
    ``commit`` makes them: row ``e * P + p`` is episode ``e`` at plan position ``p``; a column's
    dtype is what ``commit`` gives it (object if any part holds strings or objects)."""
    position = {k: p for p, k in enumerate(budgets)}
    n_plans = len(budgets)
    out: dict[str, np.ndarray] = {}
    for name in parts[0]:
        columns = [np.asarray(part[name]) for part in parts]
        kinds = {column.dtype.kind for column in columns}
        dtype = object if kinds & {"U", "S", "O"} else np.result_type(*columns)
        column = np.empty(n_episodes * n_plans, dtype=dtype)
        grid = column.reshape(n_episodes, n_plans)
        for part, group in zip(columns, groups):
            grid[:, [position[k] for k in group]] = part.reshape(n_episodes, len(group))
        out[name] = column
    return out
