"""Cluster bootstrap, paired differences, the sign-flip test and rank AUC."""

import itertools
import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import mannwhitneyu

from probecommit.audit.stats import (
    _weighted_auc,
    bootstrap_ratio,
    cluster_bootstrap_auc,
    cluster_bootstrap_mean,
    pair_episodes,
    paired_bootstrap,
    percentile_interval,
    rank_auc,
    resample_counts,
    sign_flip_test,
)


def test_resample_counts_shape_sums_and_seed():
    w = resample_counts(7, 50, seed=3)
    assert w.shape == (50, 7) and (w.sum(axis=1) == 7).all() and (w >= 0).all()
    np.testing.assert_array_equal(w, resample_counts(7, 50, seed=3))
    assert not np.array_equal(w, resample_counts(7, 50, seed=4))


def test_bootstrap_ratio_on_float_counts_equals_the_integer_counts_product():
    """Counts are held as float64 so ``counts @ x`` makes no float copy; the products are those of
    integer counts (which the product casts to the same float64 values), bit for bit."""
    w = resample_counts(600, 2000, seed=9)
    assert w.dtype == np.float64 and np.array_equal(w, np.round(w))
    rng = np.random.default_rng(2)
    num, den = rng.random(600), rng.integers(1, 5, 600).astype(float)
    integer = w.astype(np.int64)
    np.testing.assert_array_equal(w @ num, integer @ num)
    iv = bootstrap_ratio(num, den, resamples=2000, seed=9)
    lo, hi = percentile_interval((integer @ num) / (integer @ den))
    assert (iv.lo, iv.hi) == (lo, hi)


def test_ratio_estimator_hand_example():
    # Clusters with sums [1, 2] over counts [2, 2]: mean 0.75; with counts fixed the
    # resample [0, 0] gives 0.5 and [1, 1] gives 1.0.
    counts = np.array([[2, 0], [0, 2], [1, 1]])
    iv = bootstrap_ratio(np.array([1.0, 2.0]), np.array([2.0, 2.0]), counts=counts, level=0.5)
    assert iv.estimate == pytest.approx(0.75)
    assert (iv.lo, iv.hi) == pytest.approx((0.625, 0.875))  # percentiles 25/75 of {0.5, 1.0, 0.75}


def test_cluster_bootstrap_interval_covers_known_mean_at_nominal_rate():
    """Clustered data (strong instance effect): the 95% interval covers the true mean ~95%."""
    rng = np.random.default_rng(0)
    n_sim, m, r, mu = 300, 40, 4, 0.3
    hits = 0
    clusters = np.repeat(np.arange(m), r)
    for s in range(n_sim):
        effect = rng.normal(0, 1.0, m)
        values = mu + np.repeat(effect, r) + rng.normal(0, 0.5, m * r)
        iv = cluster_bootstrap_mean(values, clusters, resamples=400, seed=s)
        hits += iv.lo <= mu <= iv.hi
    rate = hits / n_sim
    # Percentile bootstrap with 40 clusters slightly under-covers; binomial sd ~0.013.
    assert 0.89 <= rate <= 0.99, rate


def test_ignoring_clusters_would_undercover():
    """The same data treated as independent episodes gives a visibly narrower interval."""
    rng = np.random.default_rng(1)
    m, r = 40, 4
    values = np.repeat(rng.normal(0, 1.0, m), r) + rng.normal(0, 0.2, m * r)
    clustered = cluster_bootstrap_mean(values, np.repeat(np.arange(m), r), resamples=500)
    naive = cluster_bootstrap_mean(values, np.arange(m * r), resamples=500)
    assert (clustered.hi - clustered.lo) > 1.5 * (naive.hi - naive.lo)


def test_rank_auc_matches_mann_whitney_and_brute_force_with_ties():
    rng = np.random.default_rng(2)
    s = rng.integers(0, 5, 60).astype(float)  # many ties
    y = rng.random(60) < 0.4
    pos, neg = s[y], s[~y]
    brute = np.mean([(p > q) + 0.5 * (p == q) for p, q in itertools.product(pos, neg)])
    u = mannwhitneyu(pos, neg).statistic / (len(pos) * len(neg))
    assert rank_auc(s, y) == pytest.approx(brute) == pytest.approx(u)
    assert np.isnan(rank_auc(s, np.zeros(60, bool)))


def test_weighted_auc_equals_auc_of_duplicated_sample():
    rng = np.random.default_rng(3)
    s, y = rng.normal(size=20), rng.random(20) < 0.5
    w = rng.integers(0, 4, 20)
    dup = np.repeat(np.arange(20), w)
    assert _weighted_auc(s, y, w[None, :].astype(float))[0] == pytest.approx(rank_auc(s[dup], y[dup]))


def test_cluster_bootstrap_auc_interval_contains_estimate():
    rng = np.random.default_rng(4)
    clusters = np.repeat(np.arange(30), 4)
    y = np.repeat(rng.random(30) < 0.3, 4)
    s = y + rng.normal(0, 1.0, 120)
    iv = cluster_bootstrap_auc(s, y, clusters, resamples=300)
    assert iv.estimate == pytest.approx(rank_auc(s, y))
    assert iv.lo <= iv.estimate <= iv.hi and iv.n_clusters == 30


def test_sign_flip_exact_small_examples():
    # Three improvements and three ties (the paper's grasp case): p cannot fall below 0.25.
    assert sign_flip_test([0.4, 0.9, 0.36, 0, 0, 0]) == pytest.approx(0.25)
    assert sign_flip_test([1.0, 2.0, 3.0]) == pytest.approx(2 / 8)
    assert sign_flip_test([1.0, -1.0]) == pytest.approx(1.0)
    assert sign_flip_test([1.0, 1.0, -0.5]) == pytest.approx(4 / 8)  # |+-1+-1+-0.5| >= 1.5 in 4 of 8
    assert sign_flip_test([0.0, 0.0]) == 1.0


def test_sign_flip_monte_carlo_agrees_with_exact():
    d = np.random.default_rng(5).normal(0.3, 1.0, 18)
    exact = sign_flip_test(d, max_exact=20)
    mc = sign_flip_test(d, max_exact=5, resamples=200_000, seed=1)
    assert abs(exact - mc) < 0.01


def _arm(values, instances=("a", "a", "b", "b", "c", "c")):
    return pd.DataFrame({"instance_id": list(instances), "repeat": [0, 1] * (len(instances) // 2),
                         "k": 5, "realized": values})


def test_paired_bootstrap_hand_example():
    base = _arm([1, 0, 0, 0, 1, 1])
    treat = _arm([1, 1, 0, 1, 1, 1])
    res = paired_bootstrap(base, treat, resamples=500)
    assert res.baseline_mean == pytest.approx(0.5) and res.treatment_mean == pytest.approx(5 / 6)
    assert res.difference.estimate == pytest.approx(2 / 6)
    assert res.n_pairs == 6 and res.n_clusters == 3
    # Cluster mean differences a 0.5, b 0.5, c 0: |+-0.5 +-0.5| >= 1 in 2 of 4 patterns.
    assert res.p_sign_flip == pytest.approx(0.5)
    # Resampling whole clusters: the difference can only be 0, 1/6, ..., up to 0.5.
    assert 0.0 <= res.difference.lo <= res.difference.estimate <= res.difference.hi <= 0.5
    assert res.difference.lo <= res.difference.estimate <= res.difference.hi


def test_pairing_refuses_different_episodes_and_duplicates():
    base = _arm([1, 0, 0, 0, 1, 1])
    other = _arm([1, 0, 0, 0, 1, 1], instances=("a", "a", "b", "b", "d", "d"))
    with pytest.raises(ValueError, match="identical episodes: 2 baseline-only and 2 treatment-only"):
        pair_episodes(base, other)
    assert len(pair_episodes(base, other, strict=False)) == 4
    with pytest.raises(ValueError, match="duplicate episodes"):
        pair_episodes(pd.concat([base, base]), base)


def test_sign_flip_monte_carlo_in_blocks_equals_one_draw(monkeypatch):
    """The signs are drawn in row blocks to bound memory; the p-value is that of one draw."""
    import probecommit.audit.stats as stats

    d = np.random.default_rng(3).normal(0.1, 1.0, 37)
    resamples = 5001
    signs = np.random.default_rng(8).choice((-1.0, 1.0), size=(resamples, d.size))
    tol = 1e-12 * max(1.0, np.abs(d).sum())
    one_draw = (1 + int(np.count_nonzero(np.abs(signs @ d) >= abs(d.sum()) - tol))) / (1 + resamples)
    for block in (37, 37 * 7, 1000, 1 << 21):  # 1, 7, 27 rows, all rows
        monkeypatch.setattr(stats, "SIGN_BLOCK_ELEMENTS", block)
        assert sign_flip_test(d, max_exact=5, resamples=resamples, seed=8) == one_draw


def test_resample_counts_and_auc_in_blocks_equal_one_draw(monkeypatch):
    """Counts and AUC weights are built a block of resamples at a time to bound memory; the
    numbers are those of one [B, M] draw and one [B, E] weight matrix."""
    import probecommit.audit.stats as stats

    n_clusters, resamples = 13, 101
    draws = np.random.default_rng(5).integers(0, n_clusters, size=(resamples, n_clusters))
    one_draw = np.stack([np.bincount(row, minlength=n_clusters) for row in draws])
    rng = np.random.default_rng(6)
    clusters = np.repeat(np.arange(n_clusters), 3)
    y = rng.random(clusters.size) < 0.4
    s = np.round(y + rng.normal(0, 1.0, clusters.size), 1)  # rounded: tied scores too
    weights = one_draw[:, clusters].astype(float)
    auc_draws = _weighted_auc(s, y, weights)
    expected = stats.percentile_interval(auc_draws)
    for block in (1, n_clusters * 7, 40, 1 << 20):  # one row, 7 rows, a block not a multiple of M, all rows
        monkeypatch.setattr(stats, "BOOTSTRAP_BLOCK_ELEMENTS", block)
        np.testing.assert_array_equal(resample_counts(n_clusters, resamples, seed=5), one_draw)
        iv = cluster_bootstrap_auc(s, y, clusters, resamples=resamples, seed=5)
        assert (iv.lo, iv.hi) == expected


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.one_of(st.floats(-50, 50), st.just(math.inf), st.just(-math.inf)), st.booleans(),
                          st.integers(0, 5)), min_size=2, max_size=30))
def test_an_infinite_score_ranks_beyond_every_finite_one(rows):
    """The AUC reads +-inf as the extreme ranks (a surprise no particle predicted is the most surprising), exactly
    as if each were replaced by a finite value beyond every finite score; only NaN is left out."""
    scores = np.array([r[0] for r in rows])
    labels = np.array([r[1] for r in rows])
    clusters = np.array([r[2] for r in rows])
    finite = np.where(np.isposinf(scores), 1e6, np.where(np.isneginf(scores), -1e6, scores))
    a = cluster_bootstrap_auc(scores, labels, clusters, resamples=50, seed=3)
    b = cluster_bootstrap_auc(finite, labels, clusters, resamples=50, seed=3)
    assert np.array_equal([a.estimate, a.lo, a.hi], [b.estimate, b.lo, b.hi], equal_nan=True)
    with_nan = cluster_bootstrap_auc(np.r_[scores, np.nan], np.r_[labels, True], np.r_[clusters, 9],
                                     resamples=50, seed=3)
    assert with_nan.estimate == a.estimate or (np.isnan(with_nan.estimate) and np.isnan(a.estimate))


def test_sign_flip_monte_carlo_signs_are_rng_choice_signs():
    # The Monte Carlo signs are drawn as integers and mapped to -1/+1: the same matrix as
    # rng.choice((-1.0, 1.0)) of the same generator, so the p-value of a seed is unchanged.
    for shape in ((7, 5), (3, 1), (1, 11)):
        a = np.random.default_rng(3).choice((-1.0, 1.0), size=shape)
        b = np.random.default_rng(3).integers(0, 2, size=shape).astype(float) * 2.0 - 1.0
        assert np.array_equal(a, b)
    d = np.random.default_rng(6).normal(0.1, 1.0, 40)
    rng = np.random.default_rng(2)
    signs = rng.choice((-1.0, 1.0), size=(5000, d.size))
    tol = 1e-12 * max(1.0, np.abs(d).sum())
    expected = (1 + int(np.count_nonzero(np.abs(signs @ d) >= abs(d.sum()) - tol))) / (1 + 5000)
    assert sign_flip_test(d, max_exact=5, resamples=5000, seed=2) == expected
