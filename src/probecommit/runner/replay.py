"""Replays: recompute beliefs and episodes from stored probes under another model.

Both arms of a comparison then see identical probes, and the engine is consulted
only through the run's engine cache (a query the run never made is computed, and
needs the engine installed).
"""

from __future__ import annotations

import contextlib
import logging
import time
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, Mapping, Sequence

import numpy as np
import pandas as pd
import pyarrow as pa

from probecommit.core.belief import BeliefState, ParticleFilter
from probecommit.process.memory import large_arrays_apart, trim_heap
from probecommit.runner.build import build_executors, build_filter, build_model, build_simulator, config_executors
from probecommit.runner.config import StudyConfig, config_data, dump_config, parse_config
from probecommit.runner.inference import (
    BeliefTrace,
    ProbeBatch,
    build_trace,
    commit,
    instance_arrays,
    prune_retained_sets,
)
from probecommit.store.probes import validate_probes
from probecommit.store.rundir import RunDir
from probecommit.store.yamlsafe import load_yaml
from probecommit.store.schema import answers_frame, cache_frame, cache_records, component_names
from probecommit.tasks.base import AnswerColumns

import yaml
from probecommit.errors import UsageError

logger = logging.getLogger(__name__)


class LoadedRun:
    """A complete run directory: its config, instances and manifest in memory, and its probes,
    episodes and engine cache read when first asked for.

    ``loaded.probes`` (and ``episodes``, ``engine_cache``) reads the table once and keeps it.
    :meth:`table` gives a table without keeping it, or only some of its rows: a replay or a
    calibration reads each run's tables once, into what it holds (probe arrays, the engine
    cache of a simulator), so the tables themselves do not stay in memory beside them.
    Tables passed in (a re-split's share of a run) are kept and used as they are.

    Args:
        beliefs: Beliefs already computed for exactly these episodes (a re-split's share of
            its pool's, ``RunBeliefs.restrict``); calibration then recomputes none. None:
            computed from the probes.
    """

    TABLES = ("probes", "episodes", "engine_cache")

    def __init__(self, path: str | Path, config: StudyConfig, instances: pd.DataFrame,
                 probes: pd.DataFrame | None = None, episodes: pd.DataFrame | None = None,
                 engine_cache: pd.DataFrame | None = None, manifest: dict[str, Any] | None = None,
                 beliefs: "RunBeliefs | None" = None) -> None:
        self.path = Path(path)
        self.config = config
        self.instances = instances
        self.manifest = manifest if manifest is not None else {}
        self.beliefs = beliefs
        self._held: dict[str, pd.DataFrame | None] = {"probes": probes, "episodes": episodes,
                                                      "engine_cache": engine_cache}

    def table(self, name: str, where: tuple[str, list] | None = None,
              columns: Sequence[str] | None = None) -> pd.DataFrame:
        """Table ``name``, not kept by this object unless it already was; with ``where =
        (column, values)``, only the rows whose ``column`` is among ``values`` (original order);
        with ``columns``, only those columns (the others are not read).
        A table read from the run directory is checked against the manifest's sha256 again."""
        held = self._held[name]
        if held is None:
            return RunDir(self.path).read_verified(name, where, columns)
        rows = held if where is None else held.loc[held[where[0]].isin(list(where[1]))]
        return rows if columns is None else rows[list(columns)]

    def arrow_table(self, name: str) -> pa.Table:
        """Table ``name`` as an Arrow table (a few column buffers), not kept by this object."""
        held = self._held[name]
        if held is None:
            return RunDir(self.path).read_verified_arrow(name)
        return pa.Table.from_pandas(held, preserve_index=False)

    def failed_rollouts(self) -> pd.DataFrame:
        """The episode rows of the trajectories whose probing failed (``method == "rollout"``,
        :func:`~probecommit.runner.inference.failed_episode_rows`), read without the other rows."""
        rollouts = self.table("episodes", where=("method", ["rollout"]))
        return rollouts.loc[rollouts["status"] == "failed"]

    def __repr__(self) -> str:
        held = [name for name, table in self._held.items() if table is not None]
        return f"LoadedRun({str(self.path)!r}, {len(self.instances)} instances, tables held: {held or 'none'})"

    def _kept(self, name: str) -> pd.DataFrame:
        if self._held[name] is None:
            self._held[name] = self.table(name)
        return self._held[name]

    probes = property(lambda self: self._kept("probes"), doc="The stored probes (read once, then kept).")
    episodes = property(lambda self: self._kept("episodes"), doc="The stored episodes (read once, then kept).")
    engine_cache = property(lambda self: self._kept("engine_cache"),
                            doc="Every engine answer the run stored (read once, then kept).")


def load_run(run_dir: str | Path) -> LoadedRun:
    """Open a complete run directory (refuses an incomplete or altered one); the large tables
    are read when first asked for (:class:`LoadedRun`)."""
    run = RunDir(run_dir)
    manifest = run.manifest()
    changed = run.verify_digests()
    if changed:
        raise run.altered(changed)
    config = parse_config(load_yaml(run.config_text(), str(run.path / "config.yaml")))
    return LoadedRun(run.path, config, run.read("instances"), manifest=manifest)


def probe_batch(loaded: LoadedRun, model: Any) -> ProbeBatch:
    """Rebuild the stored probe trajectories (successful episodes) as a batch.

    The table is read, validated and reshaped with every array above glibc's default 128 KiB
    threshold on pages of its own (:func:`~probecommit.process.memory.large_arrays_apart`): the
    table's temporaries (columns of E * K rows) then go back to the system when freed, instead of
    staying as heap fragments beside the batch, which grew what a replay of E = 3072 episodes
    holds afterwards by about 2 MB more than one of 384 did (``benchmarks/memory.py``).
    """
    with large_arrays_apart(TABLE_APART_BYTES):
        return _probe_batch(loaded, model)


#: :func:`probe_batch`'s threshold for arrays kept apart from the heap (glibc's default).
TABLE_APART_BYTES = 128 * 1024


def _probe_batch(loaded: LoadedRun, model: Any) -> ProbeBatch:
    # Validate first: a malformed table is refused naming column and row, never reshaped.
    probes = loaded.table("probes")
    u_cols, y_cols = component_names("u", model.probe_dim), component_names("y", model.observation_dim)
    if len(probes):  # empty when every trajectory failed in rollout
        probes = validate_probes(probes, str(loaded.path / "probes.parquet"),
                                 instance_ids=loaded.instances["instance_id"],
                                 probe_dim=model.probe_dim, observation_dim=model.observation_dim)
    # The run's own episode order: instance order of the instances table, then repeat, then j.
    # Worked on codes (an instance's position), not on each row's id string: a run holds E * K
    # probe rows of a few hundred distinct instances.
    inst_ids = loaded.instances["instance_id"].astype(str).to_numpy(object)
    codes, uniques = pd.factorize(probes["instance_id"])
    position = pd.Index(inst_ids).get_indexer(np.asarray(uniques, dtype=object))[codes]
    repeat, j = probes["repeat"].to_numpy(np.int64), probes["j"].to_numpy(np.int64)
    order = np.lexsort((j, repeat, position))  # every (instance, repeat, j) is given once (validated)
    position, repeat = position[order], repeat[order]
    first = np.flatnonzero((np.diff(position, prepend=-1) != 0) | (np.diff(repeat, prepend=-1) != 0))  # an episode's j = 1
    n_e = len(first)
    k = int(j.max()) if n_e else 0
    rows = loaded.instances.iloc[position[first]]
    truths, context = instance_arrays(rows, model)
    return ProbeBatch(
        split=rows["split"].astype(str).to_numpy(object),  # each episode's own (a pool of runs mixes splits)
        instance_id=inst_ids[position[first]],
        instance_index=rows["instance_index"].to_numpy(np.int64),
        repeat=repeat[first],
        truths=truths,
        u=probes[u_cols].to_numpy(float)[order].reshape(n_e, k, len(u_cols)),
        y=probes[y_cols].to_numpy(float)[order].reshape(n_e, k, len(y_cols)),
        context=context,
    )


def simulator_for_run(loaded: LoadedRun, config: StudyConfig | None = None):
    """The run's simulator with every engine answer the run already has."""
    config = config or loaded.config
    sim = build_simulator(config)
    sim.load_cache(cache_records(loaded.table("engine_cache"), build_model(config).latent_names))
    return sim


class StoredAnswers:
    """A run's engine answers, given to its simulator a chunk of instances at a time.

    A chunk's commits ask the engine about its own instances' ground truths only. So a replay
    or a calibration in chunks holds the run's answers as Arrow tables (a few column buffers
    each), and a chunk's answers become the simulator's keys, tuples and arrays only while
    that chunk is worked on: what stays in memory between chunks does not grow by a Python
    object per answer. The answers the engine gives during a chunk are kept the same way
    (:meth:`add`), so none is asked twice. Answers about no instance's truth are given once, for good.

    Args:
        table: The run's engine cache (``store.schema.cache_frame`` columns).
        latent_names: The family's latent names, in the order of an instance's truth.
    """

    def __init__(self, table: pa.Table, latent_names: Sequence[str]) -> None:
        self.latent_names = tuple(latent_names)
        #: Tables of answers with each latent column as its distinct values and each row's place among
        #: them (``np.unique``'s values and inverse): the run's, then the engine's.
        self._parts: list[tuple[pa.Table, list[tuple[np.ndarray, np.ndarray]]]] = []
        #: Keys given for good (answers about no instance's truth: :meth:`give_unclaimed`).
        self.permanent: frozenset = frozenset()
        self._append(table)

    @staticmethod
    def usable(table: pa.Table, latent_names: Sequence[str], truths: np.ndarray) -> bool:
        """Whether a table's answers can be told apart by instance: it has every latent column,
        and a truth has one value per latent. Otherwise every answer is given at once."""
        return set(latent_names) <= set(table.column_names) and truths.ndim == 2 and truths.shape[1] == len(latent_names)

    def _append(self, table: pa.Table) -> None:
        columns = [np.asarray(table.column(name).to_numpy(), dtype=float) for name in self.latent_names]
        self._parts.append((table, [np.unique(column, return_inverse=True) for column in columns]))

    def add(self, records: list[dict[str, Any]] | AnswerColumns) -> None:
        """Keep answers the engine gave (``cache_records`` rows, or ``answer_columns``), to give again with their chunk's."""
        if records is not None and len(records):
            frame = (answers_frame(records, self.latent_names) if isinstance(records, AnswerColumns)
                     else cache_frame(records, self.latent_names))
            self._append(pa.Table.from_pandas(frame, preserve_index=False))

    def merge_added(self) -> None:
        """Join the tables :meth:`add` made (one a chunk) into one, in order: a pass's chunks each
        add a table, and :meth:`about` scans every table for every chunk of every later pass
        (a calibration of 12288 episodes spent 42 s of 262 there, over 700 tables)."""
        if len(self._parts) > 2:
            added = pa.concat_tables([table for table, _ in self._parts[1:]], promote_options="default").combine_chunks()
            del self._parts[1:]
            self._append(added)

    def give_unclaimed(self, simulator: Any, truths: np.ndarray) -> None:
        """Give ``simulator``, for good, the run's answers about none of ``truths`` (the run's
        instances'). A chunk's truths are some of these, so :meth:`about` never selects them."""
        self.permanent = frozenset(simulator.load_cache(self.records([~rows for rows in self.about(truths)])))

    def about(self, truths: np.ndarray) -> list[np.ndarray]:
        """Per table, which rows may be about one of ``truths`` ``[M, d]`` (each latent among the
        truths' values): every row a commit on those instances reads, and rarely a few more.

        A column's distinct values are looked up, not its rows (``np.isin`` compares by value, so
        equal values get one answer: the same mask): the run's table was sorted again for every chunk
        of every pass, which grew with the chunks times the answers (calibrate at E = 12,288: 0.77 of
        the main thread's 29 CPU s, 0.05 of 7.9 at E = 3,072; docs/decisions.md, "cal3:")."""
        truths = np.asarray(truths, dtype=float).reshape(-1, len(self.latent_names))
        masks = []
        for table, columns in self._parts:
            rows = np.ones(table.num_rows, dtype=bool)
            for (levels, place), values in zip(columns, truths.T):
                rows &= np.isin(levels, values)[place.reshape(-1)]
            masks.append(rows)
        return masks

    def records(self, masks: list[np.ndarray]) -> AnswerColumns:
        """The answers of the rows ``masks`` select, every table's in order, as ``load_cache`` takes them (columns)."""
        parts = [cache_records(table.filter(pa.array(rows)).to_pandas(), self.latent_names)
                 for (table, _), rows in zip(self._parts, masks) if rows.any()]
        return AnswerColumns.join(parts) if parts else cache_records(None, self.latent_names)

    def table(self) -> pa.Table:
        """Every answer held, the run's then the engine's, as one Arrow table (each answer once)."""
        return pa.concat_tables([table for table, _ in self._parts], promote_options="default")


def _chunked_simulator(loaded: LoadedRun, config: StudyConfig, latent_names: Sequence[str],
                       truths: np.ndarray) -> tuple[Any, StoredAnswers | None]:
    """The run's simulator with the answers about no instance of ``truths``, and the rest of the
    run's answers to give it a chunk at a time (None: every answer given now, where they cannot
    be told apart by instance or the simulator cannot forget them)."""
    sim = build_simulator(config)
    table = loaded.arrow_table("engine_cache")
    if not StoredAnswers.usable(table, latent_names, truths):
        sim.load_cache(cache_records(table.to_pandas(), latent_names))
        return sim, None
    answers = StoredAnswers(table, latent_names)
    answers.give_unclaimed(sim, truths)
    return sim, answers


def trace_for_run(run_dir: str | Path | LoadedRun, config: StudyConfig | None = None) -> tuple[BeliefTrace, Any, Any]:
    """Beliefs of every stored episode at every budget, under ``config`` (default: the run's).

    The whole run is held at once (every budget's particle state, about 0.3 MB per
    episode at N = 1024); replays and calibration go through :class:`RunBeliefs`,
    which holds one chunk of instances at a time.

    Returns:
        ``(trace, model, simulator)``.
    """
    beliefs = RunBeliefs.of(run_dir, config, chunk_instances=None)
    return beliefs.trace(beliefs.chunks[0]), beliefs.model, beliefs.simulator


#: Instances whose beliefs are held at once by a replay or a calibration. A chunk keeps
#: every committed budget's particle state of its episodes alive (about 0.3 MB per episode
#: at N = 1024, plus the retained sets of a commit), so memory is bounded by the chunk,
#: not by the run. 96 = one paper split (384 episodes), which stays a single chunk.
CHUNK_INSTANCES = 96

#: Instances whose beliefs are computed at once while a whole run's trace is built to be kept
#: (``RunBeliefs.restrict``): the kept trace is a run's, the update's temporaries a chunk's.
KEPT_TRACE_CHUNK_INSTANCES = 24


@dataclass
class RunBeliefs:
    """A run's stored probe trajectories, whose beliefs are recomputed a chunk of instances at a time.

    An episode's beliefs and commits never depend on the batch it is computed in
    (``tests/runner/test_batch_independence.py``), and chunks are contiguous in the
    run's canonical episode order, so a table assembled from chunks equals the
    whole-run table bit for bit.

    Attributes:
        config: The config beliefs are computed under (the run's, or a replay's).
        model: Its model.
        simulator: The run's simulator: with the run's engine cache when the run is one chunk, else
            with the answers of the chunk being committed (:class:`StoredAnswers`).
        pfilter: The particle filter of ``config``.
        batch: Every successful stored trajectory, in the run's episode order.
        chunks: Row slices of ``batch``, each a whole number of instances (all repeats).
        kept_budgets: The budgets whose beliefs a trace keeps (None: every budget the run
            commits at). A study of one budget (re-splits at k = 5) keeps and commits only it.
    """

    config: StudyConfig
    model: Any
    simulator: Any
    pfilter: ParticleFilter
    batch: ProbeBatch
    chunks: list[slice]
    kept_budgets: tuple[int, ...] | None = None
    #: The run's stored engine answers, given to ``simulator`` a chunk at a time (None: it holds them all).
    answers: StoredAnswers | None = None
    #: The trace of a run that is one chunk, kept across ``commit`` calls (with its reuse cache).
    _kept: tuple[BeliefTrace, dict] | None = field(default=None, repr=False)
    #: A restriction's source (:meth:`restrict`): the whole run's kept trace and this run's rows of it, taken
    #: on the first commit, so a re-split's test half is not copied while its calibration half is held.
    _rows_of: tuple[BeliefTrace, np.ndarray] | None = field(default=None, repr=False)
    #: The first chunk's trace, built before the next pass (:meth:`first_trace_ahead`), which takes it.
    _first: BeliefTrace | None = field(default=None, repr=False)

    @classmethod
    def of(cls, run: str | Path | LoadedRun, config: StudyConfig | None = None,
           chunk_instances: int | None = CHUNK_INSTANCES, budgets: Iterable[int] | None = None) -> "RunBeliefs":
        """Prepare a run for belief recomputation.

        Args:
            run: A run directory or a loaded run.
            config: The config to infer under (default: the run's).
            chunk_instances: Instances per chunk; None holds the whole run as one chunk.
            budgets: Keep and commit only these of the run's budgets (None: all of them). An
                episode's belief at budget k does not depend on which budgets are kept, so its
                rows equal those of a full trace (tested).

        Raises:
            ValueError: A budget the run does not commit at.
        """
        loaded = run if isinstance(run, LoadedRun) else load_run(run)
        config = config or loaded.config
        kept = None
        if budgets is not None:
            kept = tuple(dict.fromkeys(require_budgets(budgets, committed_budgets(config))))
            if not kept:
                raise UsageError(f"budget(s) [] not in the run (it commits at {committed_budgets(config)})")
        model = build_model(config)
        batch = probe_batch(loaded, model)
        chunks = _chunk_slices(batch.instance_id, chunk_instances)
        if len(chunks) > 1:  # each chunk's engine answers only while it is worked on
            simulator, answers = _chunked_simulator(loaded, config, model.latent_names, batch.truths)
        else:
            simulator, answers = simulator_for_run(loaded, config), None
        return cls(config, model, simulator, build_filter(model, config.belief), batch, chunks, kept, answers)

    def trace(self, rows: slice, keep_weights: bool = False) -> BeliefTrace:
        """Beliefs of the episodes ``batch[rows]`` at every kept budget.

        With chosen budgets (``RunBeliefs.of(..., budgets=...)``) the trace keeps those only:
        not the prior (k = 0), which only the blind methods read. ``keep_weights``: each budget's
        weights as the update computed them, for a chunk about to be committed (every commit
        reads them, and ``inference._belief_at`` keeps them for the chunk's commits anyway), so
        they are not exponentiated again; a trace held for other uses does not carry them.
        """
        budgets = self.config.probes.commit_budgets if self.kept_budgets is None else self.kept_budgets
        return build_trace(self.pfilter, self.batch.subset(rows), self.config.seed, budgets,
                           keep_weights=keep_weights, keep_prior=self.kept_budgets is None)

    def _whole_trace(self, chunk_instances: int = KEPT_TRACE_CHUNK_INSTANCES) -> BeliefTrace:
        """The trace of the whole run, computed ``chunk_instances`` instances at a time.

        Each chunk's beliefs are written into arrays sized for the run, so the peak is the
        kept trace plus one chunk's working memory, not a whole run's update temporaries.
        Equal to ``self.trace`` of the whole run (an episode never depends on its batch), except
        that an array the one-batch trace shares between budgets (no episode resampled between
        them) is held once per budget here.
        """
        ok_rows = np.flatnonzero(self.batch.status == "ok")
        names = BeliefState.trace_fields()

        def room(a: np.ndarray | None) -> np.ndarray | None:
            return None if a is None else np.empty((len(ok_rows), *a.shape[1:]), dtype=a.dtype)

        whole: BeliefTrace | None = None
        at = 0
        for rows in _chunk_slices(self.batch.instance_id, chunk_instances):
            part = self.trace(rows)
            if whole is None:  # the first chunk gives every array's shape and dtype
                whole = BeliefTrace(self.batch.subset(ok_rows),
                                    {k: BeliefState(**{n: room(getattr(s, n)) for n in names}) for k, s in part.states.items()},
                                    room(part.surprise), room(part.lost))
            n = part.batch.n_episodes
            for k, state in part.states.items():
                for name in names:
                    value = getattr(state, name)
                    if value is not None:
                        getattr(whole.states[k], name)[at:at + n] = value
            whole.surprise[at:at + n] = part.surprise
            if part.lost is not None:
                whole.lost[at:at + n] = part.lost
            at += n
            del part
        return whole if whole is not None else self.trace(slice(0, 0))

    def restrict(self, instance_ids: Iterable[str]) -> "RunBeliefs":
        """The beliefs of some of the run's instances, taken from this run's, computed once.

        For re-splits of one pool: the whole run's beliefs are computed on the first call
        and kept (it must be a single chunk), and each restriction takes its episodes'
        rows, which equal their beliefs computed alone (an episode never depends on its
        batch). The restriction shares this run's simulator and is a single chunk.
        """
        if len(self.chunks) != 1:
            raise ValueError("restrict() needs a run held as one chunk (RunBeliefs.of(..., chunk_instances=None))")
        if self._kept is None:
            self._kept = self._whole_trace(), {}
        rows = np.flatnonzero(np.isin(self.batch.instance_id, list(instance_ids)))  # the run's order
        return RunBeliefs(self.config, self.model, self.simulator, self.pfilter, self.batch.subset(rows),
                          [slice(0, len(rows))], self.kept_budgets, _rows_of=(self._kept[0], rows))

    @property
    def budgets(self) -> list[int]:
        """The budgets a trace of this run holds."""
        return committed_budgets(self.config) if self.kept_budgets is None else list(self.kept_budgets)

    def commit(self, requests: Sequence[Mapping[str, Any]], *, keep: Sequence[Sequence[str] | None] | None = None,
               reduce: Sequence[Callable[[pd.DataFrame], Any] | None] | None = None,
               reuse: bool = True, final: bool = False, **common: Any) -> list[pd.DataFrame | list[Any]]:
        """Episode tables of several commits, computed chunk by chunk in one pass.

        Each chunk's beliefs are computed once and every request is committed on them
        before the next chunk, so several commits cost one belief recomputation.

        Args:
            requests: Per-table keyword arguments of ``runner.inference.commit``
                (e.g. ``{"thresholds": t, "margin": g}``); ``via`` names another function of
                those arguments to call instead (``runner.margin_search.sweep_margins``).
            keep: Per request, the columns to keep (None: all); a margin search reads four
                columns of dozens of tables.
            reduce: Per request, a function applied to each chunk's table as soon as it is
                made (None: keep the table): what a caller needs of a run's table (its
                per-instance sums, say), without the table of every episode.
            reuse: Share margin-independent work (retained sets) between the requests of a
                chunk, and between calls when the run is one chunk; False recomputes it per commit.
            final: No later call needs this run's beliefs: a one-chunk run's kept trace is
                released by this call (as :meth:`release` would after it).
            **common: Keyword arguments of ``commit`` shared by every request; without ``executors``
                (here or in the requests) the probe executor commits.

        Returns:
            Per request, its table in the run's canonical episode order, or with ``reduce``,
            the list of what it returned for each chunk, in that order.
        """
        keep = list(keep) if keep is not None else [None] * len(requests)
        reduce = list(reduce) if reduce is not None else [None] * len(requests)
        if not any("executors" in request for request in [common, *requests]):
            common = {**common, "executors": build_executors(("probe_robust",), self.model)}
        parts: list[list[Any]] = [[] for _ in requests]
        several = len(self.chunks) > 1
        if several:
            trim_heap()  # what earlier calls freed goes back before the first chunk is computed
        if self._rows_of is not None:  # a restriction's rows are copied when first committed (``restrict``)
            whole, rows = self._rows_of
            self._kept, self._rows_of = (whole.subset(rows), {}), None
        with large_arrays_apart() if several else contextlib.nullcontext():
            self._commit_chunks(parts, requests, keep, reduce, reuse, final, common)
        if self.answers is not None:
            self.answers.merge_added()
        return [p if reducer is not None else p[0] if len(p) == 1 else pd.concat(p, ignore_index=True)
                for p, reducer in zip(parts, reduce)]

    def _commit_chunks(self, parts: list[list[Any]], requests: Sequence[Mapping[str, Any]],
                       keep: list, reduce: list, reuse: bool, final: bool, common: dict[str, Any]) -> None:
        """:meth:`commit`'s loop over the chunks: each request's table (or reduction) per chunk into ``parts``."""
        several = len(self.chunks) > 1
        with self._traces_ahead() as upcoming:
            for i, rows in enumerate(self.chunks):
                taken = self._take_answers(rows)
                try:
                    self._commit_chunk(rows, parts, requests, keep, reduce, reuse, final, common, upcoming(i))
                finally:  # a chunk that raised leaves no stored answer behind in the simulator either
                    self._put_back_answers(taken)
                if several:
                    trim_heap()  # the finished chunk's pages go back, so chunks do not pile up as heap fragments

    @contextlib.contextmanager
    def _traces_ahead(self) -> Iterator[Callable[[int], BeliefTrace | None]]:
        """While a chunk is committed, the next chunk's beliefs are computed in a second thread.

        A run of several chunks recomputes its beliefs on every pass; the filter's kernels and
        NumPy release the GIL, so with two CPUs or more (``tasks.base.engine_threads``) the next
        chunk's trace is built beside the commits (a trace depends only on its episodes' stored
        probes and seeds: the same bits, tested). At most one trace is computed ahead. The thread
        is joined when the pass ends, raised or not: none outlives the call (a thread still
        running native code at interpreter exit can abort the process). Yields a function giving
        chunk ``i``'s trace (None: the chunk computes its own, as with one CPU).

        The first chunk's trace is built in the calling thread while the thread builds the
        second's: a pass began with one CPU waiting for the first (~0.15 CPU s at 96 instances,
        twice a calibration), and two traces are held then, as while any later chunk is committed.
        """
        first, self._first = self._first, None
        if not self._ahead_possible():
            yield lambda i: None
            return
        chunks = list(self.chunks)
        with ThreadPoolExecutor(max_workers=1, thread_name_prefix="probecommit-trace") as pool:
            ahead: dict[int, Future] = {}

            def upcoming(i: int) -> BeliefTrace:
                nonlocal first
                if i + 1 < len(chunks):  # queued behind chunk i's own (one thread): at most one ahead
                    ahead[i + 1] = pool.submit(self.trace, chunks[i + 1], True)
                if i == 0 and first is not None:
                    trace, first = first, None  # not held here once its chunk is done
                    return trace
                return ahead.pop(i).result() if i in ahead else self.trace(chunks[i], True)

            try:
                yield upcoming
            finally:
                for future in ahead.values():
                    future.cancel()

    def _ahead_possible(self) -> bool:
        """Whether a pass over this run builds its chunks' traces in a second thread (:meth:`_traces_ahead`)."""
        from probecommit.tasks.base import engine_threads

        return len(self.chunks) >= 2 and self._kept is None and engine_threads() >= 2

    @contextlib.contextmanager
    def first_trace_ahead(self) -> Iterator[None]:
        """Within the block, the first chunk's trace is built in a second thread; the next pass takes it.

        Why: a calibration's first pass waited for its first beliefs after loading the test run,
        checking the pair and reading the stored scores (~0.1-0.2 s of one CPU at E = 3072), which
        need none of them. Only where a pass would build its traces in a thread anyway; the thread is
        joined when the block ends, and a block that raises keeps nothing. The trace is the one the
        pass would build (its rows and seeds), so the tables are the same bits.
        """
        if not self._ahead_possible():
            yield
            return
        with ThreadPoolExecutor(max_workers=1, thread_name_prefix="probecommit-trace") as pool:
            future = pool.submit(self.trace, self.chunks[0], True)
            try:
                yield
            except BaseException:
                future.cancel()
                raise
            self._first = future.result()

    def _commit_chunk(self, rows: slice, parts: list[list[Any]], requests: Sequence[Mapping[str, Any]],
                      keep: list, reduce: list, reuse: bool, final: bool, common: dict[str, Any],
                      trace: BeliefTrace | None = None) -> None:
        """Every request on the chunk ``batch[rows]``: its beliefs computed (or kept, or given) once."""
        several = len(self.chunks) > 1
        if self._kept is not None:
            trace, cache = self._kept
        else:
            trace, cache = (self.trace(rows, keep_weights=True) if trace is None else trace), {}
            if not several and not final:
                self._kept = trace, cache
        if final:
            self._kept = None
        # A cache that outlives this call keeps every set; otherwise each set goes after its last use.
        cache_ends_here = several or final
        for i, (part, request, columns, reducer) in enumerate(zip(parts, requests, keep, reduce)):
            request = dict(request)
            via = request.pop("via", commit)  # another function of commit's arguments (a margin sweep)
            table = via(trace, self.model, self.simulator, cache=cache if reuse else None,
                        columns=columns, **common, **request)
            part.append(table if reducer is None else reducer(table))
            del table
            later = requests[i + 1:]
            if cache_ends_here and all("thresholds" in upcoming for upcoming in later):
                prune_retained_sets(cache, [upcoming["thresholds"] for upcoming in later])
        # Returning lets the chunk's beliefs go before the next chunk's are computed.

    def _take_answers(self, rows: slice) -> list:
        """Give the simulator the stored answers about the instances of ``batch[rows]``; their keys."""
        if self.answers is None:
            return []
        return self.simulator.load_cache(self.answers.records(self.answers.about(self.batch.truths[rows])))

    def _put_back_answers(self, taken: list) -> None:
        """After a chunk: drop the stored answers it was given, and keep those its engine gave in
        :attr:`answers` (a later pass over the chunk takes them from there)."""
        if self.answers is None:
            return
        self.simulator.forget_answers(taken)
        fresh = [key for key in self.simulator.answered_keys() if key not in self.answers.permanent]
        if fresh:
            as_columns = getattr(self.simulator, "answer_columns", None)
            columns = None if as_columns is None else as_columns(fresh)
            self.answers.add(columns if columns is not None else self.simulator.cache_records(fresh))
            self.simulator.forget_answers(fresh)

    def release(self) -> None:
        """Drop the kept trace of a one-chunk run (its last commit is done) and hand its pages back."""
        self._rows_of = self._first = None
        if self._kept is not None:
            self._kept = None
            trim_heap()


def committed_budgets(config: StudyConfig) -> list[int]:
    """The probe budgets ``k >= 1`` a run of ``config`` commits at."""
    return [k for k in config.probes.commit_budgets if k > 0]


def require_budgets(requested: Iterable[int], have: Sequence[int]) -> list[int]:
    """``requested`` sorted, every one among ``have``.

    Raises:
        ValueError: One line naming the budgets the run does not commit at.
    """
    budgets = sorted(int(b) for b in requested)
    missing = [b for b in budgets if b not in have]
    if missing:
        raise UsageError(f"budget(s) {missing} not in the run (it commits at {list(have)})")
    return budgets


def _chunk_slices(instance_id: np.ndarray, chunk_instances: int | None) -> list[slice]:
    """Contiguous row slices of a batch ordered by instance, ``chunk_instances`` instances each."""
    n = len(instance_id)
    if chunk_instances is None or n == 0:
        return [slice(0, n)]
    if chunk_instances < 1:
        raise ValueError(f"chunk_instances must be at least 1, got {chunk_instances}")
    starts = np.flatnonzero(np.r_[True, instance_id[1:] != instance_id[:-1]])  # first row of each instance
    bounds = [*starts[::chunk_instances].tolist(), n]
    return [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]


def replay_config(config: StudyConfig, overrides: dict[str, dict[str, Any]]) -> StudyConfig:
    data = config_data(config)
    for section, values in overrides.items():
        data[section] = {**data[section], **values}
    return parse_config(data)


def replay_episodes(
    loaded: LoadedRun,
    overrides: dict[str, dict[str, Any]] | None = None,
    thresholds: float | dict[int, float] | None = None,
    margin: float | None = None,
    fixed_probes: bool = False,
    chunk_instances: int | None = CHUNK_INSTANCES,
) -> tuple[pd.DataFrame, Any]:
    """Episodes re-inferred from a run's stored probes, without writing anything.

    Args:
        loaded: A loaded run.
        overrides: Config sections to change. ``model`` and ``belief`` change inference;
            ``simulator`` may change execution-side settings only (``aim_offset``), since
            the readings are the stored ones.
        thresholds: Retained mass or conformal thresholds (default: the config's ``nu``).
        margin: Capture-window margin ``gamma`` (default: the config's).
        fixed_probes: Allow a replay of an *adaptive* run under another model or belief.
            Its probes were chosen by the run's own belief, so the other model would
            have probed elsewhere: the replay answers "this model on those probes",
            and a difference between the two is not a paired comparison.
        chunk_instances: Instances whose beliefs are held at once (None: the whole
            run); the table does not depend on it.

    Returns:
        ``(episodes, simulator)``; the simulator carries the engine-call counts.
    """
    beliefs, request, common = replay_commit(loaded, overrides, thresholds, margin, fixed_probes, chunk_instances)
    [episodes] = beliefs.commit([request], **common)
    failed = _failed_rows(loaded, beliefs)
    if len(failed):
        episodes = pd.concat([episodes, failed], ignore_index=True)
    return episodes, beliefs.simulator


def replay_commit(loaded: LoadedRun, overrides: dict[str, dict[str, Any]] | None,
                  thresholds: float | dict[int, float] | None, margin: float | None, fixed_probes: bool,
                  chunk_instances: int | None) -> tuple[RunBeliefs, dict[str, Any], dict[str, Any]]:
    """The checked replay of ``loaded``: its beliefs under the overrides, and the request and
    keyword arguments of the one ``RunBeliefs.commit`` that gives its episodes.

    Public because a caller that reads only some budgets (``studies/explain/replay_final``) narrows
    the beliefs' kept budgets before committing: the checks stay in one place."""
    overrides = overrides or {}
    bad = set(overrides) - {"model", "belief", "simulator"}
    if bad:
        raise UsageError(f"a replay can change only the model, belief and simulator sections, not {sorted(bad)}")
    sim_bad = set(overrides.get("simulator", {})) - {"aim_offset"}
    if sim_bad:
        raise UsageError(f"stored probes fix the readings; a replay cannot change simulator {sorted(sim_bad)}")
    changes_inference = any(overrides.get(section) for section in ("model", "belief"))
    if loaded.config.probes.schedule == "adaptive" and changes_inference and not fixed_probes:
        raise UsageError(
            f"{loaded.path}: its probes were chosen adaptively by the run's own belief, so another model or belief "
            "would have probed elsewhere; replaying them is not a paired (identical-probes) comparison. "
            "Pass fixed_probes=True (CLI: --fixed-probes) to replay the recorded probes anyway."
        )
    config = replay_config(loaded.config, overrides)
    beliefs = RunBeliefs.of(loaded, config, chunk_instances)
    request = {"thresholds": config.belief.nu if thresholds is None else thresholds, "margin": margin}
    return beliefs, request, {"executors": config_executors(config, beliefs.model)}


def _failed_rows(loaded: LoadedRun, beliefs: RunBeliefs) -> pd.DataFrame:
    """The run's failed-rollout rows, under the replay's model variant."""
    failed = loaded.failed_rollouts()
    return failed.assign(variant=beliefs.model.variant) if len(failed) else failed


def replay_run(src: str | Path, out: str | Path, overrides: dict[str, dict[str, Any]], fixed_probes: bool = False,
               chunk_instances: int | None = CHUNK_INSTANCES) -> Path:
    """Write a new run directory: the source's probes, re-inferred under ``overrides``.

    The source's instances and probes are copied as they are; each chunk's episodes are
    written when the chunk is done and the engine cache goes from Arrow tables to its file, so
    what a replay holds is one chunk's work and the run's input (probe arrays and engine
    answers, about 0.55 KB an episode), not its output (``benchmarks/memory.py``).

    Args:
        src: A complete run directory.
        out: The new run directory (must not hold another run).
        overrides: Config sections to change, e.g. ``{"model": {"boundary": "corrected"}}``
            (see ``replay_episodes``).
        fixed_probes: See ``replay_episodes``.
        chunk_instances: Instances whose beliefs are held at once (see ``replay_episodes``).
    """
    logger.info("replaying %s into %s with %s", src, out, overrides or "no override")
    start = time.perf_counter()
    if Path(out).resolve() == Path(src).resolve():
        raise UsageError(f"replay would overwrite its source run {src}; give another --out")
    loaded = load_run(src)
    beliefs, request, common = replay_commit(loaded, overrides, None, None, fixed_probes, chunk_instances)
    config, sim = beliefs.config, beliefs.simulator
    run = RunDir(out)
    with run.writing(dump_config(config)):
        source = RunDir(loaded.path)
        for name in ("instances", "probes"):
            run.copy_table(source, name)
        with run.episode_stream(loaded.instances, _failed_rows(loaded, beliefs)) as episodes:
            beliefs.commit([request], reduce=[episodes.add], **common)
        # The new run's engine cache: the source's answers and those the engine gave during the replay.
        if beliefs.answers is not None:
            answers = beliefs.answers.table()
        else:
            answers = pa.Table.from_pandas(cache_frame(sim.cache_records(), beliefs.model.latent_names),
                                           preserve_index=False)
        run.write_engine_cache(answers)
        del answers
        trajectories = loaded.table("probes", columns=["instance_id", "repeat"]).drop_duplicates()
        run.write_manifest({
            "study": config.name,
            "replay_of": str(Path(src).resolve()),
            "engine": config.simulator.engine,
            "engine_calls": sim.engine_calls,
            "timing": {"engine_s": sim.engine_seconds, "this_invocation_wall_s": time.perf_counter() - start},
            "episodes": int(len(trajectories)),
        })
    return run.path
