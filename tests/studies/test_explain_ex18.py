"""ex18's E132 (T14's optimistic share as a count of splits): hand cases with exact answers."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from probecommit.studies import claims
from probecommit.studies.explain import ex18_share as ex18
from probecommit.studies.paper_values import value


def _fisher_two_sided(a: int, b: int, c: int, d: int) -> float:
    """Fisher's exact two-sided p by enumeration: every table with the same margins at most as likely."""
    row, col, n = a + b, a + c, a + b + c + d
    prob = lambda x: math.comb(col, x) * math.comb(n - col, row - x) / math.comb(n, row)  # noqa: E731
    seen = prob(a)
    return sum(prob(x) for x in range(max(0, row + col - n), min(row, col) + 1) if prob(x) <= seen * (1 + 1e-7))


def test_count_keys_exact_cases():
    got = ex18.count_keys(0, 5, 5)
    assert got["optimistic"] == 0 and got["share"] == 0 and got["sd"] == 0
    assert got["cp_lo"] == 0 and math.isclose(got["cp_hi"], 1 - 0.025 ** (1 / 5), rel_tol=1e-9)
    assert math.isclose(got["fisher_p"], 2 / math.comb(10, 5), rel_tol=1e-9)  # the two extreme tables
    got = ex18.count_keys(24, 50, 32)
    assert math.isclose(got["fisher_p"], _fisher_two_sided(24, 26, 32, 18), rel_tol=1e-9)
    assert math.isclose(got["sd"], math.sqrt(0.48 * 0.52 / 50))
    assert got["cp_lo"] < 0.48 < got["cp_hi"]
    assert ex18.count_keys(32, 50, 32)["fisher_p"] == 1.0


def test_paper_count_is_its_percent_of_the_splits():
    assert value("T14-resplits.margin_optimistic_percent") == 64
    assert ex18.paper_count(50) == 32 and ex18.paper_count(2) == 1


def _ex15_rows(pool: str, opt: list[float], e: np.ndarray) -> pd.DataFrame:
    n = len(opt)
    return pd.DataFrame({"pool": pool, "index": range(n), "level_a1": np.linspace(0.5, 1.0, n),
                         "coverage_a3": 0.8, "c5_failure": 0.3, "c5_optimistic": opt,
                         **{f"c15_optimism_k{k + 1}": e[:, k] for k in range(e.shape[1])}})


def test_rows_from_reads_each_margin_reading():
    e = np.array([[-0.1, 0.2], [0.1, -0.05], [-0.1, -0.2], [0.3, 0.1]])
    union = _ex15_rows("B_union_cover", [1.0, 0.0, 0.0, 1.0], e)
    other = _ex15_rows("pool_draw_00_paper_schedule", [np.nan] * 4, e)
    rows = ex18.rows_from([union, None, other])
    assert list(rows["pool"]) == ["B_union_cover"] * 4  # a pool without the study's calibration is left out
    assert list(rows["c5"]) == [1, 0, 0, 1]
    assert list(rows["c15_k5"]) == [1, 0, 0, 1]  # the last budget (k2 here) above zero
    assert list(rows["c15_mean"]) == [1, 1, 0, 1]
    assert list(rows["c15_any"]) == [1, 1, 0, 1]
    keys = ex18.summary(rows)
    assert keys["B_union_cover.splits"] == 4 and keys["B_union_cover.c5.optimistic"] == 2
    assert keys["paper.optimistic"] == ex18.paper_count(4) == 3
    assert math.isclose(keys["B_union_cover.level"], 0.75)
    assert math.isclose(keys["B_union_cover.c15_mean.fisher_p"], _fisher_two_sided(3, 1, 3, 1))


def _values(**over: float) -> dict[str, float]:
    v = {"f": value("T14-resplits.failure_mean"), "l": value("T14-resplits.level_mean"),
         "c": value("T14-resplits.heldout_cluster_coverage"), "p": 0.2}
    return {**v, **over}


def test_e132_needs_the_three_numbers_inside_and_the_counts_agreeing():
    assert claims._ex18_share_holds(_values())
    assert not claims._ex18_share_holds(_values(p=0.049))
    assert claims._ex18_share_holds(_values(p=0.05))
    assert not claims._ex18_share_holds(_values(l=value("T14-resplits.level_mean") + 0.11))
    assert not claims._ex18_share_holds(_values(c=value("T14-resplits.heldout_cluster_coverage") - 0.06))
    assert not claims._ex18_share_holds(_values(f=value("T14-resplits.failure_mean") + 0.03))


def test_t14_names_e132_for_its_three_failing_comparisons():
    t14 = next(c for c in claims.CLAIMS if c.id == "T14-resplits")
    named = {number: labels for number, labels in t14.explain}
    assert named["E132"] == ("level mean", "held-out cluster coverage", "margin optimistic")
    assert "E132" in claims.EXPERIMENTS
