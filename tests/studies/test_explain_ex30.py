"""ex30's E190, E191 (the margin judged on fresh calibration episodes at each candidate gamma): hand cases with exact
answers, same-seed equality, the rules at their edges, verify's round trip."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.studies import claims
from probecommit.studies.explain import ex30_fresh as ex30
from probecommit.studies.paper_values import value


def _table(values: dict[tuple[str, int], tuple[float, float]], failed: tuple[str, int] | None = None) -> pd.DataFrame:
    """One gamma's episode table at k = 5: (instance, repeat) -> (predicted, realized); ``failed`` marked failed."""
    rows = [{"instance_id": i, "repeat": r, "k": 5, "status": "failed" if (i, r) == failed else "ok",
             "predicted": p, "realized": f} for (i, r), (p, f) in values.items()]
    return pd.DataFrame(rows)


def _sums() -> ex30.GridSums:
    """Two gammas, two instances of two repeats. At 1.00 the stored episodes are optimistic (predicted 0.8 against
    realized 1); at 0.98 not (1.6 against 1). Instance a's repeat 1 is the lucky one at 1.00 (realized 0)."""
    hi = _table({("a", 0): (0.2, 1.0), ("a", 1): (0.2, 0.0), ("b", 0): (0.2, 0.0), ("b", 1): (0.2, 0.0)})
    lo = _table({("a", 0): (0.4, 1.0), ("a", 1): (0.4, 0.0), ("b", 0): (0.4, 0.0), ("b", 1): (0.4, 0.0)})
    return ex30.GridSums([1.0, 0.98], [hi, lo])


def test_grid_sums_hand_case_and_failed_rows_left_out():
    s = _sums()
    assert list(s.ids) == ["a", "b"] and s.p.shape == (2, 2, 2)
    assert s.r[0].tolist() == [[1.0, 0.0], [0.0, 0.0]] and s.n.sum() == 8
    t = ex30.GridSums([1.0], [_table({("a", 0): (0.5, 1.0), ("a", 1): (0.25, 0.0)}, failed=("a", 0))])
    assert t.p[0].tolist() == [[0.0, 0.25]] and t.n[0].tolist() == [[0.0, 1.0]]
    assert math.isclose(s.optimism(1, s.rows_of(np.array(["a"]))), (1.0 - 0.8) / 2)


def test_select_stops_at_the_largest_passing_gamma_and_a_lucky_draw_moves_it_up():
    s = _sums()
    rows = s.rows_of(np.array(["a", "b"]))
    m, e = ex30.select(s, rows, None)
    assert m == 1 and math.isclose(e, (1.0 - 1.6) / 4)
    # A draw that takes a's lucky repeat twice at 1.00 passes there (realized 0 <= 0.8): the search stops at 1.00,
    # on the draw, where the stored episodes are optimistic (the winner's curse).
    lucky = np.zeros((2, 2, 2), dtype=int)
    lucky[0, 0] = 1
    assert ex30.select(s, rows, lucky) == (0, -0.2)
    # Repeat 0 everywhere: 1.00 fails (2 > 0.8), 0.98 fails too (2 > 1.6): none passes, the smallest is taken.
    assert ex30.select(s, rows, np.zeros((2, 2, 2), dtype=int)) == (1, (2.0 - 1.6) / 4)
    # Only instance b drawn (rows of b alone): its episodes at 1.00 pass (0 <= 0.4): the search stops at 1.00.
    assert ex30.select(s, s.rows_of(np.array(["b"])), None) == (0, -0.2)


def test_select_takes_the_smallest_gamma_when_none_passes():
    bad = _table({("a", 0): (0.0, 1.0), ("a", 1): (0.0, 1.0)})
    s = ex30.GridSums([1.0, 0.98], [bad, bad])
    assert ex30.select(s, np.array([0]), None) == (1, 1.0)


@settings(max_examples=20, deadline=None)
@given(st.integers(min_value=0, max_value=2 ** 31 - 1))
def test_identical_repeats_make_every_draw_the_stored_selection(seed):
    """When an instance's repeats are identical, redrawing them changes nothing: the noisy rows equal draw -1."""
    rng = np.random.default_rng(seed)
    gammas = [1.0, 0.98, 0.96]
    tables = []
    for g in gammas:
        per = {i: (float(rng.uniform(0, 1)) * (1.2 - g), float(rng.integers(0, 2))) for i in "abcdef"}
        tables.append(_table({(i, r): per[i] for i in "abcdef" for r in range(4)}))
    s = ex30.GridSums(gammas, tables)
    rows = pd.DataFrame(ex30.split_rows(s, 0, np.array(list("abc")), np.array(list("def")), 0.5,
                                        np.random.default_rng(seed), 3))
    assert (rows["gamma"] == rows["gamma"].iloc[0]).all() and (rows["held"] == rows["held"].iloc[0]).all()
    assert np.allclose(rows["cal_drawn"], rows["cal_true"])


def test_split_rows_same_seed_equal_and_flag_is_held_above_zero():
    s = _sums()
    a = ex30.split_rows(s, 3, np.array(["a"]), np.array(["b"]), 0.7, np.random.default_rng(5), 4)
    b = ex30.split_rows(s, 3, np.array(["a"]), np.array(["b"]), 0.7, np.random.default_rng(5), 4)
    assert a == b and [r["draw"] for r in a] == [-1, 0, 1, 2, 3]
    assert all(r["optimistic"] == float(r["held"] > 0) and r["index"] == 3 for r in a)


def _share(flags: list[float], draw: int) -> pd.DataFrame:
    return pd.DataFrame({"part": "share", "index": range(len(flags)), "draw": draw, "level": 0.5, "gamma": 0.5,
                         "cal_drawn": -0.01, "cal_true": -0.01, "held": [0.1 if f else -0.1 for f in flags],
                         "optimistic": flags})


def test_e190_rule_is_the_claims_tolerance_on_the_drawn_share():
    paper = float(value("T14-resplits.margin_optimistic_percent")) / 100.0
    plain = _share([1.0] * 9 + [0.0] * 41, -1)
    for ones, holds in ((27, 1.0), (32, 1.0), (26, 0.0), (38, 0.0)):
        rows = pd.concat([plain, _share([1.0] * ones + [0.0] * (50 - ones), 0)], ignore_index=True)
        keys = ex30.share_keys(rows)
        assert keys["holds"] == holds, (ones, keys["share"], paper)
        assert math.isclose(keys["share_plain"], 0.18) and keys["splits"] == 50 and keys["draws"] == 1


def _table_rows(k2: tuple[float, float], k3: tuple[float, float]) -> pd.DataFrame:
    chosen = pd.DataFrame({"part": "select", "draw": [-1, 0, 1, 2], "index": [-1, 0, 1, 2],
                           "gamma": [0.56, 0.62, 0.58, 0.60], "cal_drawn": 0.0})
    cells = pd.DataFrame({"part": "cells", "index": [2, 3], "k": [2, 3], "gamma": 0.60, "threshold": 0.5,
                          "optimism": [sum(k2) / 2, sum(k3) / 2], "lo": [k2[0], k3[0]], "hi": [k2[1], k3[1]]})
    return pd.concat([chosen, cells], ignore_index=True)


def test_e191_rule_needs_both_paper_cells_inside():
    p2, p3 = (float(value(f"tab:audit.optimism_calibrated.{k}")) for k in (2, 3))
    keys = ex30.table_keys(_table_rows((p2 - 0.01, p2 + 0.01), (p3 - 0.01, p3 + 0.01)))
    assert keys["holds"] == 1.0 and keys["gamma_plain"] == 0.56 and keys["gamma_median"] == 0.60
    assert keys["gamma_min"] == 0.58 and keys["gamma_max"] == 0.62 and keys["draws"] == 3
    assert ex30.table_keys(_table_rows((p2 - 0.01, p2 + 0.01), (p3 + 0.001, p3 + 0.1)))["holds"] == 0.0
    assert ex30.table_keys(_table_rows((p2 - 0.1, p2 - 0.001), (p3 - 0.01, p3 + 0.01)))["holds"] == 0.0


def test_e190_e191_registered_for_their_comparisons():
    for number in ("E190", "E191"):
        e = claims.EXPERIMENTS[number]
        assert e.supports({"ok": 1.0}) and not e.supports({"ok": 0.0})
    t14 = next(c for c in claims.CLAIMS if c.id == "T14-resplits")
    assert ("E190", ("margin optimistic",)) in claims.explanations(t14)
    audit = next(c for c in claims.CLAIMS if c.id == "tab:audit")
    assert ("E191", ("optimism calibrated k=2", "optimism calibrated k=3")) in claims.explanations(audit)


def test_verify_recomputes_the_group_from_its_stored_rows(tmp_path):
    from probecommit.report import recompute

    assert ("ex30_fresh", ex30.STORED, "ex30_fresh") in recompute.STORED_SUMMARIES
    p2, p3 = (float(value(f"tab:audit.optimism_calibrated.{k}")) for k in (2, 3))
    rows = pd.concat([_share([1.0, 0.0], -1), _share([1.0, 1.0], 0), _table_rows((p2, p2), (p3, p3))],
                     ignore_index=True)
    rows.to_parquet(tmp_path / ex30.STORED)
    again = ex30.summary(pd.read_parquet(tmp_path / ex30.STORED))
    assert again == ex30.summary(rows) and again["share.share"] == 1.0 and again["table.holds"] == 1.0
