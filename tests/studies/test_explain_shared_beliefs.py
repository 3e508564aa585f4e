"""The explain target's speed machinery (issue 42): one belief trace per run gives every calibration, gate and
audit the same numbers as recomputing it per call; the cyclic pairs hold two runs; background steps hand on in order."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from probecommit.runner.calibration import calibrate, gates
from probecommit.studies.explain import draw_audit
from probecommit.studies.explain.shared_beliefs import SharedBeliefs, cyclic_pairs
from probecommit.studies.explain.timing import StepClock
from tests.conftest import cal_test_runs


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    return cal_test_runs(tmp_path_factory.mktemp("shared"), (3, 4), count=8, repeats=3)


def _same(a, b) -> None:
    """Two results equal to the bit, NaN included (their reprs list every field)."""
    assert repr(a) == repr(b)


@pytest.mark.parametrize("kept", [None, [5, 1, 3]])
def test_calibrate_on_shared_beliefs_equals_recomputed(runs, kept):
    """Whether the shared trace holds every budget and the prior or only the budgets read (``budgets=``)."""
    shared = SharedBeliefs(kept)
    budgets = [1, 3, 5]
    fresh = calibrate(runs["cal"], runs["test"], alpha=0.2, budgets=budgets, resamples=20, seed=1, chunk_instances=3)
    for _ in range(2):  # the shared trace survives a calibration's release of its own view
        got = calibrate(shared.run(runs["cal"], budgets), shared.run(runs["test"], budgets), alpha=0.2, budgets=budgets,
                        resamples=20, seed=1, chunk_instances=3)
        _same(got.to_dict(), fresh.to_dict())
        _same(got.table3, fresh.table3)


def test_gates_and_audit_on_shared_beliefs_equal_recomputed(runs):
    shared = SharedBeliefs()
    got, fresh = (gates(cal, test, alpha=0.2, resamples=10, seed=0)
                  for cal, test in ((shared.run(runs["cal"]), shared.run(runs["test"])), (runs["cal"], runs["test"])))
    _same(got.curves.to_dict("list"), fresh.curves.to_dict("list"))
    _same(got.summary.to_dict("list"), fresh.summary.to_dict("list"))
    thresholds = {1: 0.6, 3: 0.7, 5: 0.8}
    cells = [draw_audit.draw_cells(run, thresholds, 0.01, nominal=0.8, resamples=2, seed=0)
             for run in (runs["test"], shared.run(runs["test"], sorted(thresholds)))]
    _same(*cells)


def test_shared_refuses_a_budget_the_run_lacks(runs):
    with pytest.raises(ValueError, match=r"budget\(s\) \[7\]"):
        SharedBeliefs().run(runs["cal"], [1, 7])
    with pytest.raises(ValueError, match=r"budget\(s\) \[2\]"):  # not kept
        SharedBeliefs([1, 3]).run(runs["cal"], [1, 2])
    with pytest.raises(ValueError, match="the prior"):
        SharedBeliefs([1, 3]).run(runs["cal"])


class _Counting(SharedBeliefs):
    """Records which runs are held whenever a pair is evaluated."""

    def __init__(self) -> None:
        super().__init__()
        self.held: set[Path] = set()

    def touch(self, path: Path) -> None:
        self.held.add(path)

    def drop(self, path) -> None:
        self.held.discard(Path(path))


@pytest.mark.parametrize("n", [2, 3, 5])
def test_cyclic_pairs_order_and_memory(n):
    paths = [Path(f"run{i}") for i in range(n)]
    shared = _Counting()
    loads: list[Path] = []
    most = []

    def first(path):
        shared.touch(path)
        loads.append(path)
        return path.name

    def pair(cal, test):
        for path in (cal, test):
            if path not in shared.held:
                loads.append(path)
            shared.touch(path)
        most.append(len(shared.held))
        return (cal.name, test.name)

    firsts, pairs = cyclic_pairs(paths, pair, shared, first=first)
    assert firsts == [p.name for p in paths]
    assert pairs == [(paths[(i + 1) % n].name, paths[i].name) for i in range(n)]  # test i calibrated on i + 1
    assert max(most) <= 2 and not shared.held
    assert len(loads) == n + 1  # each run once; the first again for the last pair


def test_step_clock_logs_each_label_once(caplog):
    seen = []
    clock = StepClock(lambda *a: seen.append(a))
    with caplog.at_level(logging.INFO, logger="probecommit.studies.explain.timing"):
        for label in ("a", "a", "explain", "b"):
            clock(label, 0, 1)
        clock.close()
    assert [s[0] for s in clock.steps] == ["a", "b"]
    assert len(seen) == 4  # every call passed through
    assert [r.getMessage().split(":")[0] for r in caplog.records] == ["a", "b"]


def test_background_hands_results_on_in_submission_order():
    import operator

    from probecommit.studies.explain.background import Background

    got: list = []
    work = Background()
    try:
        work.submit(got.append, operator.mul, 6, 7)
        work.submit(got.append, operator.add, 1, 2)
        assert got == []  # nothing is handed on before finish
        work.finish()
    finally:
        work.close()
    assert got == [42, 3]


def test_background_raises_a_failure_and_runs_inline_on_one_cpu(monkeypatch):
    import operator

    from probecommit.studies.explain import background

    work = background.Background()
    try:
        work.submit(lambda _: None, operator.truediv, 1, 0)
        with pytest.raises(ZeroDivisionError):
            work.finish()
    finally:
        work.close()
    monkeypatch.setattr(background.os, "cpu_count", lambda: 1)
    got: list = []
    background.Background().submit(got.append, operator.add, 2, 2)
    assert got == [4]  # at once, in this process
