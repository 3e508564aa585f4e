"""The margin search in one pass (``runner.margin_search``) equals the margin-by-margin search to the last
bit: the margin, the search table, the calibration and gates results, and every recorded row in its order
(what ``probecommit verify`` recomputes the published margins from)."""

import json

import numpy as np
import pandas as pd
import pytest

from probecommit.accel import production
from probecommit.core.executors import NUMPY_KERNELS, ProbeRobust
from probecommit.runner.build import build_model
from probecommit.runner.calibration import Recorder, calibrate, gates
from probecommit.runner.replay import RunBeliefs
from tests.conftest import cal_test_runs, small_config

GRID = np.round(np.arange(100, 29, -2) / 100.0, 2)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    return cal_test_runs(tmp_path_factory.mktemp("margin_runs"), (5, 6), count=7, repeats=3)


def _calibrated(runs, reuse, chunk, **kwargs):
    record: list = []
    res = calibrate(runs["cal"], runs["test"], alpha=0.2, resamples=50, seed=5, chunk_instances=chunk, reuse=reuse,
                    record=record, **kwargs)
    return res, Recorder(record).table()


@pytest.mark.parametrize("chunk, per_pass", [(None, None), (2, None), (3, 1), (2, 4)])
def test_swept_search_equals_margin_by_margin_with_the_same_recorded_rows(runs, chunk, per_pass, monkeypatch):
    """One chunk, several, and margin-by-margin passes of one or four margins (the rows are then
    recorded pass by pass): the same result, search table and recorded rows, in the same order."""
    import probecommit.runner.calibration as calibration

    if per_pass is not None:
        monkeypatch.setattr(calibration, "MARGIN_BLOCK_ROWS", per_pass * 7 * 3 * 5)
    swept, swept_rows = _calibrated(runs, True, chunk)
    reference, reference_rows = _calibrated(runs, False, chunk)
    assert len(swept.margin.search) > 2  # the scan reads several margins
    pd.testing.assert_frame_equal(swept.margin.search, reference.margin.search, check_exact=True)
    assert json.dumps(swept.to_dict(), sort_keys=True) == json.dumps(reference.to_dict(), sort_keys=True)
    pd.testing.assert_frame_equal(swept_rows, reference_rows, check_exact=True)
    assert set(swept_rows["request"]) == {"margin", "optimism", "set", "set_margin"}


@pytest.mark.parametrize("chunk", [None, 3])
def test_swept_gates_equal_margin_by_margin(runs, chunk):
    tables = {}
    for reuse in (True, False):
        record: list = []
        res = gates(runs["cal"], runs["test"], alpha=0.2, resamples=50, seed=5, chunk_instances=chunk, reuse=reuse,
                    record=record)
        tables[reuse] = (res.info["gamma"], res.info["gamma_satisfied"], Recorder(record).table())
    assert tables[True][:2] == tables[False][:2]
    pd.testing.assert_frame_equal(tables[True][2], tables[False][2], check_exact=True)


def test_a_failed_trajectory_is_recorded_as_margin_by_margin(runs, tmp_path, monkeypatch):
    """The run's failed rollout rows are recorded per read margin after the chunks, as before."""
    import probecommit.runner.build as build
    from probecommit.runner.study import run_study

    real_build = build.build_simulator
    calls = [0]

    class Flaky:
        def __init__(self, sim):
            self._sim = sim

        def probe(self, theta, u, rng):
            calls[0] += 1
            if calls[0] == 7:
                return float("nan") * self._sim.probe(theta, u, rng)
            return self._sim.probe(theta, u, rng)

        def __getattr__(self, name):
            return getattr(self._sim, name)

    monkeypatch.setattr(build, "build_simulator", lambda cfg: Flaky(real_build(cfg)))
    cal = run_study(small_config(name="cal", instances={"split": "cal", "count": 8, "seed": 4}, repeats=3),
                    tmp_path / "flaky").run_dir
    monkeypatch.undo()
    pair = {"cal": cal, "test": runs["test"]}
    for chunk in (None, 3):
        swept, swept_rows = _calibrated(pair, True, chunk)
        reference, reference_rows = _calibrated(pair, False, chunk)
        assert (swept_rows["status"] == "failed").any()
        pd.testing.assert_frame_equal(swept_rows, reference_rows, check_exact=True)
        assert swept.to_dict() == reference.to_dict()


def test_a_run_of_one_chunk_asks_the_engine_only_for_the_margins_read(runs):
    """Margin by margin, a run of one chunk executed the aims of the margins the scan read; so does the sweep."""
    asked = {}
    for reuse in (True, False):
        beliefs = RunBeliefs.of(runs["cal"], chunk_instances=None)
        from probecommit.runner.calibration import _Run, load_for_commit

        run = _Run(load_for_commit(runs["cal"]).loaded, beliefs, reuse)
        margin, _ = run.search_margin(0.8, GRID, beliefs.budgets)
        asked[reuse] = (margin.gamma, sorted(beliefs.simulator.answered_keys()))
    assert asked[True] == asked[False]


@pytest.mark.parametrize("kernels", ["numpy", "numba"])
@pytest.mark.parametrize("threshold", [0.3, 0.8, 1.0, 1.4])
def test_choose_margins_is_choose_under_each_margin(runs, kernels, threshold):
    """``ProbeRobust.choose_margins``: aims and scores of every margin, equal to ``choose`` margin by margin
    (a prefix set and a grown set, t > 1, scored in two blocks)."""
    beliefs = RunBeliefs.of(runs["cal"], chunk_instances=None)
    trace = beliefs.trace(beliefs.chunks[0])
    model = build_model(beliefs.config)
    executor = ProbeRobust(model, kernels=production(kernels).sets if kernels == "numba" else NUMPY_KERNELS)
    state = trace.states[3]
    retained = executor.retain(state.particles, state.weights, threshold)
    index, score = executor.choose_margins(retained, GRID, trace.batch.episode_context)
    assert index.shape == score.shape == (len(GRID), trace.batch.n_episodes)
    for m, gamma in enumerate(GRID):
        one = executor.with_model(model.with_margin(gamma)).choose(retained, trace.batch.episode_context)
        np.testing.assert_array_equal(index[m], one.index)
        np.testing.assert_array_equal(score[m], one.score)
    assert len(np.unique(index, axis=0)) > 1  # the margins choose differently


def test_traces_computed_ahead_in_a_thread_give_the_same_rows_and_no_thread_outlives_the_call(runs, monkeypatch):
    """With two CPUs the next chunk's beliefs are built in a second thread while a chunk is committed:
    the same result and recorded rows as one thread, and the thread is joined when the pass ends."""
    import threading

    out = {}
    for threads in ("1", "2"):
        monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", threads)
        out[threads] = _calibrated(runs, True, 2)
        assert not [t for t in threading.enumerate() if t.name.startswith("probecommit-trace")]
    assert out["1"][0].to_dict() == out["2"][0].to_dict()
    pd.testing.assert_frame_equal(out["1"][1], out["2"][1], check_exact=True)


def test_verified_tables_are_read_from_an_arrow_buffer_as_from_the_file(runs):
    """``RunDir.read_verified`` reads Parquet from an Arrow buffer (no Arrow thread enters the interpreter:
    the abort at exit of issue 42) and gives the frames a read of the file gives, with filters and columns."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from probecommit.store.rundir import RunDir

    run = RunDir(runs["cal"])
    assert isinstance(run._verified_source("episodes"), pa.BufferReader)
    for name in ("instances", "probes", "episodes", "engine_cache"):
        pd.testing.assert_frame_equal(run.read_verified(name), pd.read_parquet(run.table_path(name)), check_exact=True)
        assert run.read_verified_arrow(name).equals(pq.read_table(run.table_path(name)))
    where, columns = ("method", ["probe_robust"]), ["instance_id", "k", "realized"]
    pd.testing.assert_frame_equal(run.read_verified("episodes", where, columns),
                                  pd.read_parquet(run.table_path("episodes"), filters=[("method", "in", where[1])],
                                                  columns=columns), check_exact=True)


def test_a_pass_builds_its_first_trace_in_the_calling_thread_beside_the_second(runs, monkeypatch):
    """With two CPUs a pass does not begin by waiting for the thread: chunk 0's beliefs are built in the
    calling thread while the thread builds chunk 1's, and every later chunk's are built in the thread, each
    once a pass (the rows are one thread's: the test above)."""
    import threading

    built = []
    real_trace = RunBeliefs.trace

    def trace(self, rows, keep_weights=False):
        built.append((rows.start, threading.current_thread() is threading.main_thread()))
        return real_trace(self, rows, keep_weights)

    monkeypatch.setattr(RunBeliefs, "trace", trace)
    monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", "2")
    beliefs = RunBeliefs.of(runs["cal"], chunk_instances=2)
    starts = [rows.start for rows in beliefs.chunks]
    assert len(starts) > 2
    for _ in range(2):  # two passes, each the same
        built.clear()
        beliefs.commit([{"thresholds": 0.8}], reduce=[lambda table: None])
        assert sorted(built) == [(start, start == 0) for start in starts]
    assert not [t for t in threading.enumerate() if t.name.startswith("probecommit-trace")]


def test_the_first_trace_built_while_the_test_run_loads_is_the_first_passs(runs, monkeypatch):
    """``calibrate`` builds the calibration run's first beliefs in the thread while it loads the test run
    (``RunBeliefs.first_trace_ahead``): once, and the pass does not build them again; a block that raises keeps
    nothing and leaves no thread."""
    import threading

    built = []
    real_trace = RunBeliefs.trace

    def trace(self, rows, keep_weights=False):
        built.append((id(self), rows.start, threading.current_thread() is threading.main_thread()))
        return real_trace(self, rows, keep_weights)

    monkeypatch.setattr(RunBeliefs, "trace", trace)
    monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", "2")
    beliefs = RunBeliefs.of(runs["cal"], chunk_instances=2)
    with pytest.raises(RuntimeError, match="planted"):
        with beliefs.first_trace_ahead():
            raise RuntimeError("planted")
    assert beliefs._first is None
    assert not [t for t in threading.enumerate() if t.name.startswith("probecommit-trace")]
    with beliefs.first_trace_ahead():
        pass
    ahead = beliefs._first
    again = real_trace(beliefs, beliefs.chunks[0], True)
    np.testing.assert_array_equal(ahead.states[3].particles, again.states[3].particles)
    built.clear()
    beliefs.commit([{"thresholds": 0.8}], reduce=[lambda table: None])
    assert sorted(start for _, start, _ in built) == [rows.start for rows in beliefs.chunks][1:]
    assert beliefs._first is None

    built.clear()
    _calibrated(runs, True, 2)
    firsts = [(who, main) for who, start, main in built if start == 0]
    assert len(firsts) == 2 and len({who for who, _ in firsts}) == 2  # each run's first trace once
    assert firsts[0][1] is False  # the calibration run's, in the thread
    assert not [t for t in threading.enumerate() if t.name.startswith("probecommit-trace")]
