"""The task contracts: an analytic TaskModel, an engine Simulator and a TaskSpec.

A task never owns an engine. The model is NumPy only and vectorized over episodes
and particles; the simulator answers named queries against ground truth. Rollout
(simulator) and inference (model) are separate: runs store every probe, and beliefs
are recomputed from stored probes.

Shapes (``E`` episodes, ``N`` particles, ``d`` latents, ``p`` probe components,
``m`` observation components, ``a`` action components, ``A`` grid actions):

* probes ``u[E, p]``, observations ``y[E, m]``, actions ``[A, a]``;
* particles ``theta[E, N, d]``; an optional observed *context* per episode
  ``context[E, c]`` (a target position, say) that the loss may depend on.

Family-specific behaviour the generic executors need (the tie-break reference, how a
grown set fills the non-decision latents, the margin) is a named method of the
model; :class:`TaskModelBase` gives the defaults a family overrides.
"""

from __future__ import annotations

import json
import os
import struct
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field, fields, is_dataclass, replace
from typing import Any, Callable, Iterable, Iterator, Protocol, runtime_checkable

import numpy as np

from probecommit.core.retained import median_over_particles


@runtime_checkable
class TaskModel(Protocol):
    """Analytic model of one task family (see the module docstring for shapes).

    Attributes:
        name: Family name (``"insertion"``).
        variant: Model variant label stored in episode tables (``"deployed"``).
        latent_names: Names of the latent coordinates, in column order (``d``).
        context_names: Names of the observed per-episode context (``c``; may be empty).
        prior_low, prior_high: Box prior ``[d]``.
        jitter_scale: Post-resampling jitter standard deviations ``[d]``.
        sigma: Observation noise the likelihood assumes.
        probe_grid: Admissible probes ``[P, p]``.
        action_grid: Admissible commit actions ``[A, a]``.
        binary_loss: True when the loss is failure (0/1), False for a continuous miss.
        decision_domain_width: ``D``, width of the decision coordinate's domain.
    """

    name: str
    variant: str
    latent_names: tuple[str, ...]
    context_names: tuple[str, ...]
    prior_low: np.ndarray
    prior_high: np.ndarray
    jitter_scale: np.ndarray
    sigma: float
    probe_grid: np.ndarray
    action_grid: np.ndarray
    binary_loss: bool
    decision_domain_width: float
    #: The few distinct noise-free readings of ``predict`` (a tap reads the floor or the top), or
    #: None (the default on :class:`TaskModelBase`): see :class:`~probecommit.core.belief.ForwardModel`.
    reading_levels: tuple[float, ...] | None

    @property
    def probe_dim(self) -> int: ...

    @property
    def observation_dim(self) -> int: ...

    @property
    def action_dim(self) -> int: ...

    def predict(self, u: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Noise-free observation ``[E, N, m]`` for probes ``u[E, p]`` and ``theta[E, N, d]``."""

    def loss(self, actions: np.ndarray, theta: np.ndarray, context: np.ndarray | None = None) -> np.ndarray:
        """Modeled loss ``[E, A, N]`` (bool failures when ``binary_loss``)."""

    def decision(self, theta: np.ndarray) -> np.ndarray:
        """Decision coordinate ``z(theta)``: ``[..., d] -> [...]``."""

    def tie_break_cost(self, actions: np.ndarray, reference: np.ndarray, context: np.ndarray | None = None) -> np.ndarray:
        """``[E, A]`` secondary cost among equally scored actions, from a belief reference ``[E, d]``."""

    def grown_scenarios(self, particles: np.ndarray, z_points: np.ndarray) -> np.ndarray:
        """Scenarios ``[E, n, d]`` at decision coordinates ``z_points[E, n]``, other latents from the belief."""

    def with_margin(self, gamma: float) -> "TaskModel":
        """The same model scoring actions with margin ``gamma`` (1 = none)."""

    def success_interval(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """Open interval of 1-D actions that succeed per scenario, or None (no fast path)."""

    def success_interval_parts(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The success interval as ``(centre, half)`` at margin one, or None: the interval is
        ``centre -+ half * margin``, bit for bit. Both parts are margin-free, so a margin search
        computes them once per retained set; ``half`` is a new array the caller may modify."""

    def success_interval_affine(self) -> tuple[int, int, float, float] | None:
        """``(centre_at, width_at, slope, intercept)`` when :meth:`success_interval_parts` is
        ``(theta[..., centre_at], slope * theta[..., width_at] + intercept)``, bit for bit; else
        None. A compiled count then reads both parts from the scenarios in place."""

    def sample_prior(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` draws ``[n, d]`` from the prior."""


def as_rows(values: Any, dim: int, what: str) -> np.ndarray:
    """Coerce a list of scalars or vectors to a float array ``[n, dim]``.

    Raises:
        ValueError: the components do not match ``dim``.
    """
    arr = np.asarray(values, dtype=float)
    if arr.ndim == 1 and dim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise ValueError(f"{what} must have {dim} component(s) per entry, got shape {arr.shape}")
    return arr


class TaskModelBase:
    """Defaults for the named hooks of :class:`TaskModel`; a family overrides what differs.

    Subclasses set the class or instance attributes of the Protocol. Grids are stored
    as ``[P, p]`` and ``[A, a]``.
    """

    context_names: tuple[str, ...] = ()
    variant: str = "deployed"
    #: Physical range ``(low, high)`` of every reading component: a Session refuses a reading
    #: outside it (a sensor fault), and check_family reads it. Unbounded by default.
    observation_range: tuple[float, float] = (-np.inf, np.inf)
    #: The few distinct noise-free readings ``predict`` can return (a tap reads the floor or the
    #: top), or None: a filter then tabulates the likelihood per level instead of per particle.
    reading_levels: tuple[float, ...] | None = None

    @property
    def probe_dim(self) -> int:
        return int(np.asarray(self.probe_grid).shape[1])

    @property
    def observation_dim(self) -> int:
        return int(self.predict(np.asarray(self.probe_grid)[:1], self.sample_prior(np.random.default_rng(0), 1)[None]).shape[-1])

    @property
    def action_dim(self) -> int:
        return int(np.asarray(self.action_grid).shape[1])

    def decision(self, theta: np.ndarray) -> np.ndarray:
        """Default decision coordinate: latent 0."""
        return np.asarray(theta)[..., 0]

    def tie_break_cost(self, actions: np.ndarray, reference: np.ndarray, context: np.ndarray | None = None) -> np.ndarray:
        """Default: the modeled loss of each action for the reference scenario (then lowest index)."""
        return self.loss(actions, np.asarray(reference)[:, None, :], context)[:, :, 0].astype(float)

    def grown_scenarios(self, particles: np.ndarray, z_points: np.ndarray,
                        centre: np.ndarray | None = None) -> np.ndarray:
        """Default: each point at the particles' per-coordinate median, its decision coordinate set.

        Valid for families whose decision coordinate is latent 0 (the default ``decision``);
        a family with another decision coordinate overrides this. ``centre`` is
        :meth:`grown_centre` of these particles when the caller kept it from another threshold.
        """
        centre = self.grown_centre(particles) if centre is None else centre
        extra = np.repeat(centre[:, None, :], z_points.shape[1], axis=1)
        extra[..., 0] = z_points
        return extra

    #: This ``grown_scenarios`` takes the belief-wide part, ``centre``, from its caller (an override does not):
    #: a calibration grows each belief's set under ``t_k`` and ``t``, and the median is the same for both.
    grown_scenarios.takes_centre = True  # type: ignore[attr-defined]

    def grown_centre(self, particles: np.ndarray) -> np.ndarray:
        """``[E, d]``: the default grown scenarios' other latents, the particles' median (latent 0 is
        replaced by the points' decision coordinate, so its median is not computed: zero)."""
        particles = np.asarray(particles)
        centre = np.zeros((particles.shape[0], particles.shape[2]))
        if particles.shape[2] > 1:
            centre[:, 1:] = median_over_particles(particles[:, :, 1:])
        return centre

    def check_sigma_and_margin(self) -> None:
        """Refuse a likelihood sigma that is not positive and finite, or a margin outside (0, 1.5]."""
        sigma, margin = self.sigma, self.margin  # type: ignore[attr-defined]
        if not (np.isfinite(sigma) and sigma > 0):
            raise ValueError(f"sigma must be positive, got {sigma!r}")
        if not 0 < margin <= 1.5:
            raise ValueError(f"margin gamma must be in (0, 1.5], got {margin!r}")

    def with_margin(self, gamma: float) -> "TaskModelBase":
        """The same model with margin ``gamma`` (a dataclass model with a ``margin`` field; the
        modeled miss or window scales with it, so actions keep their order and scores grow)."""
        if is_dataclass(self) and any(f.name == "margin" for f in fields(self)):
            return replace(self, margin=float(gamma))
        raise NotImplementedError(f"the {self.name} model has no execution margin")

    def success_interval(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """``centre -+ half * margin`` from :meth:`success_interval_parts` (None without them)."""
        parts = self.success_interval_parts(theta)
        if parts is None:
            return None
        centre, half = parts
        half *= self.margin  # in place: half is the model's own new array
        return centre - half, centre + half

    def success_interval_parts(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        return None

    def success_interval_affine(self) -> tuple[int, int, float, float] | None:
        return None

    def sample_prior(self, rng: np.random.Generator, n: int) -> np.ndarray:
        low, high = np.asarray(self.prior_low, float), np.asarray(self.prior_high, float)
        return low + (high - low) * rng.random((n, low.shape[0]))


@runtime_checkable
class Simulator(Protocol):
    """Ground-truth side of one task family in one engine.

    ``probe`` returns a noisy reading ``[m]`` drawn with the episode's generator;
    ``execute`` commits an action ``[a]`` once and returns the realized outcome, with
    at least the key ``"realized"`` (failure 0/1 or miss).
    """

    engine: str
    engine_calls: dict[str, int]
    engine_seconds: float
    #: Named queries may run in engine threads (:meth:`CachedSimulator.prefetch`); then the
    #: simulator writes :meth:`probe_query_key` and :meth:`execute_query_key`. Default False.
    parallel_queries: bool
    #: Two instances may be used from two threads at once (a study runs units in threads). Default False.
    thread_safe: bool

    def probe(self, theta: np.ndarray, u: np.ndarray, rng: np.random.Generator) -> np.ndarray: ...

    def execute(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> dict[str, Any]: ...

    def probe_query_key(self, theta: np.ndarray, u: np.ndarray) -> tuple: ...

    def execute_query_key(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> tuple: ...

    def cache_records(self) -> list[dict[str, Any]]: ...

    def load_cache(self, records: Iterable[dict[str, Any]]) -> list: ...

    def answered_keys(self) -> list: ...

    def forget_answers(self, keys: Iterable[tuple[str, tuple[float, ...], tuple[float, ...]]]) -> None: ...


#: Engine answers shared by the simulators built inside :func:`shared_engine_answers`, per
#: ground truth (family, engine, simulator settings); None outside such a block.
_ANSWER_STORE: dict[str, dict] | None = None


@contextmanager
def shared_engine_answers() -> Iterator[dict[str, dict]]:
    """Within this block, simulators of the same ground truth share their engine answers.

    Every simulator the registry builds inside the block (same family, engine and
    simulator settings) looks an answer up in one store before running its engine, so a
    query is run once per process however many runs and replays ask it (a reproduction).
    Each simulator still records every answer it used (its run's engine cache is the same
    as without the block); its ``engine_calls`` count only the queries its engine ran.
    Nested blocks share the outer store. Units run in worker processes do not share.
    """
    global _ANSWER_STORE
    if _ANSWER_STORE is not None:
        yield _ANSWER_STORE
        return
    _ANSWER_STORE = {}
    try:
        yield _ANSWER_STORE
    finally:
        _ANSWER_STORE = None


def answer_store(family: str, engine: str, settings: dict[str, Any]) -> dict | None:
    """The shared answers of a ground truth (family, engine, simulator settings) inside
    :func:`shared_engine_answers`, else None."""
    if _ANSWER_STORE is None:
        return None
    identity = json.dumps([family, engine, settings], sort_keys=True, default=str)
    return _ANSWER_STORE.setdefault(identity, {})


def _key_part(values: Iterable[float]) -> tuple[float, ...]:
    """A query argument as a tuple of Python floats (a cache key; one call per engine query, so kept lean)."""
    if isinstance(values, np.ndarray):
        return tuple(values.astype(float, copy=False).ravel().tolist())
    return tuple(map(float, values))


#: Environment variable: engine threads for :meth:`CachedSimulator.prefetch` (1 turns them off).
ENGINE_THREADS_ENV = "PROBECOMMIT_ENGINE_THREADS"
_POOL: ThreadPoolExecutor | None = None
_POOL_LOCK = threading.Lock()


@dataclass(frozen=True)
class AnswerColumns:
    """Stored engine answers as columns (``store.schema.cache_records``): iterated, the records
    :meth:`CachedSimulator.load_cache` takes, one dict a row; given whole to ``load_cache``, taken
    a column at a time.

    Why: a calibration in chunks gives its simulator each chunk's stored answers on every pass
    (issue 42): some 30,000 records at E = 3072, built and read one dict at a time on the main
    thread (~10 us each). As columns, the distinct latents, arguments and answers are found
    by their bytes in one NumPy pass, and only the keys are made per row.

    Attributes:
        engines, queries: Per row, the engine and the query name.
        thetas: ``[R, d]`` latent values.
        args, values: ``[R, a]`` and ``[R, v]`` float arrays, or (rows of different lengths) lists of 1-D arrays.
    """

    engines: list
    queries: list
    thetas: np.ndarray
    args: Any
    values: Any

    def __len__(self) -> int:
        return len(self.engines)

    def __iter__(self) -> Iterator[dict[str, Any]]:
        for e, q, t, a, v in zip(self.engines, self.queries, self.thetas, self.args, self.values):
            yield {"engine": e, "query": q, "theta": t.tolist(), "arg": a.tolist(), "value": v.tolist()}

    @staticmethod
    def join(parts: list["AnswerColumns"]) -> "AnswerColumns":
        """Several tables' answers as one, in order (arrays stacked where their widths agree)."""
        if len(parts) == 1:
            return parts[0]

        def stacked(columns: list) -> Any:
            if all(isinstance(c, np.ndarray) for c in columns) and len({c.shape[1:] for c in columns}) == 1:
                return np.concatenate(columns)
            return [row for c in columns for row in c]

        return AnswerColumns([e for p in parts for e in p.engines], [q for p in parts for q in p.queries],
                             stacked([p.thetas for p in parts]), stacked([p.args for p in parts]),
                             stacked([p.values for p in parts]))


def _distinct_rows(rows: np.ndarray, make: Callable[[list], Any]) -> list:
    """Per row of a float matrix, one object per distinct row (``make`` of its floats), matched by
    the rows' bytes (so -0.0 and 0.0, or two NaNs' payloads, stay apart): what
    :meth:`CachedSimulator.load_cache` shares row by row, for a whole column at once."""
    if not len(rows):
        return []
    if rows.shape[1] == 0:
        return [make([])] * len(rows)
    bits = np.ascontiguousarray(rows, dtype=float).view(np.int64)
    _, first, inverse = np.unique(bits, axis=0, return_index=True, return_inverse=True)
    made = [make(row) for row in rows[first].tolist()]
    return [made[i] for i in np.asarray(inverse).reshape(-1).tolist()]


def _read_only(row: list) -> np.ndarray:
    """A stored answer's array: a copy of its floats, read-only (shared by every caller)."""
    value = np.array(row, dtype=float)
    value.flags.writeable = False
    return value


def _forget_pool_in_child() -> None:
    """A forked child has none of the parent's threads: it makes its own pool on first use."""
    global _POOL, _POOL_LOCK
    _POOL, _POOL_LOCK = None, threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_pool_in_child)


def engine_threads() -> int:
    """Threads that answer engine queries at once: ``$PROBECOMMIT_ENGINE_THREADS``, else the
    CPUs this process may use (at most 4).

    Raises:
        ValueError: The variable is set to something other than a positive integer.
    """
    text = os.environ.get(ENGINE_THREADS_ENV, "").strip()
    if text:
        if not text.isdigit() or int(text) < 1:
            raise ValueError(f"{ENGINE_THREADS_ENV} must be a positive integer, got {text!r}")
        return int(text)
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, min(4, cpus))


def _engine_pool(threads: int) -> ThreadPoolExecutor:
    """The process's engine threads (kept: a thread keeps its engine buffers between batches)."""
    global _POOL
    with _POOL_LOCK:
        if _POOL is None or _POOL._max_workers != threads:  # noqa: SLF001 - the size it was made with
            if _POOL is not None:
                _POOL.shutdown(wait=True)
            _POOL = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="probecommit-engine")
        return _POOL


class CachedSimulator:
    """Base for simulators: every deterministic engine query is run once and cached.

    A family's simulator answers named queries ``kind(theta, arg) -> value`` that are
    pure functions of their arguments; :meth:`cached` caches them per
    ``(kind, theta, arg)``, counts engine calls and time, and the cache persists in the
    run directory (``store.schema.ENGINE_CACHE_COLUMNS``) so replays never re-run one.
    """

    engine = "abstract"
    #: Constructor settings applied outside the named queries (reading noise, a frame offset
    #: added to the action before the query): simulators that differ only in these give the
    #: same engine answers, so :func:`shared_engine_answers` lets them share.
    answer_independent_settings: tuple[str, ...] = ()
    #: Whether the named queries may run in several threads at once (each thread with its own
    #: engine buffers, the engine releasing the GIL while it steps): :meth:`prefetch` then runs
    #: a batch of them in engine threads. Off unless an engine's simulator says so.
    parallel_queries: bool = False
    #: Whether two simulators of this class may be used from two threads at once (no state
    #: shared between instances but under a lock): a study then runs its work units in threads
    #: (``runner.study.run_study``). Off unless a simulator says so.
    thread_safe: bool = False

    def __init__(self) -> None:
        self._cache: dict[tuple[str, tuple[float, ...], tuple[float, ...]], np.ndarray] = {}
        #: Answers shared with other simulators of the same ground truth (``shared_engine_answers``).
        self.shared_answers: dict | None = None
        self.engine_calls: dict[str, int] = {}
        self.engine_seconds = 0.0

    def probe_query_key(self, theta: np.ndarray, u: np.ndarray) -> tuple:
        """The cache key of the one engine query behind ``probe(theta, u, ...)``, for :meth:`prefetch`:
        read only when :attr:`parallel_queries` is set, which a simulator sets together with this."""
        raise NotImplementedError(f"{type(self).__name__} sets parallel_queries but writes no probe_query_key")

    def execute_query_key(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> tuple:
        """The cache key of the one engine query behind ``execute(theta, action, context)`` (see
        :meth:`probe_query_key`)."""
        raise NotImplementedError(f"{type(self).__name__} sets parallel_queries but writes no execute_query_key")

    def cached(self, kind: str, theta: Iterable[float], arg: Iterable[float]) -> np.ndarray:
        """Cached named query ``self.<kind>(*theta, *arg)``; the engine runs once per key."""
        return self.cached_key((kind, _key_part(theta), _key_part(arg)))

    def cached_key(self, key: tuple[str, tuple[float, ...], tuple[float, ...]]) -> np.ndarray:
        """:meth:`cached` for a key already built: ``(kind, theta floats, arg floats)``."""
        hit = self._cache.get(key)
        if hit is None:
            shared = self.shared_answers
            hit = None if shared is None else shared.get(key)
            if hit is None:
                start = time.perf_counter()
                hit = self._engine_answer(key)
                self._record(key, hit, time.perf_counter() - start)
            else:
                self._cache[key] = hit
        return hit

    def _engine_answer(self, key: tuple[str, tuple[float, ...], tuple[float, ...]]) -> np.ndarray:
        """Run the engine for one query: its answer as a float vector (neither cached nor counted)."""
        # A copy: the answer is made read-only and shared, never the engine's own buffer.
        return np.atleast_1d(np.array(getattr(self, key[0])(*key[1], *key[2]), dtype=float))

    def _record(self, key: tuple[str, tuple[float, ...], tuple[float, ...]], answer: np.ndarray, seconds: float) -> None:
        """Count an answer the engine just gave and keep it (in the shared answers too)."""
        self.engine_seconds += seconds
        self.engine_calls[key[0]] = self.engine_calls.get(key[0], 0) + 1
        answer.flags.writeable = False  # shared by every caller that asks the same query
        if self.shared_answers is not None:
            self.shared_answers[key] = answer
        self._cache[key] = answer

    def prefetch(self, keys: Iterable[tuple[str, tuple[float, ...], tuple[float, ...]]]) -> int:
        """Answer the queries ``keys`` not answered yet, several at once in engine threads.

        What a caller is about to ask for anyway (every distinct action of a commit), run
        ahead in parallel: the answers are the engine's own (a query is a pure function of
        its key), cached in the order given, and counted as if asked one by one. Does
        nothing unless :attr:`parallel_queries` and :func:`engine_threads` > 1. A query that
        raises is left unanswered, so the caller's own request raises it where it is handled.

        Returns:
            The number of queries run.
        """
        threads = engine_threads() if self.parallel_queries else 1
        if threads < 2:
            return 0
        shared = self.shared_answers
        missing: list[tuple[str, tuple[float, ...], tuple[float, ...]]] = []
        seen: set = set()
        for key in keys:
            if key in seen or key in self._cache or (shared is not None and key in shared):
                continue
            seen.add(key)
            missing.append(key)
        if len(missing) < 2:
            return 0

        def answer(key):
            start = time.perf_counter()
            try:
                value = self._engine_answer(key)
            except Exception:  # noqa: BLE001 - re-raised by the caller's own request
                value = None
            return value, time.perf_counter() - start

        run = 0
        for key, (value, seconds) in zip(missing, _engine_pool(threads).map(answer, missing)):
            if value is not None:
                run += 1
                self._record(key, value, seconds)
        return run

    def cache_records(self, keys: Iterable[tuple[str, tuple[float, ...], tuple[float, ...]]] | None = None
                      ) -> list[dict[str, Any]]:
        """Cache rows: engine, query, theta and arg tuples, value vector; of every answer held, or of ``keys``."""
        items = self._cache.items() if keys is None else ((k, self._cache[k]) for k in keys)
        return [{"engine": self.engine, "query": k[0], "theta": list(k[1]), "arg": list(k[2]), "value": v.tolist()}
                for k, v in items]

    def answer_columns(self, keys: list[tuple[str, tuple[float, ...], tuple[float, ...]]]) -> AnswerColumns | None:
        """:meth:`cache_records` of ``keys`` as columns (``AnswerColumns``: the same rows, iterated),
        without a dict a row; None where the keys' latents, arguments or answers differ in length."""
        if not keys:
            return None
        try:
            columns = [np.asarray([key[1] for key in keys], dtype=float), np.asarray([key[2] for key in keys], dtype=float),
                       np.asarray([self._cache[key] for key in keys], dtype=float)]
        except ValueError:  # rows of different lengths
            return None
        if any(column.ndim != 2 for column in columns):
            return None
        return AnswerColumns([self.engine] * len(keys), [key[0] for key in keys], *columns)

    def answered_keys(self) -> list[tuple[str, tuple[float, ...], tuple[float, ...]]]:
        """The keys of every answer held (taken by :meth:`load_cache` or given by the engine)."""
        return list(self._cache)

    def realized_many(self, thetas: np.ndarray, actions: np.ndarray,
                      contexts: np.ndarray | None = None) -> list[float | Exception]:
        """Per row, ``float(execute(theta, action, context)["realized"])``, or the error it raised:
        a commit's distinct (instance, aim) pairs executed in one call (``runner.inference``).
        Rows are executed in order, so the engine is asked (and counted) as one call each would.
        A simulator whose commit is one cached query may answer the rows without a call each."""
        out: list[float | Exception] = []
        for row in range(len(thetas)):
            try:
                out.append(float(self.execute(thetas[row], actions[row], None if contexts is None else contexts[row])
                                 ["realized"]))
            except Exception as exc:  # noqa: BLE001 - the caller marks the episodes failed
                out.append(exc)
        return out

    def load_cache(self, records: Iterable[dict[str, Any]]) -> list[tuple[str, tuple[float, ...], tuple[float, ...]]]:
        """Take stored answers (``cache_records`` rows of this engine; other engines' are skipped).

        Returns:
            The keys of the answers taken, for :meth:`forget_answers`.
        """
        if isinstance(records, AnswerColumns) and all(isinstance(c, np.ndarray) and c.ndim == 2 for c in
                                                      (records.thetas, records.args, records.values)):
            return self._load_columns(records)
        # A run asks many queries of few latents and answers few distinct values: equal tuples
        # and values are stored once (matched by their bytes, so -0.0 stays -0.0), read-only.
        shared: dict[tuple, Any] = {}  # (kind, bytes) -> the one object kept
        taken = []

        def once(kind: str, items: tuple) -> Any:
            packed = (kind, struct.pack(f"{len(items)}d", *items))
            return shared.setdefault(packed, items)

        for r in records:
            if r["engine"] == self.engine:
                theta = once("theta", tuple(map(float, r["theta"])))
                arg = once("arg", tuple(map(float, r["arg"])))
                value = np.array(r["value"], dtype=float)  # a copy: the caller's arrays stay writable
                value = shared.setdefault(("value", value.shape, value.tobytes()), value)
                value.flags.writeable = False
                # One string object per query name, not one per row read from a table.
                key = (sys.intern(str(r["query"])), theta, arg)
                self._cache[key] = value
                taken.append(key)
        return taken

    def _load_columns(self, answers: AnswerColumns) -> list[tuple[str, tuple[float, ...], tuple[float, ...]]]:
        """:meth:`load_cache` of answers as columns: the same keys, values and sharing (one tuple
        per distinct latent and argument, one read-only array per distinct answer), each distinct
        one made once for the whole column."""
        mine = [i for i, engine in enumerate(answers.engines) if engine == self.engine]
        if len(mine) < len(answers):
            answers = AnswerColumns([answers.engines[i] for i in mine], [answers.queries[i] for i in mine],
                                    answers.thetas[mine], answers.args[mine], answers.values[mine])
        names = {q: sys.intern(str(q)) for q in set(answers.queries)}
        keys = list(zip([names[q] for q in answers.queries], _distinct_rows(answers.thetas, tuple),
                        _distinct_rows(answers.args, tuple)))
        self._cache.update(zip(keys, _distinct_rows(answers.values, _read_only)))
        return keys

    def forget_answers(self, keys: Iterable[tuple[str, tuple[float, ...], tuple[float, ...]]]) -> None:
        """Drop the answers of ``keys`` (a replay's finished chunk of instances: those :meth:`load_cache`
        took, and those the engine gave once the caller has kept them elsewhere). A query of a
        dropped key later runs the engine again unless its answer is given back first."""
        for key in keys:
            self._cache.pop(key, None)


class NoisySimulator(CachedSimulator):
    """A cached simulator whose readings carry Gaussian noise of ``noise_sigma`` (validated once here).

    Args:
        noise_sigma: Standard deviation of the noise added to every reading (>= 0).
    """

    answer_independent_settings = ("noise_sigma",)  # noise is added to a query's answer, never inside it

    def __init__(self, noise_sigma: float) -> None:
        super().__init__()
        if not (np.isfinite(noise_sigma) and noise_sigma >= 0):
            raise ValueError(f"noise_sigma must be >= 0, got {noise_sigma!r}")
        self.noise_sigma = float(noise_sigma)


class TargetMissSimulator(NoisySimulator):
    """Ground truth of a family whose probe and commit both run one named scalar query and whose
    commit should land on a target (the context): a slide, a coast, a throw.

    A probe reads ``query(theta, u)`` plus noise; a commit's realized outcome is the miss
    ``|query(theta, action) - target|``. Subclasses define the query method and name it.

    Attributes:
        query: Name of the named query method (``"slide"``, ``"coast"``, ...).
        outcome: Key of the query's raw value in ``execute``'s result.
        target: What the context is, for the error message (``"target distance"``).
        not_finite: Message when the engine returns a non-finite value (``{action}`` is filled in).
    """

    query = "?"
    #: The named query a commit runs, when not ``query`` (a commit that is another push than the probe).
    commit_query: str | None = None
    outcome = "value"
    target = "target"
    not_finite = "{engine} {query} returned a non-finite value for action {action}"

    def probe(self, theta: np.ndarray, u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        clean = self.cached(self.query, theta, np.ravel(u))
        return clean + self.noise_sigma * rng.standard_normal(1)

    def execute(self, theta: np.ndarray, action: np.ndarray, context: np.ndarray | None = None) -> dict[str, Any]:
        if context is None:
            raise ValueError(f"the {self.family} outcome needs the {self.target} (context)")
        value = float(self.cached(self.commit_query or self.query, theta, np.ravel(action))[0])
        if not np.isfinite(value):
            raise FloatingPointError(self.not_finite.format(engine=self.engine, query=self.query,
                                                            action=np.ravel(action).tolist()))
        return {"realized": abs(value - float(np.ravel(context)[0])), self.outcome: value}


@dataclass(frozen=True)
class TaskSpec:
    """What a family registers (dm_control suite / Gymnasium ``register`` style).

    Attributes:
        name: Family name; the config's ``task`` key.
        config: Pydantic model of the family's config (a ``family`` literal, ``model`` and
            ``simulator`` sections); one branch of the study config's discriminated union.
        build_model: ``build_model(task_config) -> TaskModel``.
        simulators: Engine name -> lazy ``"module:Class"`` entry point (or the class itself); the class is
            constructed as ``Class(**task_config.simulator_kwargs())``.
        summary: One row of the paper's Table II as the code has it: ``latents``,
            ``probe``, ``action``, ``sigma``, ``budgets``, ``metric``.
        example: Study-config fields for a small example study of this family (what a
            family needs beyond defaults, e.g. ``instances.contexts``); the conformance
            suite runs it in every engine.
        default: The family a config naming no ``task`` runs (one family only: the paper's
            primary testbed); generic code never names a family.
        replay_shorthands: ``probecommit replay``'s ``--model``/``--delta`` as model-section
            fields of this family (``{"model": "boundary", "delta": "delta"}``) and the
            ``--model`` value used when none is given (``"model_default"``); empty: the family
            takes ``--set model.FIELD=VALUE`` only.
        figure_guides: ``figure_guides(model) -> {name: value}``: reference lines of the robot
            audit's aim-error figure (``window``, ``half_gap``); None: the generic window only.
        declaration: The :class:`~probecommit.tasks.declare.Declaration` the spec was derived
            from (None for a family written by hand).
    """

    name: str
    config: type
    build_model: Callable[[Any], Any]
    simulators: dict[str, Any]
    summary: dict[str, str] = field(default_factory=dict)
    example: dict[str, Any] = field(default_factory=dict)
    default: bool = False
    replay_shorthands: dict[str, str] = field(default_factory=dict)
    figure_guides: Callable[[Any], dict[str, float]] | None = None
    declaration: Any = None

    @property
    def engines(self) -> tuple[str, ...]:
        return tuple(self.simulators)
