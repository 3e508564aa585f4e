"""Conformal thresholds: the rank rule, instance and simultaneous scores, and the guarantee."""

import math

import numpy as np
import pandas as pd
import pytest

from probecommit.audit.conformal import (
    budget_thresholds,
    conformal_quantile,
    conformal_rank,
    fixed_budget_thresholds,
    instance_scores,
    score_coverage,
    simultaneous_scores,
    simultaneous_threshold,
    worst_budget_scores,
)


def test_conformal_rank_and_infinite_threshold():
    assert conformal_rank(96, 0.2) == 78  # ceil(0.8 * 97) = ceil(77.6)
    assert conformal_rank(4, 0.2) == 4  # 0.8 * 5 = 4 exactly (no float overshoot to 5)
    assert conformal_rank(9, 0.1) == 9  # 0.9 * 10 = 9
    assert conformal_rank(3, 0.2) == 4  # = M + 1
    assert conformal_quantile([0.3, 0.1, 0.2], 0.2) == math.inf
    assert conformal_quantile([0.4, 0.1, 0.3, 0.2], 0.2) == 0.4
    assert conformal_quantile(np.arange(1, 97) / 100, 0.2) == pytest.approx(0.78)
    with pytest.raises(ValueError):
        conformal_quantile([0.1, np.nan], 0.2)
    with pytest.raises(ValueError):
        conformal_rank(10, 1.0)


def _table():
    # 3 instances x 2 repeats x budgets {1, 2}; score_s chosen by hand.
    rows = []
    s = {("a", 0, 1): 0.2, ("a", 1, 1): 0.5, ("a", 0, 2): 0.3, ("a", 1, 2): 0.1,
         ("b", 0, 1): 0.9, ("b", 1, 1): 0.4, ("b", 0, 2): 1.2, ("b", 1, 2): 0.6,
         ("c", 0, 1): 0.1, ("c", 1, 1): 0.1, ("c", 0, 2): 0.7, ("c", 1, 2): 0.8}
    for (i, r, k), v in s.items():
        rows.append({"instance_id": i, "repeat": r, "k": k, "score_s": v, "status": "ok"})
    return pd.DataFrame(rows)


def test_instance_and_simultaneous_scores_by_hand():
    t = _table()
    assert instance_scores(t, 1).to_dict() == {"a": 0.5, "b": 0.9, "c": 0.1}
    assert instance_scores(t, 2).to_dict() == {"a": 0.3, "b": 1.2, "c": 0.8}
    assert simultaneous_scores(t, [1, 2]).to_dict() == {"a": 0.5, "b": 1.2, "c": 0.8}
    # M = 3 at alpha = 0.5: q = ceil(0.5 * 4) = 2 -> the 2nd smallest.
    assert fixed_budget_thresholds(t, 0.5) == {1: 0.5, 2: 0.8}
    assert simultaneous_threshold(t, [1, 2], 0.5) == 0.8
    cov = score_coverage(t, {1: 0.5, 2: 0.8}).set_index("k")
    assert cov.loc[1, "cluster_coverage"] == pytest.approx(2 / 3)  # a and c
    assert cov.loc[2, "episode_coverage"] == pytest.approx(5 / 6)


def test_scores_of_instance_parts_give_the_whole_tables_thresholds():
    # Calibration keeps each chunk's worst-repeat scores (whole instances per chunk) and joins them.
    t = _table()
    parts = pd.concat([instance_scores(t.loc[t.instance_id.isin(ids)]) for ids in (["b"], ["c", "a"])]).sort_index()
    pd.testing.assert_frame_equal(parts, instance_scores(t))
    assert budget_thresholds(parts, 0.5) == fixed_budget_thresholds(t, 0.5) == {1: 0.5, 2: 0.8}
    pd.testing.assert_series_equal(worst_budget_scores(parts, [1, 2]), simultaneous_scores(t, [1, 2]))
    with pytest.raises(ValueError, match="lacks episodes"):
        worst_budget_scores(parts.drop(columns=2).assign(**{"2": np.nan}).rename(columns={"2": 2}), [1, 2])


def test_failed_rows_and_mixed_methods():
    t = _table()
    t.loc[0, "status"] = "failed"  # a's repeat 0 at k = 1 leaves the scores
    assert instance_scores(t, 1)["a"] == 0.5
    t2 = pd.concat([_table().assign(method="probe_robust"), _table().assign(method="blind_robust")])
    with pytest.raises(ValueError, match="one method"):
        instance_scores(t2, 1)


def _cluster_scores(rng, n_sets, m, r=4, kk=1, ties=False):
    """Exchangeable clusters: a per-instance effect shared by its repeats (and budgets)."""
    effect = rng.normal(0, 1, (n_sets, m, 1, 1))
    s = np.exp(0.5 * effect + 0.3 * rng.normal(size=(n_sets, m, r, kk)))
    if ties:
        s = np.round(s, 1)  # heavy ties
    return s.max(axis=(2, 3))  # worst repeat (and worst budget)


@pytest.mark.parametrize("ties,kk", [(False, 1), (True, 1), (False, 3)])
def test_conformal_guarantee_over_random_splits(ties, kk):
    """Marginal cluster coverage >= 1 - alpha, and within 1/(M+1) + slack above it."""
    rng = np.random.default_rng(123 + kk + 10 * ties)
    n_splits, m_cal, m_test, alpha = 2000, 24, 24, 0.2
    pool = _cluster_scores(rng, n_splits, m_cal + m_test, kk=kk, ties=ties)
    # A random calibration/test split of each pool.
    perm = np.argsort(rng.random(pool.shape), axis=1)
    pool = np.take_along_axis(pool, perm, axis=1)
    cal, test = pool[:, :m_cal], pool[:, m_cal:]
    t = np.array([conformal_quantile(c, alpha) for c in cal])
    coverage = (test <= t[:, None]).mean()
    se = 0.1 / math.sqrt(n_splits)  # per-split coverage sd is about 0.1
    assert coverage >= 1 - alpha - 4 * se
    assert coverage <= 1 - alpha + 1 / (m_cal + 1) + 4 * se
    if not ties:
        # Continuous scores: the expected coverage is exactly q / (M + 1).
        q = conformal_rank(m_cal, alpha)
        assert coverage == pytest.approx(q / (m_cal + 1), abs=4 * se)


def test_off_by_one_rank_would_be_detected():
    """The test above has the power to see a wrong rank (q + 1 or q - 1)."""
    rng = np.random.default_rng(5)
    pool = _cluster_scores(rng, 2000, 48)
    cal, test = pool[:, :24], pool[:, 24:]
    srt = np.sort(cal, axis=1)
    q = conformal_rank(24, 0.2)
    slack = 4 * 0.1 / math.sqrt(2000)
    for qq, expect in ((q - 1, False), (q, True), (q + 2, False)):
        cov = (test <= srt[:, qq - 1][:, None]).mean()
        assert bool(0.8 - slack <= cov <= 0.8 + 1 / 25 + slack) == expect, (qq, cov)
