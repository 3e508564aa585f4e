"""The margin search's commits of every margin in one visit of a run's beliefs (paper Sec. IV).

The search (``audit.margin.select_margin``) asks, margin by margin from the largest down,
for the sums of predicted and realized failure of the calibration commits. What does not
depend on the margin — the beliefs, the retained sets, their success-interval parts and
the tie-break costs — is computed once here, for every margin; what does — the
failure counts, the chosen aims and their outcomes — is computed for each margin, the
counts of all margins in one compiled visit of each retained set (``runner.kernels``).

:func:`sweep_margins` has ``runner.inference.commit``'s calling convention, so a run's
chunk pass (``RunBeliefs.commit``, a request with ``via``) runs it beside other commits on
the same beliefs. Its result, per margin, is exactly the predicted and realized columns of
the ok rows at the rule's budgets of ``commit(..., margin=gamma)``, in the table's row
order (tested), so the search's sums are the same bits.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

from probecommit.core.executors import ProbeRobust, select_action
from probecommit.runner.inference import BeliefTrace, _execute
from probecommit.runner.kernels import margin_success_counts

#: The executor whose commits the margin search re-executes.
METHOD = "probe_robust"


def sweep_margins(trace: BeliefTrace, model: Any, simulator: Any, *, thresholds: float | Mapping[int, float],
                  margins: Sequence[float], rule_budgets: Sequence[int], plateau: str = "prefix",
                  cache: dict | None = None, methods: Sequence[str] = (METHOD,), **_: Any) -> tuple[np.ndarray, ...]:
    """Per margin, the predicted and realized failure of the ok rows at ``rule_budgets``.

    Args:
        trace: Beliefs per budget (one chunk of a run).
        model: The model; each margin scores with ``model.with_margin(gamma)``.
        simulator: Ground truth (``execute``, cached per distinct action).
        thresholds: The set calibration (a float for every budget or ``{k: t_k}``).
        margins: The margins, largest first.
        rule_budgets: The budgets the margin rule averages over.
        plateau: The set at ``t = 1``.
        cache: ``commit``'s cache on this trace: retained sets are shared with other commits.
        methods: Must be the probe executor's alone.

    Returns:
        ``(predicted_0, realized_0, predicted_1, realized_1, ...)``, one pair per margin, each
        a float array of that margin's rows in table order (episode by episode, budgets inside).
    """
    if tuple(methods) != (METHOD,):
        raise ValueError(f"a margin sweep commits {METHOD} alone, not {list(methods)}")
    cache = {} if cache is None else cache
    margins = [float(g) for g in margins]
    budgets = [k for k in trace.budgets if not isinstance(thresholds, Mapping) or k in thresholds]
    batch = trace.batch
    grid = np.asarray(model.action_grid, dtype=float).reshape(len(model.action_grid), -1)
    outcomes = cache.setdefault("outcomes", {})
    n_e, n_m = batch.n_episodes, len(margins)
    predicted = np.empty((n_m, n_e, len(budgets)))
    realized = np.empty((n_m, n_e, len(budgets)))
    ok = np.empty((n_m, n_e, len(budgets)), dtype=bool)
    for p, k in enumerate(budgets):
        t = float(thresholds[k] if isinstance(thresholds, Mapping) else thresholds)
        key = ("set", METHOD, k, t, plateau)
        if key not in cache:
            state = trace.states[k]
            cache[key] = ProbeRobust(model, plateau).retain(state.particles, state.weights, t)
        index, score = choose_every_margin(model, cache[key], batch.episode_context, margins, plateau)
        for m in range(n_m):
            outcome, status, _ = _execute(simulator, batch, grid[index[m]], index[m], len(grid), outcomes)
            predicted[m, :, p], realized[m, :, p], ok[m, :, p] = score[m], outcome, status != "failed"
    ok &= np.isin(budgets, list(rule_budgets))[None, None, :]
    out: list[np.ndarray] = []
    for m in range(n_m):
        out += [predicted[m][ok[m]], realized[m][ok[m]]]
    return tuple(out)


def choose_every_margin(model: Any, retained: Any, context: np.ndarray | None, margins: Sequence[float],
                        plateau: str) -> tuple[np.ndarray, np.ndarray]:
    """The aim ``[M, E]`` each margin's executor chooses over a retained set, and its score ``[M, E]``.

    Equal to ``ProbeRobust(model.with_margin(gamma), plateau).choose(retained, context)`` for
    each margin: one compiled count of every margin where the model's loss is binary with
    success-interval parts, else that call margin by margin.
    """
    counted = _failure_fractions(model, retained, margins)
    if counted is None:
        chosen = [ProbeRobust(model.with_margin(g), plateau).choose(retained, context) for g in margins]
        return np.stack([c.index for c in chosen]), np.stack([np.asarray(c.score, dtype=float) for c in chosen])
    n_m, n_e, n_a = counted.shape
    tie = np.asarray(model.tie_break_cost(model.action_grid, retained.reference, context), dtype=float)
    index = select_action(counted.reshape(n_m * n_e, n_a), np.broadcast_to(tie, counted.shape).reshape(n_m * n_e, n_a))
    index = index.reshape(n_m, n_e)
    return index, np.take_along_axis(counted, index[..., None], axis=2)[..., 0]


def _failure_fractions(model: Any, retained: Any, margins: Sequence[float]) -> np.ndarray | None:
    """``core.executors.retained_scores`` of every margin ``[M, E, A]`` from one compiled count per
    block, or None (no compiled kernels, a continuous loss, or a block without interval parts)."""
    if not model.binary_loss:
        return None
    parts = retained.interval_parts(model)
    if any(part is None for part in parts):
        return None
    actions = np.asarray(model.action_grid, dtype=float).reshape(-1)
    failures = None
    kept = None
    for (_, mask), (centre, half) in zip(retained.blocks(), parts):
        counted = margin_success_counts(centre, half, mask, np.asarray(margins), actions)
        if counted is None:
            return None
        successes, n_kept = counted
        block = n_kept[None, :, None] - successes
        failures = block if failures is None else failures + block
        kept = n_kept if kept is None else kept + n_kept
    return failures / np.maximum(kept, 1)[None, :, None]
