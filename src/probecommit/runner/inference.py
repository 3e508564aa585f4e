"""Rollout, belief traces and commits: the episode pipeline.

Rollout (the simulator) and inference (the model) are separate. ``rollout`` draws
probes and readings from the simulator; ``build_trace`` recomputes beliefs from
stored probes; ``commit`` turns beliefs into actions, scores them with the model and
asks the simulator for the realized outcome. Replays under another model variant,
faults and calibration all reuse stored probes, so compared arms see identical taps.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable, Iterable, Mapping, Sequence

import numpy as np

from probecommit.core.belief import BeliefState, ParticleFilter
from probecommit.core.executors import Belief, Commitment, Executor
from probecommit.accel import production
from probecommit.runner.seeding import INFERENCE, ROLLOUT, episode_rngs
from probecommit.store.schema import component_names
from probecommit.tasks.base import CachedSimulator

if TYPE_CHECKING:  # pandas is imported where a DataFrame is built: a run's own path builds none
    import pandas as pd


@dataclass
class ProbeBatch:
    """Stored probes of ``E`` episodes (one trajectory each, ``K`` probes).

    Attributes:
        u: ``[E, K, p]`` probes; ``y``: ``[E, K, m]`` observations.
        context: ``[E, c]`` observed context per episode (``c`` may be 0).
    """

    #: The episodes' split: one name, or one per episode when the batch pools runs of several splits (each
    #: episode's filter then draws its own run's random numbers, ``episode_rngs``).
    split: str | np.ndarray
    instance_id: np.ndarray  # [E] str
    instance_index: np.ndarray  # [E] int
    repeat: np.ndarray  # [E] int
    truths: np.ndarray  # [E, d]
    u: np.ndarray  # [E, K, p]
    y: np.ndarray  # [E, K, m]
    status: np.ndarray = field(default=None)  # type: ignore[assignment]  # [E] "ok" / "failed"
    error: np.ndarray = field(default=None)  # type: ignore[assignment]
    context: np.ndarray = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        n = len(self.instance_id)
        if self.status is None:
            self.status = np.full(n, "ok", dtype=object)
        if self.error is None:
            self.error = np.full(n, "", dtype=object)
        if self.context is None:
            self.context = np.zeros((n, 0))

    @property
    def n_episodes(self) -> int:
        return len(self.instance_id)

    @property
    def episode_context(self) -> np.ndarray | None:
        """``[E, c]``, or None for a family without context."""
        return self.context if self.context.shape[1] else None

    def subset(self, rows: np.ndarray) -> "ProbeBatch":
        return ProbeBatch(
            self.split if isinstance(self.split, str) else self.split[rows], self.instance_id[rows],
            self.instance_index[rows], self.repeat[rows],
            self.truths[rows], self.u[rows], self.y[rows], self.status[rows], self.error[rows], self.context[rows],
        )

    def probes_frame(self) -> pd.DataFrame:
        """Long table ``instance_id, repeat, j, u.., y..`` of the successful episodes."""
        import pandas as pd

        return pd.DataFrame(self.probes_columns())

    def probes_columns(self) -> dict[str, np.ndarray]:
        """:meth:`probes_frame`'s columns."""
        ok = self.status == "ok"
        e, k = self.u[ok].shape[:2]
        frame = {
            "instance_id": np.repeat(self.instance_id[ok], k).astype(str),
            "repeat": np.repeat(self.repeat[ok], k).astype(np.int64),
            "j": np.tile(np.arange(1, k + 1), e).astype(np.int64),
        }
        for base, values in (("u", self.u[ok]), ("y", self.y[ok])):
            for i, name in enumerate(component_names(base, values.shape[2])):
                frame[name] = values[..., i].ravel().astype(float)
        return frame


def instance_arrays(instances: pd.DataFrame, model: Any) -> tuple[np.ndarray, np.ndarray]:
    """Truths ``[I, d]`` and contexts ``[I, c]`` of an instance table."""
    def matrix(names: list[str]) -> np.ndarray:
        # Column by column: selecting several columns builds a DataFrame (~10 ms a unit).
        if not names:
            return np.empty((len(instances), 0))
        return np.column_stack([np.asarray(instances[name], dtype=float) for name in names]).reshape(len(instances), -1)

    return matrix([f"true_{n}" for n in model.latent_names]), matrix([f"ctx_{n}" for n in model.context_names])


def _first_split(instances: Any) -> str:
    """The split of an instance table's first row ("" when it has none)."""
    return str(np.asarray(instances["split"])[0]) if len(instances) else ""


def rollout(
    instances: pd.DataFrame,
    repeats: int,
    schedule: str | list,
    budget: int,
    model: Any,
    simulator,
    seed: int,
) -> ProbeBatch:
    """Draw every episode's probe trajectory from the simulator.

    Random schedules draw the probe's grid index and then the reading noise at each
    step, from the episode's own rollout stream, so a budget-``k`` trajectory is
    the prefix of any longer one with the same seed.
    """
    grid = np.asarray(model.probe_grid, dtype=float)
    p, m = model.probe_dim, model.observation_dim
    truths, contexts = instance_arrays(instances, model)
    random_schedule = isinstance(schedule, str) and schedule == "random"
    if not random_schedule and simulator.parallel_queries:
        # A fixed schedule taps the same positions in every episode: run those engine queries in threads first.
        simulator.prefetch([simulator.probe_query_key(theta, np.atleast_1d(np.asarray(schedule[j], dtype=float)))
                            for theta in truths for j in range(budget)])
    rows = []
    # Column arrays, not iterrows: a Series per instance costs more than its taps on the analytic engine.
    splits = [str(s) for s in np.asarray(instances["split"]).tolist()]
    indices = np.asarray(instances["instance_index"], dtype=np.int64).tolist()
    streams = episode_rngs(seed, [s for s in splits for _ in range(repeats)], [i for i in indices for _ in range(repeats)],
                           [r for _ in indices for r in range(repeats)], ROLLOUT)  # instance by instance, repeats inside
    for i, (instance_id, index) in enumerate(zip(np.asarray(instances["instance_id"]), indices)):
        theta = truths[i]
        for r in range(repeats):
            rng = streams[i * repeats + r]
            u = np.empty((budget, p))
            y = np.full((budget, m), np.nan)
            status, error = "ok", ""
            try:
                for j in range(budget):
                    u[j] = grid[rng.integers(len(grid))] if random_schedule else schedule[j]
                    y[j] = simulator.probe(theta, u[j], rng)
                    if not (math.isfinite(y[j, 0]) if m == 1 else np.isfinite(y[j]).all()):
                        shown = u[j][0] if p == 1 else u[j].tolist()
                        raise FloatingPointError(f"{simulator.engine} returned {y[j].tolist()} for probe u={shown}")
            except Exception as exc:  # noqa: BLE001 - one bad engine query must not end the study
                status, error = "failed", f"probe {j + 1}: {type(exc).__name__}: {exc}"
            rows.append((instance_id, index, r, theta, u, y, status, error, contexts[i]))
    split = _first_split(instances)
    n = len(rows)
    return ProbeBatch(
        split=split,
        instance_id=np.array([r[0] for r in rows], dtype=object),
        instance_index=np.array([r[1] for r in rows], dtype=np.int64),
        repeat=np.array([r[2] for r in rows], dtype=np.int64),
        truths=np.array([r[3] for r in rows], dtype=float).reshape(n, len(model.latent_names)),
        u=np.array([r[4] for r in rows], dtype=float).reshape(n, budget, p),
        y=np.array([r[5] for r in rows], dtype=float).reshape(n, budget, m),
        status=np.array([r[6] for r in rows], dtype=object),
        error=np.array([r[7] for r in rows], dtype=object),
        context=np.array([r[8] for r in rows], dtype=float).reshape(n, len(model.context_names)),
    )


#: The most ``[episodes x pseudo-truths, particles]`` elements one adaptive score pass holds per array (4 MB).
ADAPTIVE_SCORE_ELEMENTS = 1 << 19


def adaptive_scores(model: Any, likelihood: Any, particles: np.ndarray, weights: np.ndarray, grid: np.ndarray,
                    elements: int = ADAPTIVE_SCORE_ELEMENTS) -> np.ndarray:
    """``expected_posterior_variance`` of every episode, a block of episodes at a time.

    Each episode's score reads its own row only, so blocks give the whole batch's scores bit for bit (tested),
    while the ``[E x 32, N]`` likelihood and posterior arrays of a pass stay bounded (a unit of a few hundred
    episodes at N = 1024 held about 200 MB per thread at once)."""
    from probecommit.core.selectors import expected_posterior_variance

    n_e, n = weights.shape
    if n_e == 0:
        return expected_posterior_variance(model, likelihood, particles, weights, grid)
    step = max(1, elements // (min(32, n) * n))
    blocks = [expected_posterior_variance(model, likelihood, particles[a:a + step], weights[a:a + step], grid)
              for a in range(0, n_e, step)]
    return np.concatenate(blocks)


def rollout_adaptive(
    instances: pd.DataFrame,
    repeats: int,
    budget: int,
    model: Any,
    pfilter: ParticleFilter,
    simulator,
    seed: int,
) -> ProbeBatch:
    """Probe trajectories whose every probe is chosen by the current belief (``schedule: adaptive``).

    The belief runs online with the same inference streams ``build_trace`` uses, so
    recomputing beliefs from the stored probes under the same model reproduces this
    run exactly. The reading noise comes from each episode's rollout stream.
    """
    from probecommit.core.selectors import choose_probes

    grid = np.asarray(model.probe_grid, dtype=float)
    truths, contexts = instance_arrays(instances, model)
    ids, indices = np.asarray(instances["instance_id"]).tolist(), np.asarray(instances["instance_index"]).tolist()
    meta = [(iid, int(index), r, i) for i, (iid, index) in enumerate(zip(ids, indices)) for r in range(repeats)]
    n = len(meta)
    split = _first_split(instances)
    index = np.array([m[1] for m in meta], dtype=np.int64)
    rep = np.array([m[2] for m in meta], dtype=np.int64)
    rows = np.array([m[3] for m in meta], dtype=np.int64)
    roll = episode_rngs(seed, split, index, rep, ROLLOUT)
    infer = episode_rngs(seed, split, index, rep, INFERENCE)
    u = np.empty((n, budget, model.probe_dim))
    y = np.full((n, budget, model.observation_dim), np.nan)
    status = np.full(n, "ok", dtype=object)
    error = np.full(n, "", dtype=object)
    state = pfilter.initial(infer)
    for j in range(budget):
        u[:, j] = grid[choose_probes(adaptive_scores(model, pfilter.likelihood, state.particles, state.weights, grid))]
        for e in range(n):
            if status[e] != "ok":
                y[e, j] = model.predict(u[e:e + 1, j], state.particles[e:e + 1, :1])[0, 0]  # keep the filter running
                continue
            try:
                y[e, j] = simulator.probe(truths[rows[e]], u[e, j], roll[e])
                if not np.all(np.isfinite(y[e, j])):
                    raise FloatingPointError(f"{simulator.engine} returned {y[e, j].tolist()} for probe u={u[e, j].tolist()}")
            except Exception as exc:  # noqa: BLE001 - one bad engine query must not end the study
                status[e], error[e] = "failed", f"probe {j + 1}: {type(exc).__name__}: {exc}"
                y[e, j] = model.predict(u[e:e + 1, j], state.particles[e:e + 1, :1])[0, 0]
        state = pfilter.update(state, u[:, j], y[:, j], infer)
    return ProbeBatch(
        split=split, instance_id=np.array([m[0] for m in meta], dtype=object), instance_index=index, repeat=rep,
        truths=truths[rows].reshape(n, -1), u=u, y=y, status=status, error=error,
        context=contexts[rows].reshape(n, len(model.context_names)),
    )


@dataclass
class BeliefTrace:
    """Beliefs of a batch of episodes after each committed budget (k = 0 is the prior)."""

    batch: ProbeBatch
    states: dict[int, BeliefState]
    surprise: np.ndarray  # [E, K] -log predictive density of probe j before assimilation
    lost: np.ndarray | None = None  # [E, K] the belief lost every particle at probe j (reset)

    @property
    def budgets(self) -> list[int]:
        return sorted(k for k in self.states if k > 0)

    def subset(self, rows: np.ndarray) -> "BeliefTrace":
        """The trace of episodes ``rows`` (indices into this trace's batch), arrays copied.

        An episode's beliefs never depend on its batch, so this equals the trace built
        from those episodes alone, bit for bit (tested).
        """
        taken: dict[int, np.ndarray] = {}

        def take(a):  # an array several budgets share (no resampling between them) is taken once
            if a is None:
                return None
            if id(a) not in taken:
                taken[id(a)] = a[rows]
            return taken[id(a)]
        states = {k: BeliefState(**{name: take(getattr(s, name)) for name in BeliefState.trace_fields()})
                  for k, s in self.states.items()}
        return BeliefTrace(self.batch.subset(rows), states, self.surprise[rows], take(self.lost))


def build_trace(pfilter: ParticleFilter, batch: ProbeBatch, seed: int, budgets: Iterable[int],
                keep_weights: bool = False, keep_prior: bool = True) -> BeliefTrace:
    """Recompute beliefs from stored probes (successful episodes of ``batch`` only).

    Args:
        keep_weights: Keep each budget's normalized weights as the update computed them, so
            a commit does not exponentiate the log-weights again (one more ``[E, N]`` array
            per budget: for a bounded work unit, not a whole run's trace).
        keep_prior: Keep the prior belief (k = 0) the blind methods commit on; False for a
            trace that only probe-robust commits read (one ``[E, N, d]`` state less).
    """
    ok = np.flatnonzero(batch.status == "ok")
    batch = batch.subset(ok)
    rngs = episode_rngs(seed, batch.split, batch.instance_index, batch.repeat, INFERENCE)
    budgets = set(budgets)
    state = pfilter.initial(rngs)
    states = {0: state} if keep_prior else {}
    k_max = max(budgets) if budgets else 0
    surprise = np.full((batch.n_episodes, batch.u.shape[1]), np.nan)
    lost = np.zeros((batch.n_episodes, batch.u.shape[1]), dtype=bool)
    for j in range(1, k_max + 1):
        u_j, y_j = batch.u[:, j - 1], batch.y[:, j - 1]
        state = pfilter.update(state, u_j, y_j, rngs)
        surprise[:, j - 1] = -state.log_evidence  # the probe's log predictive density, before it was assimilated
        lost[:, j - 1] = state.lost
        if j in budgets:
            states[j] = state if keep_weights else state.compact()
    return BeliefTrace(batch, states, surprise, lost)


def commit(
    trace: BeliefTrace,
    model,
    simulator,
    executors: Sequence[Executor],
    thresholds: float | Mapping[int, float] = 0.8,
    margin: float | None = None,
    cache: dict | None = None,
    columns: Sequence[str] | None = None,
    as_columns: bool = False,
) -> pd.DataFrame:
    """Commit once per episode, executor and budget, and score the commit against ground truth.

    Args:
        trace: Beliefs per budget.
        model: The model scoring actions (its variant labels the rows, its decision coordinate
            gives ``z_true``).
        simulator: Ground truth; ``execute`` is cached per distinct action.
        executors: The injected executors (``core.executors.Executor``; ``runner.build.build_executors``
            makes them from a config's ``methods``), in table order: a blind one (``on_prior``)
            commits once on the prior belief (k = 0), any other after every budget of the trace.
        thresholds: Retained mass ``nu`` (or conformal threshold ``t``), a float for
            every budget or ``{k: t}``; ``t > 1`` uses the grown set.
        margin: The model's margin ``gamma`` (None keeps the model's); every executor is
            rebound to the model with that margin (``Executor.with_model``).
        cache: Optional dict reused across calls on the same ``trace`` (a margin search):
            what does not depend on the margin (the retained sets, the coverage score,
            the posterior variance, the hull) is computed once per budget and threshold.
            Results are identical with or without it.
        columns: Build only these columns, in this order (None: all). A margin search reads
            four columns of dozens of tables; the result equals ``table[list(columns)]``.
        as_columns: Return the table's columns (a dict of arrays, what the DataFrame is made
            of) instead: a run's unit builds its Arrow table from them directly.

    Returns:
        The episode table (columns of ``store.schema.EPISODE_COLUMNS``).
    """
    cache = {} if cache is None else cache
    if margin is not None:
        model = model.with_margin(margin)
        executors = [executor.with_model(model) for executor in executors]
    plan = _commit_plan(trace, executors, thresholds)
    z_true = model.decision(trace.batch.truths)
    frames = []
    for executor, k in plan:
        t = float(thresholds[k] if isinstance(thresholds, Mapping) else thresholds)
        belief = _belief_at(trace, model, k, cache)
        memo = cache.setdefault(("set", executor.method, k, t, executor.memo_tag), {})
        chosen = executor.decide(Belief(trace.states[k].particles, belief["weights"], belief["z"], belief["shared"]),
                                 t, trace.batch.episode_context, memo)
        summary = functools.partial(_belief_summary, belief, model, z_true)
        frames.append(_episode_columns(trace, model, simulator, executor.method, k, chosen, summary, z_true,
                                       cache.setdefault("outcomes", {}), columns))
    out = _interleave_columns(frames, trace.batch.n_episodes) if frames else {}
    if as_columns:
        return out
    import pandas as pd

    return pd.DataFrame(out) if out else pd.DataFrame()


def _commit_plan(trace: BeliefTrace, executors: Sequence[Executor],
                 thresholds: float | Mapping[int, float]) -> list[tuple[Executor, int]]:
    """``(executor, budget)`` of every commit, in table order: each executor's commits in turn, a
    blind one's on the prior (k = 0); per-budget thresholds commit only at the budgets they name."""
    budgets = [k for k in trace.budgets if not isinstance(thresholds, Mapping) or k in thresholds]
    plan = [(executor, k) for executor in executors for k in ([0] if executor.on_prior else budgets)]
    if any(k == 0 for _, k in plan) and 0 not in trace.states:
        raise ValueError("the blind methods commit on the prior belief (k = 0), which this trace does not keep "
                         "(RunBeliefs.of(..., budgets=...) keeps only the budgets it names)")
    return plan


def _belief_at(trace: BeliefTrace, model, k: int, cache: dict) -> dict[str, np.ndarray]:
    """Budget ``k``'s belief as the executors read it (decision coordinates, weights, and what its sets of
    every threshold share: ``Belief.shared``), kept in ``cache`` with its summary (:func:`_belief_summary`)
    once a column asks for that: margin-independent."""
    belief = cache.get(("belief", k))
    if belief is None:
        state = trace.states[k]
        # Contiguous once here: the decision coordinate is a strided view of the particles, and
        # every kernel reading it (coverage, variance, the executor's retained set) copied it.
        z = np.ascontiguousarray(model.decision(state.particles), dtype=np.float64)
        belief = cache[("belief", k)] = {"z": z, "weights": state.weights, "shared": {}}
    return belief


def _belief_summary(belief: dict[str, np.ndarray], model, z_true: np.ndarray) -> dict[str, np.ndarray]:
    """The belief's hull, coverage score and posterior variance, computed into ``belief`` when a column
    first reads them (a margin search's columns never do)."""
    if "score_s" not in belief:
        z, weights = belief["z"], belief["weights"]
        z_true = np.ascontiguousarray(z_true, dtype=np.float64)
        kernels = production()
        score_s, hull_lo, hull_hi = kernels.coverage_with_hull(z, weights, z_true, model.decision_domain_width)
        belief.update(hull_lo=hull_lo, hull_hi=hull_hi, score_s=score_s, post_var=kernels.weighted_variance(z, weights))
    return belief


def _episode_columns(trace: BeliefTrace, model, simulator, method: str, k: int, chosen: Commitment,
                     belief: Callable[[], dict[str, np.ndarray]], z_true: np.ndarray, outcomes: dict,
                     columns: Sequence[str] | None) -> dict[str, Any]:
    """One commit's episode-table columns (those in ``columns``, or all): the action executed
    through the simulator (``outcomes`` remembers its answers) and scored against the truth;
    ``belief()`` gives the belief's summary (:func:`_belief_summary`), made only if a column reads it."""
    batch = trace.batch
    grid = np.asarray(model.action_grid, dtype=float).reshape(len(model.action_grid), -1)
    action = grid[chosen.index]
    realized, status, error = _execute(simulator, batch, action, chosen.index, len(grid), outcomes)
    lo, hi = chosen.lo, chosen.hi
    # Each column made only when asked for (a margin search asks for four).
    makers = {
        "instance_id": lambda: batch.instance_id.astype(str),
        "repeat": lambda: batch.repeat.astype(np.int64),
        "k": lambda: np.int64(k),
        "method": lambda: method,
        "variant": lambda: model.variant,
        **{name: (lambda i=i: action[:, i]) for i, name in enumerate(component_names("action", model.action_dim))},
        "predicted": lambda: np.asarray(chosen.score, dtype=float),
        "realized": lambda: realized,
        "z_true": lambda: z_true,
        "retained_lo": lambda: lo,
        "retained_hi": lambda: hi,
        "hull_lo": lambda: belief()["hull_lo"],
        "hull_hi": lambda: belief()["hull_hi"],
        "covered": lambda: (lo <= z_true) & (z_true <= hi),
        "escaped": lambda: (z_true < belief()["hull_lo"]) | (z_true > belief()["hull_hi"]),
        "score_s": lambda: belief()["score_s"],
        "post_var": lambda: belief()["post_var"],
        "max_surprise": lambda: trace.surprise[:, :k].max(axis=1) if k > 0 else np.full(batch.n_episodes, np.nan),
        "n_retained": lambda: chosen.mask.sum(axis=1).astype(np.int64),
        "belief_resets": lambda: (trace.lost[:, :k].sum(axis=1) if trace.lost is not None
                                  else np.zeros(batch.n_episodes)).astype(np.int64),
        "status": lambda: status,
        "error": lambda: error,
    }
    wanted = list(makers) if columns is None else list(columns)
    unknown = [name for name in wanted if name not in makers]
    if unknown:
        raise ValueError(f"commit has no column {unknown[0]!r}; it makes {', '.join(makers)}")
    return {name: makers[name]() for name in wanted}


def prune_retained_sets(cache: dict, later: Iterable[float | Mapping[int, float]]) -> None:
    """Drop the retained sets in a :func:`commit` cache that no commit under ``later`` thresholds reads.

    A grown set (``t > 1``) holds a copy of its budget's particles and their success
    intervals, so a pass committing several thresholds in turn keeps only the sets still
    to be scored. The beliefs' own entries (coverage score, hull) stay.

    Args:
        cache: The dict passed as ``commit(cache=...)``.
        later: The thresholds of the commits still to come on this cache (a float for every
            budget or ``{k: t}``, as ``commit`` takes them).
    """
    later = list(later)
    uniform = {float(t) for t in later if not isinstance(t, Mapping)}
    per_budget = {(int(k), float(t)) for ts in later if isinstance(ts, Mapping) for k, t in ts.items()}
    for key in [key for key in cache if key[0] == "set"]:
        _, _, k, t, _ = key
        if t not in uniform and (k, t) not in per_budget:
            del cache[key]


def _interleave_columns(plans: list[dict[str, Any]], n_episodes: int) -> dict[str, np.ndarray]:
    """The columns of one table from per-plan columns, in canonical order: episode by episode,
    each in plan order (blind first, then budgets). Row ``e * P + p`` is episode ``e`` of plan
    ``p``; built column by column (no concat or sort)."""
    n_plans = len(plans)
    out: dict[str, Any] = {}
    for name in plans[0]:
        parts = [np.broadcast_to(np.asarray(plan[name]), (n_episodes,)) for plan in plans]
        kinds = {part.dtype.kind for part in parts}
        dtype = object if kinds & {"U", "S", "O"} else np.result_type(*parts)
        column = np.empty(n_episodes * n_plans, dtype=dtype)
        for p, part in enumerate(parts):
            column[p::n_plans] = part
        out[name] = column
    return out


def outcome_keys(batch: ProbeBatch, episodes: np.ndarray, index: np.ndarray,
                 n_actions: int) -> tuple[np.ndarray, np.ndarray, list[tuple[str, int]]]:
    """The distinct (instance, action) pairs of rows ``episodes`` of ``batch`` committing to grid actions ``index``:
    ``np.unique``'s ``first`` and ``inverse`` over those rows, and each pair's memo key
    ``(split, instance_index * n_actions + index)``, the same in every batch cut from the run or pool.

    The split is part of the key because instance indices start at 0 in every run: a batch pooling runs of
    several splits holds several instances under one index, and an index-only key gave them one shared outcome
    (whichever was executed first, so the answer also depended on thread timing).
    """
    flat = batch.instance_index.astype(np.int64)[episodes] * n_actions + np.asarray(index, dtype=np.int64)
    split = batch.split if isinstance(batch.split, str) else np.asarray(batch.split, dtype=object)
    if isinstance(split, str) or (len(split) and bool((split == split[0]).all())):
        # One split (a run's batch, even where it names the split per episode): no factorizing, one name.
        name = str(split if isinstance(split, str) else split[0])
        _, first, inverse = np.unique(flat, return_index=True, return_inverse=True)
        return first, np.asarray(inverse).reshape(-1), [(name, f) for f in flat[first].tolist()]
    import pandas as pd

    codes, names = pd.factorize(split[episodes])
    codes, names = codes.astype(np.int64), list(names)
    _, first, inverse = np.unique(flat * max(len(names), 1) + codes, return_index=True, return_inverse=True)
    keys = [(str(names[c]), f) for c, f in zip(codes[first].tolist(), flat[first].tolist())]
    return first, np.asarray(inverse).reshape(-1), keys


def _realized_many(simulator, truths: np.ndarray, actions: np.ndarray, contexts: np.ndarray | None) -> list:
    """``simulator.realized_many`` (each row's realized outcome or the error it raised), or for a
    simulator without it, ``tasks.base.CachedSimulator.realized_many``'s call of ``execute`` a row."""
    many = getattr(simulator, "realized_many", None)
    if many is None:
        return CachedSimulator.realized_many(simulator, truths, actions, contexts)
    return many(truths, actions, contexts)


def _execute(simulator, batch: ProbeBatch, action: np.ndarray, index: np.ndarray, n_actions: int,
             outcomes: dict):
    """Realized outcome of each episode's action: one ``execute`` per distinct (instance, action).

    Repeats of an instance that commit to the same action share one call, and
    ``outcomes`` remembers each answer across commits on the same batch (the engine
    answer is cached anyway; this saves the per-call overhead), under :func:`outcome_keys`.
    An error marks every episode of that (instance, action) failed, with the reason.
    """
    n = batch.n_episodes
    status = np.full(n, "ok", dtype=object)
    error = np.full(n, "", dtype=object)
    first, inverse, keys = outcome_keys(batch, np.arange(n), index, n_actions)
    context = batch.episode_context
    values = np.empty(len(keys))
    errors: dict[int, str] = {}
    if simulator.parallel_queries:
        # Every distinct action's engine query is needed below: run them in engine threads first.
        simulator.prefetch([simulator.execute_query_key(batch.truths[e], action[e], None if context is None else context[e])
                            for key, e in zip(keys, first) if key not in outcomes])
    todo = [u for u, key in enumerate(keys) if key not in outcomes]
    if todo:
        rows = first[todo]
        answers = _realized_many(simulator, batch.truths[rows], action[rows], None if context is None else context[rows])
        for u, answer in zip(todo, answers):  # an error marks the episodes, the study goes on
            outcomes[keys[u]] = f"execute: {type(answer).__name__}: {answer}" if isinstance(answer, Exception) else answer
    for u, key in enumerate(keys):
        value = outcomes[key]
        if isinstance(value, str):
            values[u], errors[u] = np.nan, value
        else:
            values[u] = value
    realized = values[inverse]
    for u, message in errors.items():
        rows = inverse == u
        status[rows], error[rows] = "failed", message
    return realized, status, error


def failed_episode_rows(batch: ProbeBatch, variant: str) -> pd.DataFrame:
    """Episode rows for trajectories whose rollout failed (kept, counted, never scored)."""
    import pandas as pd

    return pd.DataFrame(failed_episode_columns(batch, variant))


def failed_episode_columns(batch: ProbeBatch, variant: str) -> dict[str, Any]:
    """:func:`failed_episode_rows`' columns."""
    bad = np.flatnonzero(batch.status != "ok")
    return (
        {
            "instance_id": batch.instance_id[bad].astype(str),
            "repeat": batch.repeat[bad].astype(np.int64),
            "k": np.int64(0),
            "method": "rollout",
            "variant": variant,
            "status": "failed",
            "error": batch.error[bad].astype(str),
        }
    )
