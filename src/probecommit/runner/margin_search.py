"""The margin search's commits of every margin in one visit of a run's beliefs (paper Sec. IV).

The search (``audit.margin.select_margin``) asks, margin by margin from the largest down,
for the sums of predicted and realized failure of the calibration commits. What does not
depend on the margin — the beliefs, the retained sets, their success-interval parts and
the tie-break costs — is computed once here, for every margin; what does — the
failure counts, the chosen aims and their outcomes — is computed for each margin, the
counts of all margins in one compiled visit of each retained set, and every margin's choice
in the same compiled code (``runner.kernels``).

:func:`sweep_margins` has ``runner.inference.commit``'s calling convention, so a run's
chunk pass (``RunBeliefs.commit``, a request with ``via``) runs it beside other commits on
the same beliefs. Its result, per margin, is exactly the predicted and realized columns of
the ok rows at the rule's budgets of ``commit(..., margin=gamma)``, in the table's row
order (tested), so the search's sums are the same bits.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

from probecommit.core.executors import SCORE_TIE_TOLERANCE, ProbeRobust
from probecommit.runner.inference import BeliefTrace, _execute
from probecommit.runner.kernels import margin_choices

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
    model.with_margin(margins[0])  # a model with no margin refuses the search, as each margin's commit would
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
        predicted[:, :, p] = score
        realized[:, :, p], ok[:, :, p] = execute_every_margin(simulator, batch, grid, index, outcomes)
    ok &= np.isin(budgets, list(rule_budgets))[None, None, :]
    out: list[np.ndarray] = []
    for m in range(n_m):
        out += [predicted[m][ok[m]], realized[m][ok[m]]]
    return tuple(out)


def execute_every_margin(simulator: Any, batch: Any, grid: np.ndarray, index: np.ndarray,
                         outcomes: dict) -> tuple[np.ndarray, np.ndarray]:
    """Realized failure ``[M, E]`` of each margin's aims ``index[M, E]``, and which are ok (not failed).

    ``runner.inference._execute`` of every margin at once: one engine query per distinct
    (instance, aim) of all margins, remembered in ``outcomes`` as it does, so each value and
    failure is the one that margin's commit gets.
    """
    n_m, n_e = index.shape
    rows = np.broadcast_to(np.arange(n_e), (n_m, n_e)).reshape(-1)
    flat = index.reshape(-1)
    keys = batch.instance_index.astype(np.int64)[rows] * len(grid) + flat
    unique, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    missing = [u for u, key in enumerate(unique.tolist()) if key not in outcomes]
    if missing:  # the aims no commit on this batch asked for yet: inference's own call, on those rows
        chosen = first[missing]
        one = _execute(simulator, batch.subset(rows[chosen]), grid[flat[chosen]], flat[chosen], len(grid), outcomes)
        del one
    values = np.empty(len(unique))
    failed = np.zeros(len(unique), dtype=bool)
    for u, key in enumerate(unique.tolist()):
        value = outcomes[key]
        if isinstance(value, str):
            values[u], failed[u] = np.nan, True
        else:
            values[u] = value
    inverse = np.asarray(inverse).reshape(-1)
    return values[inverse].reshape(n_m, n_e), ~failed[inverse].reshape(n_m, n_e)


def choose_every_margin(model: Any, retained: Any, context: np.ndarray | None, margins: Sequence[float],
                        plateau: str) -> tuple[np.ndarray, np.ndarray]:
    """The aim ``[M, E]`` each margin's executor chooses over a retained set, and its score ``[M, E]``.

    Equal to ``ProbeRobust(model.with_margin(gamma), plateau).choose(retained, context)`` for
    each margin: one compiled count of every margin where the model's loss is binary with
    success-interval parts, else that call margin by margin.
    """
    chosen = _compiled_choices(model, retained, context, margins)
    if chosen is not None:
        return chosen
    chosen = [ProbeRobust(model.with_margin(g), plateau).choose(retained, context) for g in margins]
    return np.stack([c.index for c in chosen]), np.stack([np.asarray(c.score, dtype=float) for c in chosen])


def _compiled_choices(model: Any, retained: Any, context: np.ndarray | None,
                      margins: Sequence[float]) -> tuple[np.ndarray, np.ndarray] | None:
    """:func:`choose_every_margin` by one compiled count of every margin per block
    (``runner.kernels.margin_choices``), or None (no compiled kernels, a continuous loss, or a
    block without interval parts)."""
    if not model.binary_loss:
        return None
    parts = retained.interval_parts(model)
    if any(part is None for part in parts):
        return None
    actions = np.asarray(model.action_grid, dtype=float).reshape(-1)
    tie = model.tie_break_cost(model.action_grid, retained.reference, context)
    blocks = [(centre, half, mask) for (_, mask), (centre, half) in zip(retained.blocks(), parts)]
    return margin_choices(blocks, np.asarray(margins, dtype=float), actions, tie, SCORE_TIE_TOLERANCE)
