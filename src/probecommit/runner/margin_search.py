"""The margin search's commits of every margin in one visit of a chunk's beliefs (paper Sec. IV).

The search (``audit.margin.select_margin``) asks, margin by margin from the largest down, for
the predicted and realized failure of the calibration commits under each margin ``gamma``.
Margin by margin, each evaluation recomputed what does not depend on the margin: a run of
several chunks recomputed its beliefs for every few margins (``MARGIN_BLOCK_ROWS``), and every
margin counted the retained scenarios again. Here the beliefs and retained sets of a chunk are
made once, every margin's choice comes from one count of the scenarios
(``ProbeRobust.decide_margins``), and the aims of every margin are executed together, one engine
query per distinct (instance, aim) as ``runner.inference._execute`` makes them.

:func:`sweep_margins` has ``runner.inference.commit``'s calling convention, so a run's chunk
pass (``RunBeliefs.commit``, a request with ``via``) runs it beside other commits on the same
beliefs. Per margin, :meth:`SweptChunk.columns` is exactly the ``k``, ``status``, ``predicted``
and ``realized`` columns of ``commit(..., margin=gamma)`` on the chunk (tested), so the rows a
calibration records and the search's sums are the same bits.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from probecommit.core.executors import Belief
from probecommit.runner.commit_threads import in_threads
from probecommit.runner.inference import BeliefTrace, _belief_at, _commit_plan, _execute, commit, outcome_keys


@dataclass
class SweptChunk:
    """Every margin's commit on one chunk: the aims and scores, and the outcomes once executed.

    Arrays are ``[M, E * P]`` in the table's row order (episode by episode, the plan's budgets
    inside), one row per margin of :attr:`margins`.
    """

    margins: list[float]
    k: np.ndarray
    index: np.ndarray
    predicted: np.ndarray
    #: What executes the aims (None once every margin's are): the chunk's batch, simulator, grid and
    #: outcome memo, and the plans per episode.
    pending: tuple | None = field(default=None, repr=False)
    #: Realized failure and whether the execution failed, ``[M, E * P]``; filled per margin as executed.
    realized: np.ndarray | None = None
    failed: np.ndarray | None = None
    done: np.ndarray | None = None
    #: Tables of margins committed margin by margin (a model or executor with no one-count sweep).
    tables: list | None = field(default=None, repr=False)

    def execute(self, which: Sequence[int] | None = None) -> None:
        """Execute the aims of margins ``which`` (default: every margin) not executed yet; the
        chunk's stored answers must be in the simulator. One engine query per distinct
        (instance, aim) of those margins, by ``runner.inference._execute`` (its errors and memo)."""
        which = np.arange(len(self.margins)) if which is None else np.asarray(list(which), dtype=np.int64)
        which = which[~self.done[which]]
        if not which.size:
            return
        batch, simulator, n_actions, grid, outcomes, n_plans = self.pending
        n_rows = self.index.shape[1]
        episode = np.broadcast_to(np.arange(n_rows) // n_plans, (which.size, n_rows)).reshape(-1)
        flat = self.index[which].reshape(-1).astype(np.int64)
        first, inverse, keys = outcome_keys(batch, episode, flat, n_actions)
        missing = np.array([u for u, key in enumerate(keys) if key not in outcomes], dtype=np.int64)
        if missing.size:
            rows = first[missing]
            _execute(simulator, batch.subset(episode[rows]), grid[flat[rows]], flat[rows], n_actions, outcomes)
        answers = [outcomes[key] for key in keys]
        failed = np.array([isinstance(value, str) for value in answers], dtype=bool)
        values = np.array([np.nan if isinstance(value, str) else value for value in answers], dtype=float)
        self.realized[which] = values[inverse].reshape(which.size, n_rows)
        self.failed[which] = failed[inverse].reshape(which.size, n_rows)
        self.done[which] = True
        if self.done.all():
            self.pending, self.index = None, None  # every outcome is in: the aims are not needed again

    def columns(self, m: int) -> dict[str, np.ndarray]:
        """Margin ``margins[m]``'s ``k``, ``status``, ``predicted`` and ``realized`` columns, as
        ``commit(..., columns=("k", "status", "predicted", "realized"))`` makes them."""
        if self.tables is not None:
            table = self.tables[m]
            return {name: table[name].to_numpy() for name in ("k", "status", "predicted", "realized")}
        self.execute([m])
        status = np.full(self.k.shape[0], "ok", dtype=object)
        status[self.failed[m]] = "failed"
        return {"k": self.k, "status": status, "predicted": self.predicted[m], "realized": self.realized[m]}

    def rule_rows(self, m: int, budgets: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
        """What the margin rule sums of margin ``margins[m]``: predicted and realized failure of the
        rows not failed at ``budgets`` (``runner.calibration._margin_rows`` of its table)."""
        if self.tables is not None:
            columns = self.columns(m)
            rows = (columns["status"].astype(str) != "failed") & np.isin(columns["k"], list(budgets))
            return (np.asarray(columns["predicted"], dtype=float)[rows],
                    np.asarray(columns["realized"], dtype=float)[rows])
        self.execute([m])  # a row's status is "failed" exactly where its execution failed (columns())
        rows = ~self.failed[m] & np.isin(self.k, list(budgets))
        return self.predicted[m][rows], self.realized[m][rows]


def sweep_margins(trace: BeliefTrace, model: Any, simulator: Any, *, executors: Sequence[Any],
                  thresholds: float | Mapping[int, float], margins: Sequence[float], execute: bool = True,
                  cache: dict | None = None, columns: Sequence[str] | None = None, **_: Any) -> SweptChunk:
    """Every margin's commit of ``executors`` on a chunk's beliefs, the margin-free work done once.

    Args:
        trace: Beliefs per budget (one chunk of a run).
        model: The model; margin ``gamma`` scores with ``model.with_margin(gamma)``.
        simulator: Ground truth (``execute``, one query per distinct action).
        executors: The injected executors (set executors with ``decide_margins`` sweep; any
            other commits margin by margin).
        thresholds: The set calibration (a float for every budget or ``{k: t_k}``).
        margins: The margins, largest first.
        execute: Execute the aims now (a run of several chunks, whose answers the simulator holds
            only during the chunk); False leaves it to :meth:`SweptChunk.execute`, so a run of one
            chunk asks the engine only for the margins the search reads, as margin by margin.
        cache: ``commit``'s cache on this trace: retained sets and outcomes shared with other commits.

    Returns:
        The chunk's :class:`SweptChunk`.
    """
    cache = {} if cache is None else cache
    margins = [float(g) for g in margins]
    plan = _commit_plan(trace, executors, thresholds)
    if not all(hasattr(executor, "decide_margins") for executor, _ in plan):
        wanted = ("k", "status", "predicted", "realized")
        tables = [commit(trace, model, simulator, executors, thresholds, g, cache, wanted) for g in margins]
        return SweptChunk(margins, np.empty(0, np.int64), np.empty((0, 0)), np.empty((0, 0)), tables=tables)
    context = trace.batch.episode_context
    n_e, n_p = trace.batch.n_episodes, len(plan)
    index = np.empty((len(margins), n_e, n_p), dtype=np.int32)
    predicted = np.empty((len(margins), n_e, n_p), dtype=float)
    memos = [cache.setdefault(("set", executor.method, k, float(thresholds[k] if isinstance(thresholds, Mapping)
                                                                  else thresholds), executor.memo_tag), {})
             for executor, k in plan]  # made here, so the threads below share no dict they add to

    def choose(p: int) -> None:
        (executor, k), memo = plan[p], memos[p]
        belief = _belief_at(trace, model, k, cache)  # the belief commit() reads (weights, z)
        t = float(thresholds[k] if isinstance(thresholds, Mapping) else thresholds)
        state = Belief(trace.states[k].particles, belief["weights"], belief["z"], belief["shared"])
        index[:, :, p], predicted[:, :, p] = executor.decide_margins(state, t, margins, context, memo)

    in_threads(choose, range(len(plan)))
    grid = np.asarray(model.action_grid, dtype=float).reshape(len(model.action_grid), -1)
    k = np.tile(np.array([k for _, k in plan], dtype=np.int64), n_e)
    n_m, n_rows = len(margins), n_e * n_p
    swept = SweptChunk(margins, k, index.reshape(n_m, -1), predicted.reshape(n_m, -1),
                       pending=(trace.batch, simulator, len(grid), grid, cache.setdefault("outcomes", {}), n_p),
                       realized=np.empty((n_m, n_rows)), failed=np.zeros((n_m, n_rows), dtype=bool),
                       done=np.zeros(n_m, dtype=bool))
    if execute:
        swept.execute()
    return swept
