"""Replay, calibration and gates in bounded chunks of instances equal the whole-run results bit for bit."""

import json

import numpy as np
import pandas as pd
import pytest

from probecommit.runner.calibration import calibrate, gates
from probecommit.runner.build import build_executors, build_model, config_executors
from probecommit.runner.replay import (LoadedRun, RunBeliefs, _chunk_slices, load_run, probe_batch, replay_episodes,
                                      trace_for_run)
from tests.conftest import cal_test_runs, small_config


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    return cal_test_runs(tmp_path_factory.mktemp("chunk_runs"), (5, 6), count=7, repeats=3,
                         methods=["blind_bayes", "blind_robust", "probe_robust"])


def test_chunk_slices_hold_whole_instances():
    ids = np.array(["a", "a", "b", "b", "c", "c", "d"], dtype=object)
    assert _chunk_slices(ids, 3) == [slice(0, 6), slice(6, 7)]
    assert _chunk_slices(ids, 1) == [slice(0, 2), slice(2, 4), slice(4, 6), slice(6, 7)]
    assert _chunk_slices(ids, None) == [slice(0, 7)] == _chunk_slices(ids, 10)
    assert _chunk_slices(ids[:0], 2) == [slice(0, 0)]
    with pytest.raises(ValueError, match="at least 1"):
        _chunk_slices(ids, 0)


def test_probe_batch_puts_probes_in_the_runs_episode_order_whatever_the_row_order(runs):
    """Episodes in the instances table's order, then repeat; probes by j; each id one of the instances table's strings."""
    loaded = load_run(runs["cal"])
    model = build_model(loaded.config)
    probes = loaded.table("probes")
    shuffled = probes.sample(frac=1.0, random_state=3).reset_index(drop=True)
    batch = probe_batch(LoadedRun(loaded.path, loaded.config, loaded.instances, probes=shuffled), model)
    order = list(loaded.instances["instance_id"])
    expected = probes.assign(_o=probes["instance_id"].map(order.index)).sort_values(["_o", "repeat", "j"])
    n_e, k = 7 * 3, 5
    assert list(batch.instance_id) == list(expected["instance_id"].iloc[::k])
    np.testing.assert_array_equal(batch.repeat, expected["repeat"].iloc[::k])
    np.testing.assert_array_equal(batch.u[..., 0], expected["u"].to_numpy().reshape(n_e, k))
    np.testing.assert_array_equal(batch.y[..., 0], expected["y"].to_numpy().reshape(n_e, k))
    positions = [order.index(i) for i in batch.instance_id]
    np.testing.assert_array_equal(batch.instance_index, loaded.instances["instance_index"].to_numpy()[positions])
    np.testing.assert_array_equal(batch.truths[:, 0], loaded.instances["true_x_hole"].to_numpy()[positions])
    assert len({id(i) for i in batch.instance_id}) == 7  # shared with the instances table, not a string per episode


@pytest.mark.parametrize("chunk", [1, 3])
def test_chunked_replay_equals_whole_run(runs, chunk):
    loaded = load_run(runs["cal"])
    overrides = {"model": {"boundary": "corrected"}}
    whole, _ = replay_episodes(loaded, overrides, chunk_instances=None)
    chunked, _ = replay_episodes(loaded, overrides, chunk_instances=chunk)
    assert len(RunBeliefs.of(loaded, chunk_instances=chunk).chunks) == -(-7 // chunk)
    pd.testing.assert_frame_equal(chunked, whole, check_exact=True)
    assert set(whole["method"]) == {"blind_bayes", "blind_robust", "probe_robust"}


def test_whole_run_trace_is_unchanged(runs):
    """``trace_for_run`` (figures, the decisive-tap search) still holds the whole run."""
    trace, _, _ = trace_for_run(runs["cal"])
    assert trace.batch.n_episodes == 7 * 3 and trace.budgets == [1, 2, 3, 4, 5]


@pytest.mark.parametrize("chunk", [1, 4])
def test_chunked_calibration_equals_whole_run(runs, chunk):
    whole = calibrate(runs["cal"], runs["test"], resamples=100, chunk_instances=None)
    chunked = calibrate(runs["cal"], runs["test"], resamples=100, chunk_instances=chunk)
    assert json.dumps(chunked.to_dict(), sort_keys=True, default=str) == \
        json.dumps(whole.to_dict(), sort_keys=True, default=str)
    for name in ("table3", "audit_original", "audit_calibrated", "cost", "cost_differences"):
        pd.testing.assert_frame_equal(getattr(chunked, name), getattr(whole, name), check_exact=True)
    # A chunked run commits every margin left in one pass, but the scan reports the same rows.
    pd.testing.assert_frame_equal(chunked.margin.search, whole.margin.search, check_exact=True)


def test_chunked_calibration_with_a_margin_found_late(runs):
    """A grid whose first values fail makes the whole-run scan commit margin by margin."""
    grid = [1.0, 0.9, 0.5, 0.3, 0.1]
    whole = calibrate(runs["cal"], runs["test"], resamples=50, margin_grid=grid, chunk_instances=None)
    chunked = calibrate(runs["cal"], runs["test"], resamples=50, margin_grid=grid, chunk_instances=2)
    pd.testing.assert_frame_equal(chunked.margin.search, whole.margin.search, check_exact=True)
    assert chunked.to_dict() == whole.to_dict()


def test_margin_search_in_passes_of_few_margins_equals_the_whole_scan(runs, monkeypatch):
    """The margin-by-margin path (``reuse=False``): a run of several chunks commits the scan's margins a
    few per pass (bounded tables): one margin a pass, or two, gives the scan and the result of the
    whole-run search (the default path sweeps every margin in one pass: tests/runner/test_margin_search.py)."""
    import probecommit.runner.calibration as calibration

    grid = [1.0, 0.9, 0.5, 0.3, 0.1]
    whole = calibrate(runs["cal"], runs["test"], resamples=50, margin_grid=grid, chunk_instances=None)
    passes = []
    original = calibration._Run.commit

    def counted(self, *requests, **kwargs):
        passes.append(len(requests))
        return original(self, *requests, **kwargs)

    monkeypatch.setattr(calibration._Run, "commit", counted)
    rows = 7 * 3 * 5  # the calibration run's episodes x budgets: one margin's table
    for per_pass in (1, 2):
        passes.clear()
        monkeypatch.setattr(calibration, "MARGIN_BLOCK_ROWS", per_pass * rows)
        chunked = calibrate(runs["cal"], runs["test"], resamples=50, margin_grid=grid, chunk_instances=2, reuse=False)
        pd.testing.assert_frame_equal(chunked.margin.search, whole.margin.search, check_exact=True)
        assert chunked.to_dict() == whole.to_dict()
        # The calibration run's margin passes (the first also commits the set table and the uncalibrated
        # table whose scores check the stored rows' t_k), then the test run's pass.
        assert max(passes[1:-1], default=per_pass) <= per_pass and passes[0] == per_pass + 2


def test_a_loaded_run_reads_its_large_tables_when_asked_and_verifies_them(runs, tmp_path):
    import shutil

    from probecommit.store.rundir import RunDirError

    loaded = load_run(runs["cal"])
    assert all(loaded._held[name] is None for name in loaded.TABLES)  # nothing read yet
    whole = pd.read_parquet(runs["cal"] / "episodes.parquet")
    rows = loaded.table("episodes", where=("method", ["blind_robust", "rollout"]))
    pd.testing.assert_frame_equal(rows.reset_index(drop=True),
                                  whole.loc[whole["method"].isin(["blind_robust", "rollout"])].reset_index(drop=True))
    assert loaded._held["episodes"] is None  # a table asked for is not kept ...
    pd.testing.assert_frame_equal(loaded.episodes, whole)
    assert loaded._held["episodes"] is loaded.episodes  # ... the attribute reads it once and keeps it
    copy = tmp_path / "run"
    shutil.copytree(runs["cal"], copy)
    altered = load_run(copy)
    (copy / "probes.parquet").write_bytes(b"not the run's probes")
    with pytest.raises(RunDirError, match="probes.parquet changed since the run wrote its manifest"):
        altered.table("probes")


def test_chunked_gates_equal_whole_run(runs):
    whole = gates(runs["cal"], runs["test"], resamples=50, chunk_instances=None)
    chunked = gates(runs["cal"], runs["test"], resamples=50, chunk_instances=2)
    pd.testing.assert_frame_equal(chunked.summary, whole.summary, check_exact=True)
    pd.testing.assert_frame_equal(chunked.curves, whole.curves, check_exact=True)
    assert json.dumps(chunked.info, sort_keys=True, default=str) == json.dumps(whole.info, sort_keys=True, default=str)


def test_restricted_beliefs_equal_beliefs_computed_alone(runs):
    """A re-split takes its instances' beliefs from the pool's: the same arrays, bit for bit."""
    pool = RunBeliefs.of(runs["cal"], chunk_instances=None)
    ids = sorted(set(pool.batch.instance_id))
    keep = [ids[4], ids[1], ids[6]]  # any order: rows stay in the run's order
    part = pool.restrict(keep)
    alone = RunBeliefs(pool.config, pool.model, pool.simulator, pool.pfilter,
                       pool.batch.subset(np.flatnonzero(np.isin(pool.batch.instance_id, keep))), [slice(0, 9)])
    assert part._kept is None  # taken when first committed: a re-split's halves are not both copied at once
    committed = part.commit([{"thresholds": 0.8}])[0]
    taken, computed = part._kept[0], alone.trace(alone.chunks[0])
    assert list(taken.batch.instance_id) == list(computed.batch.instance_id) and len(taken.batch.instance_id) == 9
    assert taken.budgets == computed.budgets
    for k in computed.states:
        a, b = taken.states[k], computed.states[k]
        for name in ("particles", "log_weights", "resampled", "u_hist", "y_hist", "lost", "log_evidence"):
            x, y = getattr(a, name), getattr(b, name)
            assert (x is None and y is None) or np.array_equal(x, y, equal_nan=True), (k, name)
    np.testing.assert_array_equal(taken.surprise, computed.surprise)
    pd.testing.assert_frame_equal(committed, alone.commit([{"thresholds": 0.8}])[0], check_exact=True)
    with pytest.raises(ValueError, match="one chunk"):
        RunBeliefs.of(runs["cal"], chunk_instances=2).restrict(keep)


def test_calibration_of_a_subset_with_the_pools_beliefs_equals_recomputing(runs):
    from probecommit.studies.insertion import subset_run

    loaded, test = load_run(runs["cal"]), load_run(runs["test"])
    ids = sorted(set(loaded.instances["instance_id"]))[:5]
    pool = RunBeliefs.of(loaded, chunk_instances=None)
    shared = calibrate(subset_run(loaded, ids, pool), test, resamples=50)
    alone = calibrate(subset_run(loaded, ids), test, resamples=50)
    assert json.dumps(shared.to_dict(), sort_keys=True, default=str) == json.dumps(alone.to_dict(), sort_keys=True, default=str)
    pd.testing.assert_frame_equal(shared.table3, alone.table3, check_exact=True)


def test_commit_of_some_columns_equals_those_columns_of_the_whole_table(runs):
    """``commit(..., columns=C)`` (what a margin search asks for) is ``commit(...)[C]``, dtypes included."""
    from probecommit.runner.inference import commit

    beliefs = RunBeliefs.of(runs["cal"], chunk_instances=None)
    trace = beliefs.trace(beliefs.chunks[0])
    kwargs = dict(thresholds=1.3, margin=0.9, executors=build_executors(("blind_robust", "probe_robust"), beliefs.model))
    whole = commit(trace, beliefs.model, beliefs.simulator, **kwargs)
    for columns in (("k", "status", "predicted", "realized"), ("covered", "instance_id", "action", "n_retained")):
        some = commit(trace, beliefs.model, beliefs.simulator, columns=columns, **kwargs)
        pd.testing.assert_frame_equal(some, whole[list(columns)], check_exact=True)
    with pytest.raises(ValueError, match="no column 'aim'"):
        commit(trace, beliefs.model, beliefs.simulator, columns=("k", "aim"), **kwargs)


def test_beliefs_kept_at_some_budgets_commit_the_rows_of_the_whole_trace(runs):
    """``RunBeliefs.of(..., budgets=K)`` keeps and commits only K; its rows are the full trace's rows at K."""
    whole = RunBeliefs.of(runs["cal"], chunk_instances=None)
    some = RunBeliefs.of(runs["cal"], chunk_instances=2, budgets=[4, 2])
    assert some.budgets == [2, 4] and whole.budgets == [1, 2, 3, 4, 5]
    assert sorted(some.trace(some.chunks[0]).states) == [2, 4]  # no prior: only the blind methods read it
    full = whole.commit([{"thresholds": 0.8}])[0]
    kept = some.commit([{"thresholds": 0.8}])[0]
    expected = full[full.k.isin([2, 4])].reset_index(drop=True)
    pd.testing.assert_frame_equal(kept, expected, check_exact=True)
    with pytest.raises(ValueError, match=r"budget\(s\) \[7\] not in the run"):
        RunBeliefs.of(runs["cal"], budgets=[2, 7])
    with pytest.raises(ValueError, match=r"prior belief \(k = 0\)"):
        some.commit([{"thresholds": 0.8, "executors": build_executors(("blind_robust",), some.model)}])


@pytest.mark.parametrize("budgets", [None, [3]])
def test_a_whole_trace_built_in_chunks_equals_one_batch(runs, budgets):
    """The kept trace of a re-split pool, built a few instances at a time, is the one-batch trace bit for bit."""
    pool = RunBeliefs.of(runs["cal"], chunk_instances=None, budgets=budgets)
    one, chunked = pool.trace(pool.chunks[0]), pool._whole_trace(chunk_instances=2)
    assert sorted(chunked.states) == sorted(one.states) and chunked.batch.n_episodes == one.batch.n_episodes == 21
    assert list(chunked.batch.instance_id) == list(one.batch.instance_id)
    for k in one.states:
        for name in ("particles", "log_weights", "resampled", "u_hist", "y_hist", "accepted", "lost", "log_evidence"):
            x, y = getattr(chunked.states[k], name), getattr(one.states[k], name)
            assert (x is None and y is None) or (x.dtype == y.dtype and np.array_equal(x, y, equal_nan=True)), (k, name)
    np.testing.assert_array_equal(chunked.surprise, one.surprise)
    np.testing.assert_array_equal(chunked.lost, one.lost)


def test_calibration_and_gates_of_some_budgets_equal_keeping_every_budget(runs):
    """calibrate/gates with ``budgets`` keep only those beliefs; the result equals keeping them all."""
    def with_every_budget(run_dir):
        loaded = load_run(run_dir)
        loaded.beliefs = RunBeliefs.of(loaded)
        return loaded

    for budgets in ([3], [1, 4]):
        fast = calibrate(runs["cal"], runs["test"], budgets=budgets, resamples=50)
        every = calibrate(with_every_budget(runs["cal"]), with_every_budget(runs["test"]), budgets=budgets, resamples=50)
        assert json.dumps(fast.to_dict(), sort_keys=True, default=str) == json.dumps(every.to_dict(), sort_keys=True, default=str)
        pd.testing.assert_frame_equal(fast.audit_original, every.audit_original, check_exact=True)
    g_fast = gates(runs["cal"], runs["test"], budgets=[2, 3], resamples=50)
    g_every = gates(with_every_budget(runs["cal"]), with_every_budget(runs["test"]), budgets=[2, 3], resamples=50)
    pd.testing.assert_frame_equal(g_fast.summary, g_every.summary, check_exact=True)
    pd.testing.assert_frame_equal(g_fast.curves, g_every.curves, check_exact=True)


def test_prune_retained_sets_keeps_what_later_commits_read():
    from probecommit.runner.inference import prune_retained_sets

    cache = {("belief", 1): "b1", "outcomes": {}, ("set", "probe_robust", 1, 0.8, "prefix"): "s",
             ("set", "probe_robust", 1, 1.3, "prefix"): "grown1", ("set", "probe_robust", 2, 1.3, "prefix"): "grown2",
             ("set", "blind_robust", 0, 0.8, "prefix"): "blind"}
    prune_retained_sets(cache, [{2: 1.3}])
    assert set(cache) == {("belief", 1), "outcomes", ("set", "probe_robust", 2, 1.3, "prefix")}
    prune_retained_sets(cache, [0.8])
    assert set(cache) == {("belief", 1), "outcomes"}


def test_several_requests_in_one_pass_equal_each_alone(runs):
    """Sets pruned after their last use, and a final pass releasing a kept trace, change no row."""
    loaded = load_run(runs["cal"])
    requests = [{"thresholds": 0.8}, {"thresholds": {1: 1.2, 3: 1.4}}, {"thresholds": 1.2, "margin": 0.7},
                {"thresholds": 0.8, "margin": 0.9}]
    alone = [RunBeliefs.of(loaded, chunk_instances=None).commit([r], reuse=False)[0] for r in requests]
    for chunk in (None, 3):
        beliefs = RunBeliefs.of(loaded, chunk_instances=chunk)
        together = beliefs.commit(requests, final=True)
        assert beliefs._kept is None
        for a, b in zip(together, alone):
            pd.testing.assert_frame_equal(a, b, check_exact=True)
    kept = RunBeliefs.of(loaded, chunk_instances=None)
    kept.commit(requests[:1])
    assert kept._kept is not None  # a one-chunk run keeps its beliefs for the next call unless told it is the last
    pd.testing.assert_frame_equal(kept.commit(requests[1:2], final=True)[0], alone[1], check_exact=True)
    assert kept._kept is None


def test_calibration_of_runs_with_failed_episodes_keeps_what_the_whole_tables_give(tmp_path, monkeypatch):
    """Failed commits inside the chunks and rollout rows after them: the kept reductions (per-instance
    sums, scores and optimism, rows at the cost budget) give the whole tables' audit, in chunks or not."""
    from probecommit.audit.metrics import audit_table
    from probecommit.runner.calibration import load_for_commit
    from probecommit.runner.study import run_study
    from tests.runner.faults import inject, pick_faults

    configs = {split: small_config(name=split, instances={"split": split, "count": 7, "seed": seed}, repeats=4,
                                   methods=["blind_robust", "probe_robust"]) for split, seed in (("cal", 5), ("test", 6))}
    clean = run_study(configs["test"], tmp_path / "clean").run_dir
    inject(monkeypatch, **pick_faults(clean)["faults"])  # faults on two test instances, kept while calibrating
    cal, test = (run_study(configs[split], tmp_path / split).run_dir for split in ("cal", "test"))
    stored = pd.read_parquet(test / "episodes.parquet")
    assert (stored["method"] == "rollout").any() and ((stored["method"] == "probe_robust") & (stored["status"] == "failed")).any()

    whole = calibrate(cal, test, resamples=100, chunk_instances=None)
    for chunk in (2, 3):
        assert calibrate(cal, test, resamples=100, chunk_instances=chunk).to_dict() == whole.to_dict()
    run = load_for_commit(test)
    [table] = run.commit((run.nu, None))  # the whole validated table, as calibrate audited it before
    pd.testing.assert_frame_equal(whole.audit_original, audit_table(table, budgets=whole.budgets, resamples=100),
                                  check_exact=True)
    assert whole.audit_original["n_failed"].min() >= 1


def test_a_chunk_is_given_only_its_instances_engine_answers_and_none_is_asked_twice(runs, tmp_path):
    """A run of several chunks gives its simulator a chunk's stored answers while that chunk is
    committed (the answers about its instances' truths), keeps the engine's own answers apart,
    and asks the engine exactly the queries the whole-run replay asks; the replay run it writes
    holds the same engine cache."""
    from probecommit.runner.replay import replay_run

    loaded = load_run(runs["cal"])
    overrides = {"model": {"boundary": "corrected"}}
    whole, whole_sim = replay_episodes(loaded, overrides, chunk_instances=None)
    beliefs = RunBeliefs.of(loaded, replace_config(loaded, overrides), chunk_instances=2)
    assert beliefs.answers is not None and not beliefs.simulator.answered_keys()  # every answer is about an instance
    held = []
    commit = beliefs.simulator.cached_key

    def asked(key):
        held.append((key[1], len(beliefs.simulator.answered_keys())))
        return commit(key)

    beliefs.simulator.cached_key = asked
    config = beliefs.config
    request = dict(executors=config_executors(config, beliefs.model))
    [chunked] = beliefs.commit([{"thresholds": config.belief.nu, "margin": None}], **request)
    pd.testing.assert_frame_equal(chunked, whole, check_exact=True)
    assert beliefs.simulator.engine_calls == whole_sim.engine_calls
    assert not beliefs.simulator.answered_keys()  # everything went back to the Arrow tables
    # While a chunk is committed, the simulator holds at most the answers about its 2 instances.
    truths = {tuple(t) for t in beliefs.batch.truths.tolist()}
    stored = loaded.table("engine_cache")
    per_truth = stored.groupby(["x_hole", "c"]).size()
    assert {theta for theta, _ in held} <= truths
    assert max(n for _, n in held) <= 2 * per_truth.max() + whole_sim.engine_calls["peg_depth"]
    assert max(n for _, n in held) < len(stored)
    # The engine's answers of the pass's 4 chunks are one table after it, in the order they came.
    assert len(beliefs.answers._parts) == 2 and beliefs.answers._parts[1][0].num_rows == whole_sim.engine_calls["peg_depth"]
    # A second pass takes the engine's answers from where the first left them: no new engine call.
    calls = dict(beliefs.simulator.engine_calls)
    beliefs.commit([{"thresholds": config.belief.nu, "margin": None}], **request)
    assert beliefs.simulator.engine_calls == calls

    chunked_run = replay_run(runs["cal"], tmp_path / "chunked", overrides, chunk_instances=2)
    whole_run = replay_run(runs["cal"], tmp_path / "whole", overrides, chunk_instances=None)
    pd.testing.assert_frame_equal(load_run(chunked_run).table("engine_cache"), load_run(whole_run).table("engine_cache"),
                                  check_exact=True)
    assert len(load_run(whole_run).table("engine_cache")) == len(stored) + whole_sim.engine_calls["peg_depth"]


def replace_config(loaded, overrides):
    from probecommit.runner.replay import replay_config

    return replay_config(loaded.config, overrides)


def test_a_chunk_that_raises_leaves_no_stored_answer_in_the_simulator(runs):
    loaded = load_run(runs["cal"])
    beliefs = RunBeliefs.of(loaded, chunk_instances=2)
    calls = []

    def failing(table):
        calls.append(len(table))
        if len(calls) == 2:
            raise RuntimeError("a reducer failed")
        return len(table)

    with pytest.raises(RuntimeError, match="a reducer failed"):
        beliefs.commit([{"thresholds": 0.8, "margin": None}], executors=build_executors(["probe_robust"], beliefs.model),
                       reduce=[failing])
    assert len(calls) == 2 and not beliefs.simulator.answered_keys()
    # ... and the run commits again as if nothing had happened.
    [parts] = beliefs.commit([{"thresholds": 0.8, "margin": None}], executors=build_executors(["probe_robust"], beliefs.model),
                             reduce=[len])
    assert sum(parts) == sum(len(t) for t in [replay_episodes(loaded, chunk_instances=None)[0].query(
        "method == 'probe_robust'")])


def test_a_table_read_with_rows_and_columns_named_equals_those_of_the_whole_table(runs):
    """``LoadedRun.table(where=..., columns=...)`` reads only those rows and columns, from disk or held."""
    loaded = load_run(runs["test"])
    whole = loaded.table("episodes")
    expected = whole.loc[whole["method"] == "blind_robust", ["instance_id", "k", "realized"]].reset_index(drop=True)
    read = loaded.table("episodes", where=("method", ["blind_robust"]), columns=["instance_id", "k", "realized"])
    assert list(read.columns) == ["instance_id", "k", "realized"] and len(read) > 0
    pd.testing.assert_frame_equal(read.reset_index(drop=True), expected)
    loaded.episodes  # now held
    pd.testing.assert_frame_equal(loaded.table("episodes", where=("method", ["blind_robust"]),
                                               columns=["instance_id", "k", "realized"]).reset_index(drop=True), expected)


@pytest.mark.parametrize("every_repeat", [False, True])
def test_replay_run_writes_chunk_by_chunk_the_table_the_whole_run_gives(tmp_path, monkeypatch, every_repeat):
    """A replay run's episodes, written a chunk at a time with the failed rollouts placed among
    them (one instance failed in some repeats, or in every repeat so that it is in no chunk),
    read back as the whole replayed table put in canonical order."""
    from probecommit.runner.replay import replay_run
    from probecommit.runner.study import run_study
    from probecommit.store.rundir import atomic_write_parquet, canonical_tables
    from probecommit.store.schema import EPISODE_COLUMNS
    from tests.runner.faults import inject, pick_faults

    cfg = small_config(name="faulty", instances={"count": 7}, repeats=3,
                       methods=["blind_bayes", "blind_robust", "probe_robust"])
    faults = pick_faults(run_study(cfg, tmp_path / "clean").run_dir)["faults"]
    inject(monkeypatch, **{**faults, "nan_u": None} if every_repeat else faults)
    source = run_study(cfg, tmp_path / "faulty").run_dir
    loaded = load_run(source)
    overrides = {"model": {"boundary": "corrected"}}
    whole, _ = replay_episodes(loaded, overrides, chunk_instances=None)
    assert (whole["method"] == "rollout").sum() == (3 if every_repeat else 2)
    merged = canonical_tables({"instances": loaded.instances, "episodes": whole})["episodes"]
    atomic_write_parquet(tmp_path / "expected.parquet", merged, EPISODE_COLUMNS)
    expected = pd.read_parquet(tmp_path / "expected.parquet")
    for chunk in (1, 3, None):
        out = replay_run(source, tmp_path / f"replay-{chunk}", overrides, chunk_instances=chunk)
        pd.testing.assert_frame_equal(load_run(out).episodes, expected, check_exact=True)
        pd.testing.assert_frame_equal(load_run(out).probes, loaded.probes, check_exact=True)
        assert not list(out.glob("**/*.tmp"))
