"""ex28's E186 (T14's held-out coverage by the W = 1 plateau counted as one tie): hand cases with exact answers."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.studies import claims
from probecommit.studies.explain import ex28_plateau as ex28
from probecommit.studies.explain.ex5_calibration import split_halves
from probecommit.studies.paper_values import value


def test_snapped_removes_only_the_plateaus_round_off():
    s = np.array([1.0 - 2 ** -52, 1.0, 1.0 + 1e-12, 0.999, 1.05, 0.5])
    assert list(ex28.snapped(s)) == [1.0, 1.0, 1.0, 0.999, 1.05, 0.5]


def test_pool_facts_hand_case():
    s = np.array([0.01, 0.01, 0.02, 0.3, 0.3, 0.7, 1.0, 1.0, 1.2, 1.4])
    got = ex28.pool_facts(s)
    assert got == {"plateau_share": 0.2, "beyond_share": 0.2, "tie_max": 0.3}
    assert ex28.pool_facts(np.array([0.1, 0.2]))["tie_max"] == 0.0


def test_split_row_counts_a_plateau_tie_covered_only_when_asked():
    # Calibration half of 4: q = ceil(0.8 * 5) = 4, the 4th smallest, on the plateau.
    s = pd.Series([0.1, 0.2, 1.0, 1.0, 0.3, 1.0, 1.5, 0.05], index=list("abcdefgh"))
    row = ex28.split_row(s, np.array(list("abcd")), np.array(list("efgh")), 0.2)
    assert row["level"] == 1.0 and row["on_plateau"] == 1.0
    assert row["coverage_le"] == 0.75 and row["coverage_lt"] == 0.5 and row["tied"] == 0.25


@settings(max_examples=25, deadline=None)
@given(st.integers(min_value=0, max_value=2 ** 31 - 1))
def test_without_ties_the_split_mean_is_near_the_conformal_identity(seed):
    """Distinct scores: every split's two coverages agree (no tie), and the level is a calibration score."""
    rng = np.random.default_rng(seed)
    s = pd.Series(rng.permutation(40) / 40.0, index=np.arange(40))
    for cal, test in split_halves(s.index.to_numpy(), 5, seed % 1000):
        row = ex28.split_row(s, cal, test, 0.2)
        assert row["coverage_le"] == row["coverage_lt"] and row["tied"] == 0.0
        assert row["level"] in set(s.loc[cal])


def _episodes(scores: list[float]) -> pd.DataFrame:
    """One budget-5 episode table: each instance's four repeats, the worst repeat the given score."""
    rows = [{"instance_id": i, "repeat": r, "k": 5, "method": "probe_robust", "variant": "base", "status": "ok",
             "score_s": s if r == 0 else s / 2} for i, s in enumerate(scores) for r in range(4)]
    return pd.DataFrame(rows)


def test_pool_rows_and_summary_same_seed_equal_and_rule():
    scores = [0.01 * (i + 1) for i in range(14)] + [1.0 - 2 ** -52, 1.0, 1.0, 1.3]
    a = ex28.pool_rows("B_pool_cover", _episodes(scores), 0.2, 6, 9)
    b = ex28.pool_rows("B_pool_cover", _episodes(scores), 0.2, 6, 9)
    pd.testing.assert_frame_equal(a, b)
    assert len(a) == 6 and set(a["budget"]) == {5}
    assert math.isclose(a["plateau_share"].iloc[0], 3 / 18) and math.isclose(a["beyond_share"].iloc[0], 1 / 18)
    keys = ex28.summary(a)
    assert keys["cover.pools"] == 1 and math.isclose(keys["B_pool_cover.level"], a["level"].mean())
    assert math.isclose(keys["B_pool_cover.tie_gain"], (a["coverage_le"] - a["coverage_lt"]).mean())
    assert keys["holds"] == float(keys["pools_holding"] >= 1)


def _keys(level: float, sd: float, coverage: float) -> dict[str, float]:
    return {"p.level": level, "p.level_sd": sd, "p.coverage_le": coverage}


def test_e186_rule_uses_the_claims_tolerances():
    paper = {q: value(f"T14-resplits.{q}") for q in ("level_mean", "level_sd", "heldout_cluster_coverage")}
    l, sd, c = paper["level_mean"], paper["level_sd"], paper["heldout_cluster_coverage"]
    assert ex28.holds(_keys(l, sd, c), "p", paper)
    assert ex28.holds(_keys(l + 0.09, sd - 0.09, c - 0.049), "p", paper)
    assert not ex28.holds(_keys(l + 0.11, sd, c), "p", paper)
    assert not ex28.holds(_keys(l, sd - 0.11, c), "p", paper)
    assert not ex28.holds(_keys(l, sd, c - 0.051), "p", paper)


def test_e186_is_registered_for_t14_coverage_only():
    e = claims.EXPERIMENTS["E186"]
    assert e.supports({"h": 1.0}) and not e.supports({"h": 0.0})
    t14 = next(c for c in claims.CLAIMS if c.id == "T14-resplits")
    assert ("E186", ("held-out cluster coverage",)) in claims.explanations(t14)


def test_verify_recomputes_the_group_from_its_stored_rows(tmp_path):
    from probecommit.report import recompute

    assert ("ex28_plateau", ex28.STORED, "ex28_plateau") in recompute.STORED_SUMMARIES
    scores = [0.02 * (i + 1) for i in range(12)] + [1.0, 1.0, 1.2]
    rows = pd.concat([ex28.pool_rows(p, _episodes(scores), 0.2, 4, 9) for p in ("B_pool_cover", "B_union_cover")],
                     ignore_index=True)
    rows.to_parquet(tmp_path / ex28.STORED)
    assert ex28.summary(pd.read_parquet(tmp_path / ex28.STORED)) == ex28.summary(rows)
