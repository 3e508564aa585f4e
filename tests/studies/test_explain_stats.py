"""Hand cases for the explain study's statistics (studies/explain/stats.py, generator.py)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from probecommit.studies.explain.generator import redraw_shares, share_beyond, stratified_metrics
from probecommit.studies.explain.stats import (
    capture_failure,
    equivalence_power,
    interval_se,
    percentile_of,
    pool_escape_ratio,
    standardized_mean,
)


def test_pool_escape_ratio_point_values():
    # 4 clusters x 2 trajectories; committed: clusters a, b; rejected: c, d.
    committed = np.array([1, 1, 1, 1, 0, 0, 0, 0], bool)
    escaped = np.array([1, 0, 0, 0, 1, 1, 0, 1], bool)
    clusters = ["a", "a", "b", "b", "c", "c", "d", "d"]
    out = pool_escape_ratio(committed, escaped, clusters, resamples=200, seed=1)
    assert out["committed_rate"][0] == pytest.approx(0.25)
    assert out["rejected_rate"][0] == pytest.approx(0.75)
    assert out["ratio"][0] == pytest.approx(1 / 3)
    for key in out:
        lo, hi = out[key][1], out[key][2]
        assert lo <= hi


def test_pool_escape_ratio_same_seed_same_interval():
    rng = np.random.default_rng(3)
    committed, escaped = rng.random(80) < 0.6, rng.random(80) < 0.2
    clusters = np.repeat(np.arange(20), 4)
    a = pool_escape_ratio(committed, escaped, clusters, resamples=300, seed=5)
    b = pool_escape_ratio(committed, escaped, clusters, resamples=300, seed=5)
    assert a == b


def test_standardized_mean_reweights_strata():
    values = np.array([0.0, 0.0, 1.0, 1.0, 1.0])
    strata = np.array(["in", "in", "in", "out", "out"])
    # stratum means: in = 1/3, out = 1; weights 0.7/0.3 -> 0.7/3 + 0.3
    assert standardized_mean(values, strata, {"in": 0.7, "out": 0.3}) == pytest.approx(0.7 / 3 + 0.3)
    assert math.isnan(standardized_mean(values, strata, {"in": 0.5, "missing": 0.5}))


def test_percentile_of_counts_ties_half():
    assert percentile_of(2.0, np.array([1.0, 2.0, 3.0, 4.0])) == pytest.approx(0.375)
    assert percentile_of(10.0, np.array([1.0, 2.0])) == 1.0


def test_equivalence_power_hand_cases():
    z = 1.959963984540054
    # margin = 2 z se: at difference 0 the interval fits iff |estimate| < z se: probability 0.95.
    assert equivalence_power(1.0, 0.0, 2 * z) == pytest.approx(0.95, abs=1e-9)
    # an interval wider than twice the margin can never fit
    assert equivalence_power(1.0, 0.0, 0.5 * z) == 0.0
    # margin 1.5 z se: fits iff |estimate| < z se / 2
    assert equivalence_power(1.0, 0.0, 1.5 * z) == pytest.approx(2 * 0.5 * (1 + math.erf(z / 2 / math.sqrt(2))) - 1)
    assert interval_se(-z, z) == pytest.approx(1.0)


def test_capture_failure_window():
    # w(c=1) = 1.7 mm; scale 0.5 -> 0.85 mm; failure iff |a - x| >= window
    a = np.array([0.0, 0.8, 0.9, 1.6, 1.8])
    x = np.zeros(5)
    c = np.ones(5)
    assert capture_failure(a, x, c, 1.0).tolist() == [0, 0, 0, 0, 1]
    assert capture_failure(a, x, c, 0.5).tolist() == [0, 0, 1, 1, 1]


def test_share_beyond_and_redraw_are_fractions():
    assert share_beyond(np.array([-8.0, -7.0, 0.0, 7.5]), 7.0) == 0.5
    shares = redraw_shares("B_test_random", 96, -10.0, 10.0, 7.0, range(400))
    assert shares.mean() == pytest.approx(0.3, abs=0.01)  # the generator's expected share
    assert shares.std(ddof=1) == pytest.approx(math.sqrt(0.3 * 0.7 / 96), rel=0.15)


def test_stratified_metrics_hand_table():
    rows = pd.DataFrame({
        "method": "probe_robust", "status": "ok", "k": 8,
        "z_true": [-9.0, 2.0, 3.0, 8.0],
        "escaped": [True, False, False, True], "covered": [False, True, True, False],
        "realized": [1.0, 0.0, 1.0, 1.0], "predicted": [0.0, 0.0, 0.5, 0.5],
    })
    out = stratified_metrics(rows, 8, 7.0, 0.3)
    assert out["share_beyond"] == 0.5
    assert out["escape.beyond"] == 1.0 and out["escape.inside"] == 0.0
    assert out["escape.standardized"] == pytest.approx(0.3)
    assert out["failure.inside"] == 0.5
    assert out["optimism.beyond"] == pytest.approx(0.75)


def test_conformal_quantile_draws_identity_resample_is_the_quantile():
    from probecommit.audit.conformal import conformal_quantile
    from probecommit.studies.explain.stats import conformal_quantile_draws

    values = np.array([0.3, 0.1, 0.9, 0.5, 0.7, 0.2, 0.8, 0.4, 0.6])
    counts = np.ones((1, values.size))
    assert conformal_quantile_draws(values, counts, 0.2)[0] == conformal_quantile(values, 0.2)
    # a resample that takes only the smallest value three times over... and the rest
    counts = np.zeros((1, values.size))
    counts[0, 1] = values.size  # every draw is 0.1
    assert conformal_quantile_draws(values, counts, 0.2)[0] == 0.1
    # too few instances: +inf, as the conformal rule says
    assert np.isinf(conformal_quantile_draws(values[:3], np.ones((2, 3)), 0.2)).all()


def test_margin_draws_picks_largest_gamma_reaching_realized():
    from probecommit.studies.explain.stats import margin_draws

    gammas = np.array([1.0, 0.8, 0.6])
    # two instances; predicted rises as gamma falls, realized flat at 1 per instance
    predicted = np.array([[0.5, 0.5], [0.9, 1.2], [1.5, 1.5]])
    realized = np.ones((3, 2))
    counts = np.array([[1.0, 1.0], [2.0, 0.0], [0.0, 2.0]])
    assert margin_draws(gammas, predicted, realized, counts).tolist() == [0.8, 0.6, 0.8]
