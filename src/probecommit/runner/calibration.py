"""Calibration and commit gates on run directories (paper Secs. IV and VI).

These functions tie the pure audit modules to the runner: beliefs are recomputed
from each run's stored probes (``runner.replay.RunBeliefs``, a chunk of instances at
a time; of each chunk's tables only per-instance reductions and a few rows are kept, so
memory barely grows with the run's size) and the commit is re-executed
(``runner.inference.commit``) under each threshold and margin, so every arm of a
comparison sees identical probes and every coverage is measured on the set as
constructed. Ground truth comes from the runs' engine caches; an action no episode of
the run committed to is executed in the engine (never, for a run made with
``execute_all_aims``).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Sequence

import numpy as np
import pandas as pd
from threadpoolctl import threadpool_limits

from probecommit.audit.conformal import (
    DEFAULT_ALPHA,
    budget_thresholds,
    conformal_quantile,
    instance_scores,
    worst_budget_scores,
)
from probecommit.audit.gates import DEFAULT_TARGET_RATE, GatesResult, gates_from_tables
from probecommit.audit.io import check_episode_values, ok_episodes, validate_episodes
from probecommit.audit.margin import (
    GAMMA_GRID,
    MarginResult,
    instance_optimism,
    margin_candidates,
    optimism_margin,
    select_margin,
)
from probecommit.audit.metrics import audit_from_sums, instance_sums, summary_row
from probecommit.audit.stats import (
    DEFAULT_LEVEL,
    DEFAULT_RESAMPLES,
    DEFAULT_SEED,
    EPISODE_KEYS,
    bootstrap_ratio,
    cluster_bootstrap_mean,
    paired_bootstrap,
    resample_counts,
)
from probecommit.audit.surprise import surprise_auc
from probecommit.runner.build import config_executors
from probecommit.runner.commit_threads import commit_in_threads, in_threads
from probecommit.runner.margin_search import SweptChunk, sweep_margins
from probecommit.runner.replay import CHUNK_INSTANCES, LoadedRun, RunBeliefs, load_run, require_budgets
from probecommit.errors import UsageError

#: The executor's method whose commits are calibrated.
PROBE_METHOD = "probe_robust"


# ----------------------------------------------------------------------------- runs


#: The columns a margin search reads from each re-executed table (``audit.margin.margin_satisfied``).
MARGIN_COLUMNS = ("k", "status", "predicted", "realized")

#: The columns the test run's calibrated tables are audited, paired and counted on
#: (``audit.metrics.audit_table``, ``audit.stats.paired_bootstrap``): a table of every episode
#: and budget, so its other columns are not built. The uncalibrated table is kept whole (validated).
AUDIT_COLUMNS = ("instance_id", "repeat", "k", "method", "variant", "status", "predicted", "realized", "covered",
                 "escaped")

#: Rows of margin-search tables (episodes x budgets, per margin) one pass over a run of several
#: chunks commits at most: a pass recomputes the run's beliefs, so it commits several margins,
#: but not so many that their tables grow with the run (16 bytes a row, :func:`_margin_rows`:
#: 4 MB; E = 3072 at k = 1..8: ten margins a pass, E = 12288: two).
MARGIN_BLOCK_ROWS = 2**18

#: A commit request: the thresholds (mass ``nu``, ``t`` or ``{k: t_k}``) and the margin (None: the model's).
Request = tuple[float | dict[int, float], float | None]
#: What is kept of a chunk's episode table: a DataFrame, a tuple of DataFrames, or None.
Reduction = Callable[[pd.DataFrame], Any]


class Recorder:
    """The re-executed episode rows a calibration's results are computed from, kept for publishing.

    Why: calibrated commits come from beliefs recomputed from stored probes, which a publication
    does not hold; storing the few columns each result reads (``COMMIT_COLUMNS``) lets
    ``probecommit verify`` recompute the calibrated numbers (``calibration_from_tables``,
    ``gates_from_commits``) from the published table. ``Recorder(None)`` keeps nothing.
    """

    def __init__(self, sink: list[pd.DataFrame] | None) -> None:
        self.sink = sink

    def wrap(self, request: str, reducer: Reduction, columns: Sequence[str], gamma: float | None = None) -> Reduction:
        """``reducer``, keeping each table's ``columns`` labelled with the request (and margin) first."""
        if self.sink is None:
            return reducer

        def keep(table: pd.DataFrame) -> Any:
            rows = table[list(columns)].reset_index(drop=True)
            self.sink.append(rows.assign(request=request, gamma=float("nan") if gamma is None else float(gamma)))
            return reducer(table)

        return keep

    def keep(self, request: str, table: pd.DataFrame, columns: Sequence[str]) -> None:
        """Keep a whole table's ``columns`` (a commit not reduced chunk by chunk)."""
        self.wrap(request, lambda t: None, columns)(table)

    def mark(self) -> int:
        """Where the rows kept from now on start (for :meth:`drop_since`)."""
        return 0 if self.sink is None else len(self.sink)

    def drop_since(self, mark: int) -> None:
        """Forget the rows kept since :meth:`mark` gave ``mark`` (a pass whose results were not used)."""
        if self.sink is not None:
            del self.sink[mark:]

    def keep_margins(self, gammas: Iterable[float]) -> None:
        """Drop the margin rows of candidates the search committed in a block but never read."""
        if self.sink is None:
            return
        read = {round(float(g), 10) for g in gammas}
        self.sink[:] = [part for part in self.sink if not len(part) or part["request"].iat[0] != "margin"
                        or round(float(part["gamma"].iat[0]), 10) in read]

    def table(self) -> pd.DataFrame:
        """Every kept row, one table (columns a request does not read are empty)."""
        return pd.concat(self.sink or [], ignore_index=True)


def _concat_parts(parts: Sequence[Any]) -> Any:
    """The reductions of a run's parts joined: DataFrames concatenated (their index kept), arrays and
    lists concatenated, tuples element by element; None parts (nothing kept) skipped, and None when every part is."""
    parts = [part for part in parts if part is not None]
    if not parts:
        return None
    if isinstance(parts[0], tuple):
        return tuple(_concat_parts(column) for column in zip(*parts))
    if isinstance(parts[0], list):
        return [item for part in parts for item in part]
    if isinstance(parts[0], np.ndarray):
        return np.concatenate(parts)
    return pd.concat(parts) if len(parts) > 1 else parts[0]


def calibration_scores(cal: "_Run") -> pd.DataFrame:
    """The uncalibrated commit's worst-repeat scores, instances (sorted) x budgets, kept chunk by chunk
    (of a run from :func:`load_for_commit`).

    Raises:
        ValueError: No episode of the run committed.
    """
    [scores] = cal.commit((cal.nu, None), reduce=[_scores])
    if scores is None:
        raise UsageError(f"{cal.loaded.path}: no episode of the calibration run committed (every one failed)")
    return scores.sort_index()


def _margin_rows(table: pd.DataFrame, budgets: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """The values ``audit.margin.margin_satisfied(table, budgets)`` sums, in order: predicted and
    realized failure of the ok rows at ``budgets``, as two float arrays (16 bytes a row, against
    32 for the rows with their budget and index)."""
    ok = ok_episodes(table)
    rows = ok.loc[ok["k"].isin(budgets)]
    return rows["predicted"].to_numpy(float), rows["realized"].to_numpy(float)


def _scores(table: pd.DataFrame) -> pd.DataFrame | None:
    """Worst-repeat coverage scores, instances x budgets (``audit.conformal.instance_scores``)."""
    return instance_scores(table, None) if len(ok_episodes(table)) else None


def _optimism(table: pd.DataFrame, budgets: list[int]) -> pd.DataFrame | None:
    """Mean optimism over repeats, instances x budgets (``audit.margin.instance_optimism``)."""
    return instance_optimism(table, budgets) if len(ok_episodes(table)) else None


def _cost_rows(table: pd.DataFrame, k: int) -> pd.DataFrame:
    """The rows at budget ``k`` and the columns a failure comparison reads (``_failure_at``, pairing)."""
    return table.loc[table["k"] == k, [*EPISODE_KEYS, "status", "realized"]]


def _audited(table: pd.DataFrame, k: int) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """The audit's per-instance sums (``audit.metrics.instance_sums``) and the rows at budget ``k``."""
    return (*instance_sums(table), _cost_rows(table, k))


def _all_covered(table: pd.DataFrame, budgets: list[int]) -> pd.Series:
    """Per instance, whether every ok episode at ``budgets`` is covered."""
    ok = ok_episodes(table)
    return ok.loc[ok["k"].isin(budgets)].groupby("instance_id")["covered"].all()


@dataclass
class _Run:
    """A loaded run whose commits are re-executed from recomputed beliefs (internal)."""

    loaded: LoadedRun
    beliefs: RunBeliefs
    #: Share margin-independent work (retained sets, coverage scores) between commits;
    #: False recomputes it each time (the reference path the benchmark compares against).
    reuse: bool = True
    #: The set construction at t = 1, if not the run config's (``calibrate(..., plateau=)``).
    override_plateau: str | None = None
    structure_checked: bool = False
    #: The run's episode rows of trajectories whose probing failed (read on the first commit), of the
    #: beliefs' model variant.
    failed_rollouts: pd.DataFrame | None = None

    @property
    def nu(self) -> float:
        return float(self.loaded.config.belief.nu)

    @property
    def plateau(self) -> str:
        return self.override_plateau or self.loaded.config.calibration.plateau

    @functools.cached_property
    def executors(self) -> list:
        """The probe executor every commit of this run injects (built once)."""
        return config_executors(self.loaded.config, self.beliefs.model, (PROBE_METHOD,), self.plateau)

    def commit(self, *requests: Request, keep: Sequence[Sequence[str] | None] | None = None,
               reduce: Sequence[Reduction | None] | None = None, final: bool = False) -> list[Any]:
        """Episode tables of the probe executor, one per request, in one pass over the run's chunks.

        Args:
            *requests: ``(thresholds, margin)`` pairs.
            keep: Per request, the columns to keep (None: all, validated). A margin search
                reads four columns of dozens of tables; those are not validated (the
                validation needs every column) and not kept whole.
            reduce: Per request, what is kept of each chunk's table (and of the run's failed
                rollout rows) instead of the table: a function of a table returning a
                DataFrame or a tuple of them (None: nothing), concatenated over the parts.
                A whole table (``keep`` None) is validated chunk by chunk before it is reduced.
            final: The run's last commit: its beliefs are released as the pass goes.

        Returns:
            Per request, its table or, with ``reduce``, its concatenated reductions.
        """
        keep = list(keep) if keep is not None else [None] * len(requests)
        reduce = list(reduce) if reduce is not None else [None] * len(requests)
        per_chunk = [None if reducer is None else self._checked(reducer, columns)
                     for reducer, columns in zip(reduce, keep)]
        tables = self.beliefs.commit([_commit_request(request, self.reuse) for request in requests], keep=keep,
                                     reduce=per_chunk, reuse=self.reuse, final=final, executors=self.executors)
        out = []
        for table, columns, reducer in zip(tables, keep, reduce):
            if reducer is None:
                out.append(self._finish(table, columns))
                continue
            failed = self._failed()
            out.append(_concat_parts([*table, reducer(failed if columns is None else failed[list(columns)])
                                      if len(failed) else None]))
        return out

    def _failed(self) -> pd.DataFrame:
        """The run's rollout rows (read once), of the variant the beliefs are computed under."""
        if self.failed_rollouts is None:  # read once: the run's rollout rows, not its whole table
            rows = self.loaded.failed_rollouts()
            self.failed_rollouts = rows.assign(variant=self.beliefs.model.variant) if len(rows) else rows
        return self.failed_rollouts

    def _checked(self, reducer: Reduction, columns: Sequence[str] | None) -> Reduction:
        """``reducer`` after the chunk's whole table (with its instances' rollout rows) is validated."""
        if columns is not None:
            return reducer

        def check_then_reduce(table: pd.DataFrame) -> Any:
            failed = self._failed()
            mine = failed.loc[failed["instance_id"].isin(table["instance_id"].unique())] if len(failed) else failed
            whole = pd.concat([table, mine], ignore_index=True) if len(mine) else table
            if self.structure_checked:  # a table commit built: its values checked, not converted again
                check_episode_values(whole, f"{self.loaded.path} (re-executed)")
            else:
                self._validate(whole)
            return reducer(table)

        return check_then_reduce

    def _finish(self, table: pd.DataFrame, columns: Sequence[str] | None) -> pd.DataFrame:
        # Trajectories whose probing failed have no belief; carry the run's failure
        # rows along so they stay counted (and the repeat-count check sees them).
        failed = self._failed()
        if len(failed):
            table = pd.concat([table, failed if columns is None else failed[list(columns)]], ignore_index=True)
        if columns is not None:
            return table
        return self._validate(table)

    def _validate(self, table: pd.DataFrame) -> pd.DataFrame:
        table = validate_episodes(table, f"{self.loaded.path} (re-executed)", structure=not self.structure_checked)
        self.structure_checked = True
        return table

    def search_margin(self, thresholds: float | dict[int, float], grid: Iterable[float], budgets: Sequence[int],
                      *extra: tuple[Request, Reduction | None],
                      record: "Recorder | None" = None) -> tuple[MarginResult, list[Any]]:
        """The validation-tuned margin under ``thresholds`` (``audit.margin.select_margin``).

        A run of one chunk keeps its beliefs, so each margin is committed when the scan
        asks for it. A run of several chunks would recompute its beliefs for each one,
        so an evaluation commits the next margins of the scan with it, in one pass, as many
        as :data:`MARGIN_BLOCK_ROWS` rows allow. Of each margin's table, only the rows the
        margin rule reads are kept, and let go once scanned.

        Args:
            thresholds: The set calibration the margin is searched under.
            grid: Margin candidates.
            budgets: Budgets the margin rule averages over.
            *extra: Further requests with their reductions (see :meth:`commit`), committed in
                the first pass; a third item names the columns the reduction reads (default: the
                whole table, validated).
            record: Where each evaluated margin's rows are kept (``Recorder``, request ``margin``),
                so a publication can store them and ``verify`` search the margin again.

        Returns:
            The margin and what :meth:`commit` returns for ``extra``.
        """
        candidates = margin_candidates(grid)
        if self.reuse and candidates:
            return self._sweep_margin(thresholds, candidates, budgets, extra, record or Recorder(None))
        tables: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        extras: list[Any] = []
        # Margins committed in one pass: as many as MARGIN_BLOCK_ROWS rows of their tables allow,
        # so the memory held is bounded, not a whole scan's tables of every episode.
        rows = self.beliefs.batch.n_episodes * max(len(self.beliefs.budgets), 1)
        per_pass = max(1, MARGIN_BLOCK_ROWS // max(rows, 1))
        margin_rows = functools.partial(_margin_rows, budgets=list(budgets))
        recorder = record or Recorder(None)

        def evaluate(gamma: float) -> pd.DataFrame:
            if gamma not in tables:
                block = [gamma] if len(self.beliefs.chunks) == 1 else [g for g in candidates if g <= gamma][:per_pass]
                first = [] if extras else list(extra)
                out = self.commit(*[(thresholds, g) for g in block], *[request for request, *_ in first],
                                  keep=[MARGIN_COLUMNS] * len(block) + [_columns(item) for item in first],
                                  reduce=[recorder.wrap("margin", margin_rows, MARGIN_COLUMNS, gamma=g) for g in block]
                                  + [reducer for _, reducer, *_ in first])
                tables.update(zip(block, out[:len(block)]))
                extras.extend(out[len(block):])
            predicted, realized = tables.pop(gamma)  # the scan reads each margin once
            return pd.DataFrame({"predicted": predicted, "realized": realized})

        # The rows are those at ``budgets`` already (_margin_rows).
        result = select_margin(evaluate, candidates, budgets=None)
        recorder.keep_margins(result.search["gamma"])
        return result, extras

    def _margins_per_pass(self) -> int:
        """Margins the margin-by-margin search commits in one pass over a run of several chunks."""
        rows = self.beliefs.batch.n_episodes * max(len(self.beliefs.budgets), 1)
        return max(1, MARGIN_BLOCK_ROWS // max(rows, 1))

    def _sweep_margin(self, thresholds: float | dict[int, float], candidates: list[float], budgets: Sequence[int],
                      extra: Sequence[tuple[Request, Reduction | None]],
                      recorder: Recorder) -> tuple[MarginResult, list[Any]]:
        """:meth:`search_margin` with every margin committed in one pass over the run's beliefs
        (``runner.margin_search.sweep_margins``: beliefs, retained sets and counts once), ``extra`` beside it.

        The same margin, search table and recorded rows as margin by margin (``reuse=False``,
        tested). A run of several chunks executes every margin's aims during its chunk's pass (the
        margin-by-margin search executed each pass's block of margins, all of them for a paper-sized
        run); a run of one chunk executes a margin's aims when the scan reads it, as before.
        """
        several = len(self.beliefs.chunks) > 1
        sink = recorder.sink
        marks: list[int] = []  # where each chunk's rows of the extra requests start in the sink, then their failed rows

        def sweep(*args: Any, **kwargs: Any) -> SweptChunk:
            if sink is not None:
                marks.append(len(sink))
            return sweep_margins(*args, **kwargs)

        def part(swept: Any) -> list[SweptChunk] | None:
            if isinstance(swept, SweptChunk):
                return [swept]
            if sink is not None:  # the run's failed rollout rows: the extras' follow
                marks.append(len(sink))
            return None

        request = {"thresholds": _executable(thresholds), "margins": candidates, "execute": several, "via": sweep}
        chunks, *extras = self.commit(request, *[request for request, *_ in extra],
                                      keep=[MARGIN_COLUMNS] + [_columns(item) for item in extra],
                                      reduce=[part] + [reducer for _, reducer, *_ in extra])
        chunks = chunks or []
        position = {gamma: m for m, gamma in enumerate(candidates)}

        def evaluate(gamma: float) -> pd.DataFrame:
            rows = [chunk.rule_rows(position[gamma], budgets) for chunk in chunks]
            return pd.DataFrame({"predicted": _concat_parts([p for p, _ in rows]) if rows else np.empty(0),
                                 "realized": _concat_parts([r for _, r in rows]) if rows else np.empty(0)})

        result = select_margin(evaluate, candidates, budgets=None)
        if sink is not None:
            blocks = ([candidates[i:i + self._margins_per_pass()] for i in range(0, len(candidates),
                                                                                 self._margins_per_pass())]
                      if several else [[gamma] for gamma in candidates])
            sink[marks[0]:] = self._margin_records(sink, marks, blocks, chunks, list(result.search["gamma"]))
        return result, extras

    def _margin_records(self, sink: list[pd.DataFrame], marks: list[int], blocks: list[list[float]],
                        chunks: list[SweptChunk], read: list[float]) -> list[pd.DataFrame]:
        """The recorded rows of a swept search in the order the margin-by-margin search kept them:
        pass by pass (a block of margins), chunk by chunk, each read margin's rows then (first pass)
        the extra requests' rows; after the chunks, the run's failed rollout rows per margin, then
        the extras'. ``sink[marks[c]:marks[c + 1]]`` are chunk ``c``'s extra rows."""
        marks = [*marks, len(sink)] if len(marks) == len(chunks) else marks
        extras = [sink[marks[c]:marks[c + 1]] for c in range(len(chunks))]
        failed_extras = sink[marks[len(chunks)]:]
        failed = self._failed()
        read = {round(float(gamma), 10) for gamma in read}
        out: list[pd.DataFrame] = []
        for b, block in enumerate(blocks):
            block = [gamma for gamma in block if round(gamma, 10) in read]
            if not block:
                break
            for c, chunk in enumerate(chunks):
                for gamma in block:
                    columns = chunk.columns(chunk.margins.index(gamma))
                    out.append(pd.DataFrame(columns)[list(MARGIN_COLUMNS)].assign(request="margin", gamma=float(gamma)))
                if b == 0:
                    out.extend(extras[c])
            if len(failed):
                for gamma in block:
                    out.append(failed[list(MARGIN_COLUMNS)].reset_index(drop=True).assign(request="margin",
                                                                                       gamma=float(gamma)))
            if b == 0:
                out.extend(failed_extras)
        return out

    def release(self) -> None:
        """Drop the beliefs kept between commits (the run's last commit is done)."""
        self.beliefs.release()


def _columns(extra: tuple) -> Sequence[str] | None:
    """The columns an extra request of :meth:`_Run.search_margin` keeps (its third item; None: all, validated)."""
    return extra[2] if len(extra) > 2 else None


def _commit_request(request: Request | dict[str, Any], threaded: bool = False) -> dict[str, Any]:
    """``RunBeliefs.commit``'s keyword arguments of a ``(thresholds, margin)`` request (a dict is one already);
    ``threaded``: the chunk's budgets committed in two threads (``runner.commit_threads``, the same table)."""
    if isinstance(request, dict):
        return request
    thresholds, margin = request
    return {"thresholds": _executable(thresholds), "margin": margin, **({"via": commit_in_threads} if threaded else {})}


def _executable(thresholds: float | dict[int, float]) -> float | dict[int, float]:
    """Map an infinite conformal threshold (too few calibration clusters) to t = 2.

    ``t = 2`` grows the hull by ``D`` on each side, so the set contains the whole
    decision domain of width ``D``: the executable meaning of "cover everything".
    """
    if isinstance(thresholds, dict):
        return {k: (2.0 if math.isinf(t) else float(t)) for k, t in thresholds.items()}
    return 2.0 if math.isinf(thresholds) else float(thresholds)


def load_for_commit(run, reuse: bool = True, plateau: str | None = None, chunk_instances: int | None = CHUNK_INSTANCES,
                    budgets: Iterable[int] | None = None) -> _Run:
    """A run ready for re-execution (``commit``, ``search_margin``); with ``budgets``, only those budgets'
    beliefs are kept and committed (the results read no other budget, so they are the same, in a fraction
    of the work). Public: the explain target re-commits runs under its own thresholds and margins.

    Args:
        run: Run directory or ``LoadedRun``.
        reuse: Build each retained set and coverage score once per threshold (see :func:`calibrate`).
        plateau: The set at ``t = 1`` (default the run's ``calibration.plateau``).
        chunk_instances: Instances whose beliefs are held at once (None: a whole run).
        budgets: The budgets to keep (default every budget).
    """
    loaded = run if isinstance(run, LoadedRun) else load_run(run)
    beliefs = loaded.beliefs or RunBeliefs.of(loaded, chunk_instances=chunk_instances, budgets=budgets)
    return _Run(loaded, beliefs, reuse, plateau)


def _check_pair(cal: _Run, test: _Run) -> None:
    """Calibration transfers only between runs of one model, belief and probe schedule."""
    a, b = cal.loaded.config, test.loaded.config
    for section in ("family", "model", "belief", "probes"):
        if getattr(a, section) != getattr(b, section):
            raise UsageError(f"calibration and test runs differ in their '{section}' settings; "
                             "calibrate on a run of the same model, belief and probe schedule")
    shared = shared_truths(cal.loaded.instances, test.loaded.instances)
    if len(shared):
        # By content, not by id: the same truths under other ids are the same instances.
        first = shared.iloc[0]
        raise UsageError(f"calibration and test runs share {len(shared)} instance(s) by their truth and context values "
                         f"(e.g. {first['instance_id_cal']!r} in {cal.loaded.path} is {first['instance_id_test']!r} "
                         f"in {test.loaded.path}); in-sample calibration has no coverage guarantee: calibrate on "
                         "a run of other instances")


def shared_truths(cal: pd.DataFrame, test: pd.DataFrame, digits: int = 12) -> pd.DataFrame:
    """Pairs of instances, one per table, whose truth (``true_*``) and context (``ctx_*``) values are
    equal (to ``digits`` significant digits): the leak check reads values, never ids.

    Returns:
        Columns ``instance_id_cal`` and ``instance_id_test``, one row per shared pair.
    """
    cols = sorted(c for c in set(cal.columns) & set(test.columns) if c.startswith(("true_", "ctx_")))
    if not cols:
        return pd.DataFrame(columns=["instance_id_cal", "instance_id_test"])

    def keyed(frame: pd.DataFrame, tag: str) -> pd.DataFrame:
        values = frame[cols].to_numpy(float)
        rounded = np.vectorize(lambda v: float(f"{v:.{digits}g}"), otypes=[float])(values) if values.size else values
        out = pd.DataFrame(rounded, columns=cols)
        out[f"instance_id_{tag}"] = frame["instance_id"].astype(str).to_numpy()
        return out

    return keyed(cal, "cal").merge(keyed(test, "test"), on=cols)[["instance_id_cal", "instance_id_test"]]


def _budgets(run: _Run, budgets: Iterable[int] | None) -> list[int]:
    have = run.beliefs.budgets
    return have if budgets is None else require_budgets(budgets, have)


# ----------------------------------------------------------------------------- calibrate


@dataclass
class CalibrationResult:
    """Calibration on one run, evaluated on another (paper Tables III and IV).

    Attributes:
        alpha: Miscoverage level (``1 - alpha`` = 0.80 in the paper).
        budgets: Budgets calibrated.
        n_calibration: Calibration instances ``M``.
        thresholds: Fixed-budget conformal thresholds ``{k: t_k}``.
        simultaneous_threshold: Budget-simultaneous ``t`` over ``budgets``.
        margin: The validation-tuned margin search (under ``thresholds``).
        distribution_free_margin: Conformal ``1 - alpha`` quantile of the
            calibration instances' worst-budget optimism (set-calibrated executor).
        table3: Per budget: cluster coverage and optimism, original vs
            calibrated (set calibration + margin), with intervals.
        summary: Bottom row of Table III (mean ``|coverage - (1 - alpha)|`` and
            mean ``|e_k|``, original and calibrated).
        cost: Test failure at ``cost_budget``: no calibration, set calibration,
            set calibration + margin (and Blind-Robust when the run has it).
        cost_differences: Paired differences between those arms.
        cost_budget: The budget of the cost comparison (the final budget by default).
        simultaneous_coverage: Test fraction of instances covered in all repeats
            and all budgets at the simultaneous threshold, with its interval.
        audit_original, audit_calibrated: Full test audit tables.
        arms: Each arm's test episodes at ``cost_budget`` (the rows ``cost`` and ``cost_differences``
            are computed from), so two calibrations' arms can be paired (Table V's set + margin row).
    """

    alpha: float
    budgets: list[int]
    n_calibration: int
    thresholds: dict[int, float]
    simultaneous_threshold: float
    margin: MarginResult
    distribution_free_margin: float
    table3: pd.DataFrame
    summary: dict[str, float]
    cost: pd.DataFrame
    cost_differences: pd.DataFrame
    cost_budget: int
    simultaneous_coverage: dict[str, float]
    audit_original: pd.DataFrame = field(repr=False)
    audit_calibrated: pd.DataFrame = field(repr=False)
    arms: dict[str, pd.DataFrame] = field(default_factory=dict, repr=False)

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly summary (infinite thresholds as the string ``"inf"``)."""
        def num(v: float) -> float | str:
            return "inf" if isinstance(v, float) and math.isinf(v) else v

        return {
            "alpha": self.alpha,
            "budgets": self.budgets,
            "n_calibration": self.n_calibration,
            "thresholds": {str(k): num(v) for k, v in self.thresholds.items()},
            "simultaneous_threshold": num(self.simultaneous_threshold),
            "gamma": self.margin.gamma,
            "gamma_satisfied": self.margin.satisfied,
            "distribution_free_margin": num(self.distribution_free_margin),
            "summary": self.summary,
            "cost_budget": self.cost_budget,
            "cost": self.cost.to_dict("records"),
            "cost_differences": self.cost_differences.to_dict("records"),
            "simultaneous_coverage": self.simultaneous_coverage,
            "table3": self.table3.to_dict("records"),
        }


#: The columns :func:`_failure_at` reads of an episode table.
FAILURE_COLUMNS = ("instance_id", "k", "status", "realized")


def _failure_at(table: pd.DataFrame, k: int, counts: np.ndarray, names: np.ndarray, level: float):
    rows = ok_episodes(table)
    rows = rows.loc[rows["k"] == k]
    idx = np.searchsorted(names, rows["instance_id"].to_numpy().astype(str))
    num = np.bincount(idx, weights=rows["realized"].to_numpy(float), minlength=names.size)
    den = np.bincount(idx, minlength=names.size).astype(float)
    return bootstrap_ratio(num, den, counts=counts, level=level), len(rows)


def calibrate(cal_run, test_run, alpha: float = DEFAULT_ALPHA, budgets: Sequence[int] | None = None, *,
              cost_budget: int | None = None, margin_grid: Iterable[float] = GAMMA_GRID,
              resamples: int = DEFAULT_RESAMPLES, seed: int = DEFAULT_SEED, level: float = DEFAULT_LEVEL,
              reuse: bool = True, plateau: str | None = None,
              chunk_instances: int | None = CHUNK_INSTANCES,
              record: list[pd.DataFrame] | None = None) -> CalibrationResult:
    """Calibrate the executor on one run and report its effect on another.

    Steps: beliefs of both runs are recomputed from stored probes; worst-repeat
    coverage scores of the calibration run give ``t_k`` per budget and the
    simultaneous ``t``; the margin ``gamma`` is searched with the calibration
    commits re-executed at ``t_k``; the test commits are re-executed with no
    calibration (``nu``), set calibration (``t_k``) and set calibration + margin,
    and audited.

    Args:
        cal_run: Calibration run directory (or ``LoadedRun``).
        test_run: Test run directory (same model, belief and schedule; disjoint instances).
        alpha: Miscoverage level.
        budgets: Budgets to calibrate (default: every budget the runs commit at).
        cost_budget: Budget of the failure comparison (default: the largest).
        margin_grid: Margin candidates.
        resamples: Cluster-bootstrap resamples.
        seed: Bootstrap seed.
        level: Interval level.
        reuse: Build each retained set and coverage score once per threshold and
            rescore it per margin (True); False recomputes everything per commit, the
            reference path of ``benchmarks/calibrate.py``. Identical results.
        plateau: The set at ``t = 1``: ``prefix`` (the paper) or ``hull`` (no exception
            to the guarantee); default the runs' ``calibration.plateau``.
        chunk_instances: Instances whose beliefs are held at once (None: a whole run), so
            memory does not grow with the runs' size. Identical results.
        record: A list the re-executed rows each result reads are appended to (``Recorder``),
            for a publication to store and :func:`calibration_from_tables` to read.

    Returns:
        The calibration result.
    """
    cal = load_for_commit(cal_run, reuse, plateau, chunk_instances, budgets)
    with cal.beliefs.first_trace_ahead():  # built while the test run is loaded and the pair checked
        test = load_for_commit(test_run, reuse, plateau, chunk_instances, budgets)
        _check_pair(cal, test)
    budgets = _budgets(cal, budgets)
    _budgets(test, budgets)
    cost_budget = max(budgets) if cost_budget is None else int(cost_budget)
    if cost_budget not in budgets:
        raise UsageError(f"cost budget {cost_budget} is not among the calibrated budgets {budgets}")
    rec = Recorder(record)

    # Of each table, only what the results read is kept, chunk by chunk: per-instance scores, sums and
    # optimism, the rows at the cost budget and the margin rows, so memory does not grow with the runs.
    optimism_of = rec.wrap("optimism", functools.partial(_optimism, budgets=budgets), OPTIMISM_COLUMNS)
    scores, margin, [optimism] = search_with_scores(
        cal, lambda scores: _thresholds(scores, alpha, budgets)[0], margin_grid, budgets, rec,
        lambda t_k: [((t_k, None), optimism_of, OPTIMISM_COLUMNS)])
    t_k, t_sim, _ = _thresholds(scores, alpha, budgets)
    # The calibration run is done: its tables, beliefs and engine cache go before the test run's commits.
    cal.release()
    del cal

    # Every test commit in one pass over the test run's chunks. Of the set-calibrated arm only the cost
    # budget's rows are read (Table IV's failure and pairs), so only that budget is committed.
    audited = functools.partial(_audited, k=cost_budget)
    orig, set_rows, full, covered = test.commit(
        (test.nu, None), ({cost_budget: t_k[cost_budget]}, None), (t_k, margin.gamma), (t_sim, None),
        keep=[None] + [AUDIT_COLUMNS] * 3,
        reduce=[audited, rec.wrap("set", functools.partial(_cost_rows, k=cost_budget), SET_COLUMNS),
                rec.wrap("set_margin", audited, AUDIT_COLUMNS),
                functools.partial(_all_covered, budgets=budgets)],
        final=True)
    blind = ok_episodes(test.loaded.table("episodes", where=("method", ["blind_robust"]), columns=FAILURE_COLUMNS))
    return _summarize(CalibrationParts(scores, margin, optimism, orig, set_rows, full, covered, blind),
                      alpha=alpha, budgets=budgets, cost_budget=cost_budget, resamples=resamples, seed=seed, level=level)


#: The columns of the calibration run's stored episode rows that :func:`_stored_scores` reads.
SCORE_COLUMNS = ("instance_id", "k", "method", "variant", "status", "score_s")

#: Thresholds of the calibration scores (``t_k`` or ``t``): what the margin is searched under.
ThresholdsOf = Callable[[pd.DataFrame], "float | dict[int, float]"]
#: The extra requests of the search's pass under given thresholds (see :meth:`_Run.search_margin`).
ExtraOf = Callable[["float | dict[int, float]"], list]


def search_with_scores(cal: _Run, thresholds_of: ThresholdsOf, margin_grid: Iterable[float], budgets: list[int],
                       rec: Recorder, extra_of: ExtraOf = lambda thresholds: []) -> tuple[pd.DataFrame, MarginResult,
                                                                                        list[Any]]:
    """The calibration run's scores (recomputed), and the margin search (with ``extra_of``'s requests)
    under the thresholds they give, in one pass over its beliefs where the run's stored rows tell
    those thresholds beforehand.

    Why: the search needs its thresholds before its pass, and they come from the scores of the
    ``nu`` commit, so the scores took a pass of their own (a third of calibrate's belief
    recomputations). The run stores its ``nu`` commit's rows, whose scores are the recomputed ones
    for a run made by this code under its own config; their thresholds are taken as a guess, the
    search runs under it with the ``nu`` commit beside it, and the guess is checked against the
    recomputed scores' thresholds exactly. Stored rows that are not what the beliefs give (another
    code's run, an imported or edited one) cost a second pass under the recomputed thresholds, its
    recorded rows replacing the first's: the result is always the recomputed scores', bit for bit.

    Returns:
        The scores (instances sorted x budgets), the margin and ``extra_of``'s results.
    """
    guess = _stored_scores(cal, thresholds_of)
    scores = None if guess is not None else calibration_scores(cal)
    thresholds = guess if guess is not None else thresholds_of(scores)
    start = rec.mark()
    extra = extra_of(thresholds) + ([((cal.nu, None), _scores)] if scores is None else [])
    margin, extras = cal.search_margin(thresholds, margin_grid, budgets, *extra, record=rec)
    if scores is not None:
        return scores, margin, extras
    recomputed = extras.pop()
    if recomputed is None:
        raise UsageError(f"{cal.loaded.path}: no episode of the calibration run committed (every one failed)")
    scores = recomputed.sort_index()
    actual = thresholds_of(scores)
    if actual != thresholds:  # the stored rows are not what the recomputed beliefs give
        rec.drop_since(start)
        margin, extras = cal.search_margin(actual, margin_grid, budgets, *extra_of(actual), record=rec)
    return scores, margin, extras


def _stored_scores(cal: _Run, thresholds_of: ThresholdsOf) -> "float | dict[int, float] | None":
    """The thresholds of the calibration run's stored ``nu`` commit scores (a guess that
    :func:`search_with_scores` checks); None where the stored rows give none (no probe rows or
    scores, a budget missing, NaN)."""
    try:
        rows = cal.loaded.table("episodes", where=("method", [PROBE_METHOD]), columns=SCORE_COLUMNS)
        scores = _scores(rows)
        return None if scores is None else thresholds_of(scores.sort_index())
    except (ValueError, KeyError):  # pyarrow's errors for a missing column are ValueErrors too
        return None


#: The columns a publication stores of each recorded request (``Recorder``): what its reduction reads.
OPTIMISM_COLUMNS = ("instance_id", "k", "status", "predicted", "realized")
SET_COLUMNS = ("instance_id", "repeat", "k", "status", "realized")
RAW_GATE_COLUMNS = ("instance_id", "repeat", "k", "status", "predicted", "realized", "escaped", "post_var",
                    "max_surprise")
ADJUSTED_GATE_COLUMNS = ("instance_id", "repeat", "k", "status", "predicted", "realized")


def _thresholds(scores: pd.DataFrame, alpha: float, budgets: list[int]) -> tuple[dict[int, float], float, int]:
    """Fixed-budget thresholds ``t_k``, the budget-simultaneous ``t`` and the calibration instances ``M``."""
    simultaneous = worst_budget_scores(scores, budgets)
    return (budget_thresholds(scores, alpha, budgets), conformal_quantile(simultaneous.to_numpy(), alpha),
            int(simultaneous.size))


@dataclass
class CalibrationParts:
    """What a calibration's results are computed from: the calibration scores, the margin search, and
    the reductions of each commit (``_optimism``, ``_audited``, ``_cost_rows``, ``_all_covered``)."""

    scores: pd.DataFrame
    margin: MarginResult
    optimism: pd.DataFrame
    orig: tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]
    set_rows: pd.DataFrame
    full: tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]
    #: Per test instance, covered at every budget at ``t`` (None: not recorded, no simultaneous coverage).
    covered: pd.Series | None
    blind: pd.DataFrame


def _summarize(parts: CalibrationParts, **options: Any) -> CalibrationResult:
    """The calibration result from its parts: one function for ``calibrate`` (parts reduced chunk by chunk
    from re-executed commits) and ``calibration_from_tables`` (parts reduced from a publication's stored rows).

    Its bootstraps are matrix-vector products (``counts @ x``, ``signs @ d``) of a few MB each, run
    two at a time in threads (``in_threads``); BLAS's own threads add nothing to products this size
    but spin between them, beside ours: 1.2 of 1.9 CPU seconds here at E = 3072 on two CPUs. One
    BLAS thread splits no dot product differently (each draw is one row's dot product), so the
    numbers are the same bits.
    """
    with threadpool_limits(limits=1, user_api="blas"):
        return _summary(parts, **options)


#: The paired cost comparisons (Table IV): (baseline, treatment) arms.
COST_PAIRS = (("no calibration", "set calibration + margin"), ("no calibration", "set calibration"),
              ("set calibration", "set calibration + margin"))


def _summary(parts: CalibrationParts, *, alpha: float, budgets: list[int], cost_budget: int, resamples: int,
             seed: int, level: float) -> CalibrationResult:
    """:func:`_summarize`'s work. Its bootstraps (the two audits, the failure rows, the paired
    comparisons, the simultaneous coverage) are independent jobs, run two at a time in threads: with
    an integer ``seed`` each draws from its own generator, so the same numbers in any order; a
    Generator ``seed`` is one stream, so its jobs run in this thread in the order listed (the
    order of the draws)."""
    t_k, t_sim, n_calibration = _thresholds(parts.scores, alpha, budgets)
    df_margin = optimism_margin(parts.optimism.sort_index(), alpha)
    boot = {"resamples": resamples, "seed": seed, "level": level}
    arms = {"no calibration": parts.orig[2], "set calibration": parts.set_rows,
            "set calibration + margin": parts.full[2]}
    jobs: list[tuple[Any, Callable[[], Any]]] = [
        ("original", lambda: audit_from_sums(*parts.orig[:2], budgets=budgets, **boot)),
        ("calibrated", lambda: audit_from_sums(*parts.full[:2], budgets=budgets, **boot)),
        ("cost", lambda: _cost_table(parts, arms, cost_budget, boot)),
        *[(pair, functools.partial(_compare, arms, pair, boot)) for pair in COST_PAIRS],
        ("simultaneous", lambda: _simultaneous(parts.covered, boot)),
    ]
    done: dict[Any, Any] = {}

    def run(i: int) -> None:
        name, job = jobs[i]
        done[name] = job()

    in_threads(run, range(len(jobs)), None if not isinstance(seed, np.random.Generator) else 1)
    a_orig, a_cal = done["original"], done["calibrated"]
    table3 = pd.DataFrame({"k": a_orig["k"]})
    for name, src in (("original", a_orig), ("calibrated", a_cal)):
        for metric in ("cluster_coverage", "coverage", "optimism"):
            for sfx in ("", "_lo", "_hi"):
                table3[f"{metric}{sfx}_{name}"] = src[f"{metric}{sfx}"].to_numpy()
    table3.insert(1, "threshold", table3["k"].map(t_k))
    nominal = 1.0 - alpha
    s_orig, s_cal = summary_row(a_orig, nominal), summary_row(a_cal, nominal)
    summary = {f"{k}_original": v for k, v in s_orig.items()} | {f"{k}_calibrated": v for k, v in s_cal.items()}
    return CalibrationResult(
        alpha=alpha, budgets=budgets, n_calibration=n_calibration,
        thresholds=t_k, simultaneous_threshold=t_sim, margin=parts.margin, distribution_free_margin=df_margin,
        table3=table3, summary=summary, cost=done["cost"],
        cost_differences=pd.DataFrame([done[pair] for pair in COST_PAIRS]), cost_budget=cost_budget,
        simultaneous_coverage=done["simultaneous"], audit_original=a_orig, audit_calibrated=a_cal, arms=arms,
    )


def _cost_table(parts: CalibrationParts, arms: dict[str, pd.DataFrame], cost_budget: int,
                boot: dict[str, Any]) -> pd.DataFrame:
    """Cost of calibration (Table IV): failure at the cost budget per arm (and Blind-Robust's at its
    own budget), one set of resamples of the test instances for all of them."""
    names = np.unique(parts.orig[0]["instance_id"].to_numpy().astype(str))
    counts = resample_counts(names.size, boot["resamples"], boot["seed"])
    rows = []
    blind = parts.blind
    settings = ([("blind_robust", blind, int(blind["k"].iloc[0]))] if len(blind) else []) + \
        [(label, table, cost_budget) for label, table in arms.items()]
    for label, table, k in settings:
        iv, n = _failure_at(table, k, counts, names, boot["level"])
        rows.append({"setting": label, "k": k, "n_episodes": n,
                     "failure": iv.estimate, "failure_lo": iv.lo, "failure_hi": iv.hi})
    return pd.DataFrame(rows)


def _compare(arms: dict[str, pd.DataFrame], pair: tuple[str, str], boot: dict[str, Any]) -> dict[str, Any]:
    """The paired difference of realized failure between two arms (one row of ``cost_differences``);
    it draws its own resamples (a [resamples, instances] matrix each)."""
    base, treat = pair
    pdiff = paired_bootstrap(arms[base], arms[treat], "realized", **boot)
    return {"baseline": base, "treatment": treat, "difference": pdiff.difference.estimate,
            "lo": pdiff.difference.lo, "hi": pdiff.difference.hi, "p_sign_flip": pdiff.p_sign_flip,
            "n_pairs": pdiff.n_pairs, "n_clusters": pdiff.n_clusters}


def _simultaneous(covered: pd.Series | None, boot: dict[str, Any]) -> dict[str, float]:
    """Simultaneous coverage on test, measured on the sets as constructed at ``t`` (NaN when not recorded)."""
    if covered is None:
        return {"cluster_coverage": math.nan, "lo": math.nan, "hi": math.nan}
    per_inst = covered.sort_index().astype(float)
    iv = cluster_bootstrap_mean(per_inst.to_numpy(), per_inst.index.to_numpy(), **boot)
    return {"cluster_coverage": iv.estimate, "lo": iv.lo, "hi": iv.hi}


def _stored_margin(rows: pd.DataFrame, grid: Iterable[float], budgets: list[int]) -> MarginResult:
    """The margin search again, each candidate's table read from the stored ``margin`` rows.

    Raises:
        KeyError: The search asks for a margin the publication did not store.
    """
    by_gamma = {round(float(g), 10): part for g, part in rows.groupby("gamma", sort=False)}

    def evaluate(gamma: float) -> pd.DataFrame:
        if round(gamma, 10) not in by_gamma:
            raise KeyError(f"the margin search evaluates gamma = {gamma}, whose rows are not stored")
        predicted, realized = _margin_rows(by_gamma[round(gamma, 10)], budgets)
        return pd.DataFrame({"predicted": predicted, "realized": realized})

    return select_margin(evaluate, margin_candidates(grid), budgets=None)


def _request(commits: pd.DataFrame, request: str, columns: Sequence[str]) -> pd.DataFrame:
    """One request's stored rows and columns, with the dtypes it was committed with (a column other
    requests lack is stored nullable: integers and flags are restored here)."""
    rows = commits.loc[commits["request"] == request, [c for c in columns if c in commits.columns]]
    rows = rows.reset_index(drop=True)
    for column, dtype in (("repeat", "int64"), ("k", "int64"), ("covered", bool), ("escaped", bool)):
        if column in rows.columns and not rows[column].isna().any():
            rows[column] = rows[column].astype(dtype)
    return rows


def calibration_from_tables(commits: pd.DataFrame, cal_episodes: pd.DataFrame, test_episodes: pd.DataFrame,
                            alpha: float, budgets: Sequence[int], *, cost_budget: int | None = None,
                            margin_grid: Iterable[float] = GAMMA_GRID, resamples: int = DEFAULT_RESAMPLES,
                            seed: int = DEFAULT_SEED, level: float = DEFAULT_LEVEL) -> CalibrationResult:
    """:func:`calibrate`'s result from stored tables, for ``probecommit verify``.

    Args:
        commits: The rows :func:`calibrate` recorded (``record=``) of one calibration.
        cal_episodes: The calibration run's stored episodes (its uncalibrated ``nu`` commits).
        test_episodes: The test run's stored episodes (its ``nu`` commits and Blind-Robust rows).
        alpha, budgets, cost_budget, margin_grid, resamples, seed, level: As :func:`calibrate`'s.

    Returns:
        The result :func:`calibrate` returned, when the stored rows are the ones it committed; its
        simultaneous coverage is NaN (its rows are not stored).
    """
    budgets = sorted(int(k) for k in budgets)
    cost_budget = max(budgets) if cost_budget is None else int(cost_budget)
    probe = lambda t: t.loc[t["method"] == PROBE_METHOD]  # noqa: E731
    scores = _scores(probe(cal_episodes)).sort_index()
    margin = _stored_margin(_request(commits, "margin", (*MARGIN_COLUMNS, "gamma")), margin_grid, budgets)
    optimism = _optimism(_request(commits, "optimism", OPTIMISM_COLUMNS), budgets)
    parts = CalibrationParts(
        scores, margin, optimism, _audited(probe(test_episodes), cost_budget),
        _cost_rows(_request(commits, "set", SET_COLUMNS), cost_budget),
        _audited(_request(commits, "set_margin", AUDIT_COLUMNS), cost_budget),
        None,  # a publication prints no simultaneous coverage, so it stores no rows for it
        ok_episodes(test_episodes.loc[test_episodes["method"] == "blind_robust", list(FAILURE_COLUMNS)]))
    return _summarize(parts, alpha=alpha, budgets=budgets, cost_budget=cost_budget, resamples=resamples, seed=seed,
                      level=level)


# ----------------------------------------------------------------------------- gates


def gates(cal_run, test_run, alpha: float = DEFAULT_ALPHA, budgets: Sequence[int] | None = None, *,
          target_rate: float = DEFAULT_TARGET_RATE, margin_grid: Iterable[float] = GAMMA_GRID,
          post_var_executor: str = "raw", resamples: int = DEFAULT_RESAMPLES, seed: int = DEFAULT_SEED,
          reuse: bool = True, plateau: str | None = None,
          chunk_instances: int | None = CHUNK_INSTANCES, record: list[pd.DataFrame] | None = None) -> GatesResult:
    """Commit gates on the test run with the decision layer calibrated on the calibration run.

    The decision layer uses the budget-simultaneous threshold ``t`` over the
    nested budgets and a margin searched under ``t`` (Sec. VI). Gates: the raw
    scenario fraction of the uncalibrated ``nu`` executor, the adjusted score of
    the calibrated + margin executor, posterior variance, and the hindsight oracle.

    Args:
        cal_run: Calibration run directory (or ``LoadedRun``).
        test_run: Test run directory.
        alpha: Miscoverage level of the simultaneous threshold.
        budgets: Nested budgets (default: every budget the runs commit at).
        target_rate: Operating-point commit rate (0.6 in the paper).
        margin_grid: Margin candidates.
        post_var_executor: Whose aims the posterior-variance gate executes.
        resamples: Bootstrap resamples of the surprise AUC.
        seed: Bootstrap seed.
        reuse: Build each retained set and coverage score once per threshold and
            rescore it per margin (True); False recomputes everything per commit, the
            reference path of ``benchmarks/calibrate.py``. Identical results.
        plateau: The set at ``t = 1``: ``prefix`` (the paper) or ``hull`` (no exception
            to the guarantee); default the runs' ``calibration.plateau``.
        chunk_instances: Instances whose beliefs are held at once (None: a whole run).
        record: A list the re-executed rows the gates read are appended to (``Recorder``), for a
            publication to store and :func:`gates_from_commits` to read.

    Returns:
        Curves, areas and the committed pools; ``info`` holds ``t``, ``gamma``
        and the surprise AUC table of the raw test episodes.
    """
    cal = load_for_commit(cal_run, reuse, plateau, chunk_instances, budgets)
    with cal.beliefs.first_trace_ahead():  # built while the test run is loaded and the pair checked
        test = load_for_commit(test_run, reuse, plateau, chunk_instances, budgets)
        _check_pair(cal, test)
    budgets = _budgets(cal, budgets)
    _budgets(test, budgets)
    rec = Recorder(record)

    def simultaneous(scores: pd.DataFrame) -> float:
        return conformal_quantile(worst_budget_scores(scores, budgets).to_numpy(), alpha)

    scores, margin, _ = search_with_scores(cal, simultaneous, margin_grid, budgets, rec)
    t_sim = simultaneous(scores)
    cal.release()
    del cal  # the calibration run is done before the test run's commits
    raw, adjusted = test.commit((test.nu, None), (t_sim, margin.gamma), final=True)
    rec.keep("raw", raw, [c for c in RAW_GATE_COLUMNS if c in raw.columns])
    rec.keep("adjusted", adjusted, ADJUSTED_GATE_COLUMNS)
    return _gates_result(raw, adjusted, t_sim, margin, alpha=alpha, budgets=budgets, target_rate=target_rate,
                         post_var_executor=post_var_executor, resamples=resamples, seed=seed)


def _gates_result(raw: pd.DataFrame, adjusted: pd.DataFrame, t_sim: float, margin: MarginResult, *, alpha: float,
                  budgets: list[int], target_rate: float, post_var_executor: str, resamples: int,
                  seed: int) -> GatesResult:
    """The gates and their provenance from the two executors' test tables (one function for
    :func:`gates` and :func:`gates_from_commits`)."""
    result = gates_from_tables(raw, adjusted, budgets=budgets, target_rate=target_rate,
                               post_var_executor=post_var_executor)
    raw_b = raw.loc[raw["k"].isin(budgets)]
    result.info.update(threshold=t_sim, gamma=margin.gamma, gamma_satisfied=margin.satisfied, alpha=alpha,
                       surprise=surprise_auc(raw_b, resamples=resamples, seed=seed))
    return result


def gates_from_commits(commits: pd.DataFrame, cal_episodes: pd.DataFrame, alpha: float, budgets: Sequence[int], *,
                       target_rate: float = DEFAULT_TARGET_RATE, margin_grid: Iterable[float] = GAMMA_GRID,
                       post_var_executor: str = "raw", resamples: int = DEFAULT_RESAMPLES,
                       seed: int = DEFAULT_SEED) -> GatesResult:
    """:func:`gates`'s result from the rows it recorded (``record=``) and the calibration run's stored
    episodes, for ``probecommit verify``: ``t`` from the stored scores, the margin searched again over
    the stored margin rows, the gates swept again over the stored test rows."""
    budgets = sorted(int(k) for k in budgets)
    cal = cal_episodes.loc[cal_episodes["method"] == PROBE_METHOD]
    t_sim = conformal_quantile(worst_budget_scores(_scores(cal).sort_index(), budgets).to_numpy(), alpha)
    margin = _stored_margin(_request(commits, "margin", (*MARGIN_COLUMNS, "gamma")), margin_grid, budgets)
    raw = _request(commits, "raw", RAW_GATE_COLUMNS)
    adjusted = _request(commits, "adjusted", ADJUSTED_GATE_COLUMNS)
    return _gates_result(raw, adjusted, t_sim, margin, alpha=alpha, budgets=budgets,
                         target_rate=target_rate, post_var_executor=post_var_executor, resamples=resamples,
                         seed=seed)
