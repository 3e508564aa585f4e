"""Hand cases for ex6's explain experiments (E62..E64): taps without replacement, the random
gates over one range, surprise under every reading, and the registry rules that can fail."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.audit.gates import curve_area, gate_curve
from probecommit.studies import claims
from probecommit.studies.explain import ex6_gates, ex6_probes, ex6_surprise


# ------------------------------------------------------------------ E62: taps without replacement


def test_without_replacement_draws_distinct_positions_reproducibly():
    a = ex6_probes.without_replacement(9, 8, seed=2026, instance_index=3, repeat=1)
    assert len(a) == 8 and len(set(a.tolist())) == 8 and set(a.tolist()) <= set(range(9))
    assert np.array_equal(a, ex6_probes.without_replacement(9, 8, seed=2026, instance_index=3, repeat=1))
    assert not np.array_equal(a, ex6_probes.without_replacement(9, 8, seed=2026, instance_index=3, repeat=2))
    with pytest.raises(ValueError):
        ex6_probes.without_replacement(9, 10, seed=0, instance_index=0, repeat=0)


def test_distinct_taps_by_hand():
    probes = pd.DataFrame({"instance_id": ["a"] * 4 + ["b"] * 4, "repeat": [0] * 8, "j": [1, 2, 3, 4] * 2,
                           "u": [0.0, 3.0, 0.0, 3.0, -3.0, 0.0, 3.0, 6.0]})
    d = ex6_probes.distinct_taps(probes).set_index(["instance_id", "k"])["distinct_taps"]
    assert d.loc["a"].tolist() == [1, 2, 2, 2] and d.loc["b"].tolist() == [1, 2, 3, 4]


def test_probe_rule_summary_from_stored_rows_by_hand():
    """Two instances, one repeat, k = 1 and 2; escape rises on one instance without replacement."""
    rows = pd.DataFrame({"instance_id": ["a", "a", "b", "b"] * 2, "repeat": 0, "k": [1, 2] * 4,
                         "escaped": [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
                         "distinct_taps": [1, 1, 1, 2, 1, 2, 1, 2],
                         "rule": ["with_replacement"] * 4 + ["without_replacement"] * 4})
    v = ex6_probes.summary(rows, dict(resamples=200, seed=0))
    assert v["with_replacement.escape_k2"][0] == 0.0 and v["without_replacement.escape_k2"][0] == 0.5
    assert v["paired_escape_k2"][0] == 0.5
    assert v["with_replacement.distinct_taps_k2"] == 1.5 and v["without_replacement.distinct_taps_k2"] == 2.0


def test_e62_rule_needs_the_paper_inside_both_budgets_and_a_rise():
    e = claims.EXPERIMENTS["E62"]
    p1, p8 = claims._pv("T19-pybullet-escape.k1"), claims._pv("T19-pybullet-escape.k8")
    ok = {"l1": p1 - 0.01, "h1": p1 + 0.01, "l8": p8 - 0.01, "h8": p8 + 0.01, "e8": p8, "s8": p8 - 0.05}
    assert e.supports(ok)
    assert not e.supports({**ok, "h8": p8 - 0.001})  # the paper's k = 8 above our interval (ours: 0.161 < 0.167)
    assert not e.supports({**ok, "l1": p1 + 0.001})
    assert not e.supports({**ok, "s8": p8 + 0.01})  # no rise over the run as made
    by_id = {c.id: c for c in claims.CLAIMS}
    for cid in ("T19-pybullet-escape", "tab:engines"):
        assert "E62" in [x if isinstance(x, str) else x[0] for x in by_id[cid].explain]


# ------------------------------------------------------------------ E63: the gates over one range


def test_area_between_by_hand():
    curve = pd.DataFrame({"commit_rate": [0.0, 0.5, 0.5, 1.0], "failure": [0.2, 0.4, 0.1, 0.3]})
    # [0.25, 0.5]: f from 0.3 to 0.4 -> 0.25 * 0.35; the vertical step adds nothing; [0.5, 1]: 0.5 * 0.2.
    assert ex6_gates.area_between(curve, 0.25, 1.0) == pytest.approx(0.0875 + 0.1)
    assert ex6_gates.area_between(curve, 0.0, 1.0) == pytest.approx(curve_area(curve)["area"])
    assert ex6_gates.area_between(curve, 0.6, 0.6) == 0.0


def test_compare_reads_a_short_range_as_the_cause():
    """Raw ties at 0 on four of six trajectories (its curve starts at 2/3); posterior variance orders all six.
    By hand: raw commits 4/6 at f 1/4, 5/6 at 2/5, 1 at 1/3; posterior variance 1/6..1 at f 0, 0, 1/3, 1/4,
    1/5, 1/3. Raw's own-range area is the smaller; per unit range and over [2/3, 1] posterior variance's is."""
    y = np.array([[1.0], [0.0], [0.0], [0.0], [1.0], [0.0]])
    col = lambda *v: np.array(v, dtype=float)[:, None]  # noqa: E731
    gates = {"raw": (col(4, 0, 0, 5, 0, 0), y), "adjusted": (col(3, 6, 5, 4, 2, 1), y),
             "posterior_variance": (col(6, 1, 4, 2, 3, 5), y)}
    v = ex6_gates.compare(gates)
    assert v["raw.c_min"] == pytest.approx(2 / 3) and v["common.c_lo"] == pytest.approx(2 / 3)
    assert v["common.c_hi"] == 1.0
    assert v["raw.area"] == pytest.approx((1 / 6) * ((1 / 4 + 2 / 5) / 2 + (2 / 5 + 1 / 3) / 2))
    assert v["raw.area"] == pytest.approx(curve_area(gate_curve(*gates["raw"]))["area"])
    pv = (1 / 6) * ((0 + 1 / 3) / 2 + (1 / 3 + 1 / 4) / 2 + (1 / 4 + 1 / 5) / 2 + (1 / 5 + 1 / 3) / 2)
    assert v["posterior_variance.area"] == pytest.approx(pv)
    assert v["posterior_variance.normalized"] == pytest.approx(pv / (5 / 6))
    assert v["posterior_variance.common_area"] == pytest.approx((1 / 6) * ((1 / 4 + 1 / 5) / 2 + (1 / 5 + 1 / 3) / 2))
    assert v["raw.common_area"] == pytest.approx(v["raw.area"])
    assert v["area.lowest_is_posterior_variance"] == 0
    assert v["normalized.lowest_is_posterior_variance"] == 1
    assert v["common_area.lowest_is_posterior_variance"] == 1


def test_lowest_breaks_ties_in_a_fixed_order():
    assert ex6_gates.lowest({"raw": 0.2, "adjusted": 0.2, "posterior_variance": 0.2}) == "raw"
    assert ex6_gates.lowest({"raw": 0.3, "adjusted": 0.2, "posterior_variance": 0.1}) == "posterior_variance"


def test_e63_rule_can_fail():
    e = claims.EXPERIMENTS["E63"]
    assert e.supports({"low": 1, "share": 0.5})
    assert not e.supports({"low": 0, "share": 0.9})
    assert not e.supports({"low": 1, "share": 0.49})


# ------------------------------------------------------------------ E64: surprise readings


def test_surprise_summary_reads_the_label_at_either_budget():
    """Three trajectories at k = 1: the highest surprise is the one escaped by k = 1 (AUC 1) but not the one
    escaped at the final budget, which has the lowest surprise (AUC 0); "not covered" mirrors it."""
    rows = pd.DataFrame({"instance_id": ["a", "b", "c"], "repeat": 0, "k": 1, "density": [3.0, 1.0, 2.0],
                         "class": [3.0, 1.0, 2.0], "escaped_own": [True, False, False],
                         "covered_own": [False, True, True], "escaped_final": [False, True, False],
                         "covered_final": [True, False, True], "first_tap_pocket": [True, True, False]})
    v = ex6_surprise.summary(rows, resamples=50, seed=0)
    assert v["density.own_hull.k1"][0] == 1.0 and v["class.own_retained.k1"][0] == 1.0
    assert v["density.final_hull.k1"][0] == 0.0 and v["class.final_retained.k1"][0] == 0.0
    assert v["n.own_hull.k1"] == 1 and v["n.final_retained.k1"] == 1
    assert v["first_tap_pocket.escaped"] == 1.0 and v["first_tap_pocket.rest"] == 0.5


def test_e64_needs_one_reading_for_both_budgets():
    e = claims.EXPERIMENTS["E64"]
    p1, p5 = claims._pv("T36-surprise.auc_k1"), claims._pv("T36-surprise.auc_k5")
    away = {f"{i}.k{k}.{j}": (0.0 if j == 1 else 0.1) for i in range(8) for k in (1, 5) for j in (1, 2)}
    assert not e.supports(away)
    split = {**away, "0.k1.1": p1 - 0.01, "0.k1.2": p1 + 0.01, "1.k5.1": p5 - 0.01, "1.k5.2": p5 + 0.01}
    assert not e.supports(split)  # k = 1 matched by one reading, k = 5 by another: not one definition
    assert e.supports({**split, "1.k1.1": p1 - 0.01, "1.k1.2": p1 + 0.01})  # density, final-budget retained label
    own = {**away, "3.k1.1": p1 - 0.01, "3.k1.2": p1 + 0.01, "3.k5.1": p5 - 0.01, "3.k5.2": p5 + 0.01}
    assert not e.supports(own)  # the label at the surprise's own budget: the paper's words rule it out
