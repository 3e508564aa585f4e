"""A chunk's commit split by budget over two threads (``runner.commit_threads``) is ``commit``'s table to the
last bit, column by column and dtype by dtype, and asks each engine query once."""

import threading

import numpy as np
import pandas as pd
import pytest

from probecommit.runner.build import build_executors
from probecommit.runner.commit_threads import LockedSimulator, commit_in_threads, in_threads
from probecommit.runner.inference import commit
from probecommit.runner.replay import RunBeliefs
from probecommit.tasks.base import ENGINE_THREADS_ENV
from tests.conftest import cal_test_runs


@pytest.fixture(scope="module")
def beliefs(tmp_path_factory):
    runs = cal_test_runs(tmp_path_factory.mktemp("commit_threads"), (5, 6), count=5, repeats=3)
    run = RunBeliefs.of(runs["cal"], chunk_instances=None)
    return run, run.trace(run.chunks[0])


@pytest.fixture(autouse=True)
def two_threads(monkeypatch):
    monkeypatch.setenv(ENGINE_THREADS_ENV, "2")


@pytest.mark.parametrize("thresholds, margin, columns", [
    (0.8, None, None),  # every column (strings, flags, integers, the belief summary)
    ({1: 0.7, 3: 1.2, 4: 0.95, 5: 1.0}, 0.6, None),  # per-budget thresholds, grown sets, a margin
    ({2: 0.9, 4: 1.3}, None, ("instance_id", "k", "status", "predicted", "realized")),
])
def test_the_same_table_as_one_thread(beliefs, thresholds, margin, columns):
    run, trace = beliefs
    executors = build_executors(("probe_robust",), run.model)
    one = commit(trace, run.model, run.simulator, executors, thresholds, margin, {}, columns)
    two = commit_in_threads(trace, run.model, run.simulator, executors, thresholds, margin, {}, columns)
    assert list(two.columns) == list(one.columns)
    assert list(two.dtypes) == list(one.dtypes)
    pd.testing.assert_frame_equal(two, one, check_exact=True)
    assert len(one) == trace.batch.n_episodes * (len(thresholds) if isinstance(thresholds, dict) else 5)


def test_one_cpu_or_a_blind_executor_commits_in_this_thread(beliefs, monkeypatch):
    run, trace = beliefs
    monkeypatch.setenv(ENGINE_THREADS_ENV, "1")
    seen = []
    original = threading.Thread.start
    monkeypatch.setattr(threading.Thread, "start", lambda self: (seen.append(self.name), original(self))[1])
    executors = build_executors(("probe_robust",), run.model)
    one = commit(trace, run.model, run.simulator, executors, 0.8, None, {}, None)
    pd.testing.assert_frame_equal(commit_in_threads(trace, run.model, run.simulator, executors, 0.8), one,
                                  check_exact=True)
    assert "probecommit-commit" not in seen


def test_an_error_in_the_helper_thread_is_raised_here():
    def work(item):
        if item == 1:
            raise KeyError("in the helper")

    with pytest.raises(KeyError, match="in the helper"):
        in_threads(work, range(4))


def test_a_free_thread_takes_the_next_item(monkeypatch):
    """Items go to whichever thread is free, in order: while one thread runs a long item, the
    other runs every short one (a fixed share would leave half of them waiting behind it)."""
    monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", "2")
    ran: dict[int, str] = {}

    def work(item):
        ran[item] = threading.current_thread().name
        if item == 0:
            threading.Event().wait(0.5)

    in_threads(work, range(6))
    assert sorted(ran) == list(range(6))
    assert {ran[item] for item in range(1, 6)} == {ran[1]} != {ran[0]}


def test_the_locked_simulator_runs_one_engine_call_at_a_time():
    inside, most = [0], [0]

    class Engine:
        calls = 0

        def execute(self, *args):
            inside[0] += 1
            most[0] = max(most[0], inside[0])
            threading.Event().wait(0.002)
            inside[0] -= 1
            Engine.calls += 1
            return {"realized": 0.0}

    shared = LockedSimulator(Engine())
    in_threads(lambda item: [shared.execute(item) for _ in range(10)], range(2))
    assert most[0] == 1 and Engine.calls == 20
    assert shared.calls == 20  # every other attribute is the simulator's own


def test_rows_interleave_in_canonical_order():
    from probecommit.runner.commit_threads import _interleave

    a = {"k": np.array([1, 3, 1, 3]), "s": np.array(["a1", "a3", "b1", "b3"], dtype=object)}
    b = {"k": np.array([2, 2]), "s": np.array(["a2", "b2"])}
    out = _interleave([a, b], [[1, 3], [2]], [1, 2, 3], 2)
    assert out["k"].tolist() == [1, 2, 3, 1, 2, 3]
    assert out["s"].tolist() == ["a1", "a2", "a3", "b1", "b2", "b3"] and out["s"].dtype == object
