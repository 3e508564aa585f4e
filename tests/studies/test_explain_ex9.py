"""ex9's explain experiments (E80..E82): the summaries of the stored rows on hand cases, and the
claims' ``supports`` rules deciding on hand values (each one can fail)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex9_calibration as ex9
from probecommit.studies.paper_values import value


def test_tie_coverage_counts_ties_only_in_the_conformal_event():
    # M = 4 calibration scores, alpha = 0.2: q = ceil(0.8 * 5) = 4, the 4th smallest, 1.0
    cal = np.array([0.2, 0.5, 1.0, 1.0])
    test = np.array([0.1, 1.0, 1.0, 1.3])
    got = ex9.tie_coverage(cal, test, 0.2)
    assert got == {"level": 1.0, "le": 0.75, "lt": 0.25, "tied": 0.5}


def test_coverage_rows_use_the_insertion_studys_splits_and_worst_repeats():
    # Two repeats per instance at k = 5 (and a k = 1 row that must be ignored); worst repeat = the max
    ids = [f"i{j}" for j in range(6)]
    worst = dict(zip(ids, [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]))
    rows = []
    for i in ids:
        for rep, s in enumerate((worst[i] / 2, worst[i])):
            rows.append({"instance_id": i, "repeat": rep, "k": 5, "method": "probe_robust", "status": "ok",
                         "score_s": s})
        rows.append({"instance_id": i, "repeat": 0, "k": 1, "method": "probe_robust", "status": "ok", "score_s": 9.0})
    table = ex9.coverage_rows("pool", pd.DataFrame(rows), 0.2, 2, 9, 5)
    assert list(table["index"]) == [0, 1] and set(table["pool"]) == {"pool"}
    from probecommit.studies.explain.ex5_calibration import split_halves
    for r, (cal, test) in zip(table.to_dict("records"), split_halves(np.array(sorted(ids)), 2, 9)):
        expect = ex9.tie_coverage(np.array([worst[i] for i in cal]), np.array([worst[i] for i in test]), 0.2)
        assert {k: r[k] for k in expect} == expect


def _coverage(pool: str, le: list[float], tied: list[float]) -> pd.DataFrame:
    n = len(le)
    return pd.DataFrame({"part": "coverage", "pool": pool, "index": range(n), "alpha": 0.2, "half": 96,
                         "level": 0.8, "le": le, "lt": np.array(le) - np.array(tied), "tied": tied})


def test_coverage_keys_by_hand():
    rows = pd.concat([_coverage("a", [0.80, 0.82], [0.0, 0.02]), _coverage("b", [0.90, 0.86], [0.1, 0.0])],
                     ignore_index=True)
    keys = ex9.coverage_keys(rows)
    assert keys["pools"] == 2 and keys["splits"] == 4 and keys["calibration_clusters"] == 96
    assert keys["identity"] == pytest.approx(78 / 97)
    assert (keys["le.min"], keys["le.max"]) == pytest.approx((0.81, 0.88))
    assert (keys["lt.min"], keys["lt.max"]) == pytest.approx((0.80, 0.83))
    assert keys["tied.max"] == pytest.approx(0.05)
    assert keys["splits_with_ties"] == pytest.approx(0.5)


def test_cost_and_margin_keys_by_hand():
    cost = pd.DataFrame({"part": "cost", "pool": ["a", "a", "b", "b", "b"], "index": [0, 1, 0, 1, 2],
                         "difference": [0.0, 0.1, 0.2, 0.3, 0.4], "lo": [-0.1, 0.01, 0.0, -0.2, 0.1],
                         "hi": [0.1, 0.2, 0.3, -0.01, 0.5], "gamma": 0.6})
    keys = ex9.cost_keys(cost)
    assert keys["pools"] == 2 and keys["splits"] == 5
    assert (keys["estimate.p025"], keys["estimate.p975"]) == pytest.approx((0.01, 0.39))
    assert (keys["share_above_zero"], keys["share_below_zero"]) == pytest.approx((0.4, 0.2))
    margin = pd.DataFrame({"part": "margin", "index": [2, 3], "k": [2, 3], "gamma": 0.62, "threshold": 1.0,
                           "optimism": [-0.05, 0.01], "lo": [-0.1, -0.04], "hi": [0.0, 0.06]})
    keys = ex9.margin_keys(margin)
    assert keys == {"gamma": 0.62, "optimism.k2": -0.05, "optimism.k2.lo": -0.1, "optimism.k2.hi": 0.0,
                    "optimism.k3": 0.01, "optimism.k3.lo": -0.04, "optimism.k3.hi": 0.06}


def test_summary_survives_the_stored_parquet(tmp_path):
    rows = pd.concat([_coverage("a", [0.8, 0.82], [0.0, 0.02]),
                      pd.DataFrame({"part": "cost", "pool": "a", "index": [0, 1], "difference": [0.0, 0.1],
                                    "lo": [-0.1, 0.01], "hi": [0.1, 0.2], "gamma": 0.6})], ignore_index=True)
    rows.to_parquet(tmp_path / ex9.STORED)
    assert ex9.summary(pd.read_parquet(tmp_path / ex9.STORED)) == ex9.summary(rows)
    assert {k.split(".")[0] for k in ex9.summary(rows)} == {"coverage", "cost"}  # no margin rows: no margin keys


def test_pools_are_those_present(tmp_path):
    (tmp_path / "pool_draw_01_paper_schedule").mkdir()
    (tmp_path / "B_pool_cover_paper_schedule").mkdir()
    assert ex9.pools(tmp_path) == ["B_pool_cover_paper_schedule", "pool_draw_01_paper_schedule"]


def test_e80_needs_the_paper_inside_and_ties_to_carry_it():
    support = claims.EXPERIMENTS["E80"].supports
    p, ident = value("T14-resplits.heldout_cluster_coverage"), 78 / 97
    assert support({"lo": p - 0.01, "hi": p + 0.01, "id": ident})
    assert not support({"lo": p + 0.001, "hi": p + 0.05, "id": ident})  # the paper below the range
    assert not support({"lo": ident + 0.01, "hi": 1.0, "id": ident})  # inside, but the identity nearly carries it


def test_e81_needs_the_paper_inside_and_the_paper_verdict_often_enough():
    support = claims.EXPERIMENTS["E81"].supports
    p = value("T13-cost-of-calibration.full")
    base = {"lo": p - 0.05, "hi": p + 0.01}
    assert support({**base, "share": claims.EX5_VERDICT_SHARE})
    assert not support({**base, "share": claims.EX5_VERDICT_SHARE - 0.01})
    assert not support({"lo": p - 0.05, "hi": p - 0.0001, "share": 0.5})


def test_e82_needs_both_cells_inside():
    support = claims.EXPERIMENTS["E82"].supports
    k2, k3 = value("tab:audit.optimism_calibrated.2"), value("tab:audit.optimism_calibrated.3")
    inside = {"k2lo": k2 - 0.01, "k2hi": k2 + 0.01, "k3lo": k3 - 0.01, "k3hi": k3 + 0.01}
    assert support(inside)
    assert not support({**inside, "k2hi": k2 - 0.001})
    assert not support({**inside, "k3lo": k3 + 0.001})


def test_ex9_experiments_speak_only_to_their_claims():
    by_claim = {c.id: [e for e, _ in claims.explanations(c)] for c in claims.CLAIMS}
    owners = {e: cid for cid, es in by_claim.items() for e in es if e in ("E80", "E81", "E82", "E83")}
    assert owners == {"E80": "T14-resplits", "E81": "T13-cost-of-calibration", "E82": "tab:audit", "E83": "T14-resplits"}


def test_optimism_keys_average_the_budgets_equally():
    rows = pd.DataFrame({"part": "resplit_optimism", "index": range(4), "optimism_k1": [0.1, -0.3, 0.0, 0.2],
                         "optimism_k2": [-0.05, 0.1, 0.0, 0.2], "optimism_k10": [0.0, 0.1, 0.3, -0.1]})
    keys = ex9.optimism_keys(rows)  # averages 0.0167, -0.0333, 0.1, 0.1; the last budget is k = 10, not k = 2
    assert keys["splits"] == 4 and keys["budgets"] == 3
    assert keys["margin_optimistic"] == pytest.approx(0.75)
    assert keys["margin_optimistic_last"] == pytest.approx(0.5)
    assert keys["optimism_mean"] == pytest.approx((0.05 / 3 - 0.1 / 3 + 0.1 + 0.1) / 4)


def test_e83_reads_the_share_within_the_claims_tolerance():
    support = claims.EXPERIMENTS["E83"].supports
    share = value("T14-resplits.margin_optimistic_percent") / 100
    assert support({"share": share + claims.EX9_OPTIMISTIC_TOL - 0.001})
    assert not support({"share": share - claims.EX9_OPTIMISTIC_TOL - 0.001})
