"""The one-visit margin search equals the margin-by-margin one bit for bit (issue 42, target 3)."""

import json

import numpy as np
import pandas as pd
import pytest

from probecommit.audit.margin import GAMMA_GRID, margin_candidates
from probecommit.core.executors import interval_success_counts_numpy
from probecommit.runner import kernels, margin_search
from probecommit.runner.calibration import MARGIN_COLUMNS, _margin_rows, calibrate, gates
from probecommit.runner.inference import commit
from probecommit.runner.replay import RunBeliefs, load_run
from tests.conftest import small_config

needs_kernels = pytest.mark.skipif(not kernels.HAVE_KERNELS, reason="no compiled kernels in this process")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    from probecommit.runner.study import run_study

    root = tmp_path_factory.mktemp("margin_runs")
    out = {}
    for split, seed in (("cal", 5), ("test", 6)):
        cfg = small_config(name=split, instances={"split": split, "count": 7, "seed": seed}, repeats=3,
                           methods=["blind_robust", "probe_robust"])
        out[split] = run_study(cfg, root / split).run_dir
    return out


@needs_kernels
@pytest.mark.parametrize("seed", range(4))
def test_every_margin_counted_in_one_visit_equals_each_count(seed):
    """Random intervals with ends on grid points, NaN and infinite parts, negative and zero widths."""
    rng = np.random.default_rng(seed)
    actions = np.round(np.arange(-10.0, 10.0 + 1e-9, 0.5), 10)
    n_e, n_s = 9, 200
    centre = rng.choice(np.r_[actions, rng.uniform(-12, 12, 40)], size=(n_e, n_s))
    half = rng.choice(np.r_[0.5, 1.0, 2.5, rng.uniform(0.0, 4.0, 40)], size=(n_e, n_s))
    for value, share in ((np.nan, 0.02), (np.inf, 0.02), (-np.inf, 0.01), (0.0, 0.02), (-1.0, 0.02)):
        half[rng.random((n_e, n_s)) < share] = value
        centre[rng.random((n_e, n_s)) < share / 2] = value
    mask = rng.random((n_e, n_s)) < 0.8
    margins = np.array(margin_candidates(np.r_[GAMMA_GRID, 1.5, 0.25]))
    counts, kept = kernels.margin_success_counts(centre, half, mask, margins, actions)  # one block
    np.testing.assert_array_equal(kept, mask.sum(axis=1))
    for m, gamma in enumerate(margins):
        width = half * gamma
        with np.errstate(invalid="ignore"):  # inf - inf: a NaN end, as the kernel must read it
            expected = interval_success_counts_numpy(centre - width, centre + width, mask, actions)
        np.testing.assert_array_equal(counts[m], expected, err_msg=f"margin {gamma}")


def test_margins_must_decrease():
    if not kernels.HAVE_KERNELS:
        assert kernels.margin_success_counts(np.zeros((1, 1)), np.ones((1, 1)), np.ones((1, 1), bool),
                                             np.array([0.5, 1.0]), np.arange(3.0)) is None
        return
    with pytest.raises(ValueError, match="decreasing"):
        kernels.margin_success_counts(np.zeros((1, 1)), np.ones((1, 1)), np.ones((1, 1), bool),
                                      np.array([0.5, 1.0]), np.arange(3.0))


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("thresholds", [0.8, {1: 1.2, 3: 1.4, 5: 0.9}])
def test_sweep_equals_each_margins_commit(runs, thresholds, compiled, monkeypatch):
    """Per margin, the sweep's rows are the margin rule's rows of that margin's commit (grown sets included)."""
    if not compiled:  # the margin-by-margin fallback (no kernels, or a model without interval parts)
        monkeypatch.setattr(margin_search, "margin_choices", lambda *args: None)
    beliefs = RunBeliefs.of(load_run(runs["cal"]), chunk_instances=None)
    trace = beliefs.trace(beliefs.chunks[0])
    margins = margin_candidates(GAMMA_GRID)
    rule = [1, 3, 5]
    swept = margin_search.sweep_margins(trace, beliefs.model, beliefs.simulator, thresholds=thresholds,
                                        margins=margins, rule_budgets=rule, cache={})
    assert len(swept) == 2 * len(margins)
    for m, gamma in enumerate(margins):
        table = commit(trace, beliefs.model, beliefs.simulator, thresholds=thresholds, margin=gamma,
                       columns=MARGIN_COLUMNS)
        predicted, realized = _margin_rows(table, rule)
        np.testing.assert_array_equal(swept[2 * m], predicted)
        np.testing.assert_array_equal(swept[2 * m + 1], realized)


@pytest.mark.parametrize("chunk", [None, 2])
def test_calibrate_and_gates_equal_the_reference_path(runs, chunk):
    """The one-pass search gives the margin-by-margin reference's results, its search table included."""
    fast = calibrate(runs["cal"], runs["test"], resamples=100, chunk_instances=chunk)
    slow = calibrate(runs["cal"], runs["test"], resamples=100, chunk_instances=chunk, reuse=False)
    assert json.dumps(fast.to_dict(), sort_keys=True, default=str) == json.dumps(slow.to_dict(), sort_keys=True, default=str)
    pd.testing.assert_frame_equal(fast.margin.search, slow.margin.search, check_exact=True)
    assert len(fast.margin.search) > 1  # the scan went past the first margin
    g_fast = gates(runs["cal"], runs["test"], resamples=100, chunk_instances=chunk)
    g_slow = gates(runs["cal"], runs["test"], resamples=100, chunk_instances=chunk, reuse=False)
    pd.testing.assert_frame_equal(g_fast.summary, g_slow.summary, check_exact=True)
    pd.testing.assert_frame_equal(g_fast.curves, g_slow.curves, check_exact=True)
    assert g_fast.info["gamma"] == g_slow.info["gamma"]


@needs_kernels
@pytest.mark.parametrize("seed", range(3))
def test_compiled_choice_equals_select_action(seed):
    """Ties within the tolerance, equal tie costs, NaN and infinite costs, rows with nothing retained."""
    from probecommit.core.executors import SCORE_TIE_TOLERANCE, select_action

    rng = np.random.default_rng(seed)
    n_m, n_e, n_a = 5, 40, 12
    kept = rng.integers(0, 6, n_e)
    successes = np.minimum(rng.integers(0, 6, (n_m, n_e, n_a)), kept[None, :, None])
    tie = rng.choice([0.0, 0.5, 1.0, 1.5], size=(n_e, n_a))
    tie[rng.random((n_e, n_a)) < 0.05] = np.nan
    tie[rng.random((n_e, n_a)) < 0.05] = np.inf
    tie[:3] = np.inf  # rows whose every cost is infinite
    score = np.empty((n_m, n_e))
    index = kernels._choose_by_counts(np.ascontiguousarray(successes), kept, tie, SCORE_TIE_TOLERANCE, score)
    for m in range(n_m):
        fractions = (kept[:, None] - successes[m]) / np.maximum(kept, 1)[:, None]
        expected = select_action(fractions, tie)
        np.testing.assert_array_equal(index[m], expected)
        np.testing.assert_array_equal(score[m], np.take_along_axis(fractions, expected[:, None], axis=1)[:, 0])


def test_beliefs_computed_a_chunk_ahead_give_the_same_results(runs, monkeypatch):
    """The next chunk's trace built in a second thread while one is committed: the same tables."""
    monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", "1")
    one = calibrate(runs["cal"], runs["test"], resamples=100, chunk_instances=2)
    monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", "2")
    beliefs = RunBeliefs.of(load_run(runs["cal"]), chunk_instances=2)
    with beliefs._traces_ahead() as upcoming:
        assert upcoming(beliefs.chunks[0]) is not None  # the second thread is used
    ahead = calibrate(runs["cal"], runs["test"], resamples=100, chunk_instances=2)
    assert json.dumps(one.to_dict(), sort_keys=True, default=str) == json.dumps(ahead.to_dict(), sort_keys=True, default=str)
    pd.testing.assert_frame_equal(one.audit_calibrated, ahead.audit_calibrated, check_exact=True)
