"""Hand cases for ex13's experiments: E106 (the surprise AUC over draws of the generator: rows, halves, summary)
and E107 (the mixture under every reading of q0's units: the exact effective epsilon, the summary), and the
registry rules wiring them (each can fail)."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex13_mixture as em
from probecommit.studies.explain import ex13_surprise as es

BOOT = dict(resamples=200, seed=0)


def _episodes(ids: list[str], surprise: dict[int, list[float]], escaped: list[bool]) -> pd.DataFrame:
    rows = []
    for k, values in surprise.items():
        for i, s, e in zip(ids, values, escaped):
            rows.append({"instance_id": i, "repeat": 0, "k": k, "method": "probe_robust", "status": "ok",
                         "max_surprise": s, "escaped": e if k == 5 else False})
    rows.append({"instance_id": ids[0], "repeat": 0, "k": 5, "method": "blind", "status": "ok", "max_surprise": 99.0,
                 "escaped": True})  # another executor's row: not read
    return pd.DataFrame(rows)


def test_draw_rows_read_the_first_and_final_budget_and_the_first_tap_class():
    ids = ["b", "a", "c"]
    episodes = _episodes(ids, {1: [0.3, 2.5, 0.4], 5: [1.0, 2.6, 3.0]}, [False, True, False])
    probes = pd.DataFrame({"instance_id": ["a", "a", "b", "c"], "repeat": 0, "j": [1, 2, 1, 1],
                           "u": [-12.0, -6.0, -12.0, -12.0], "y": [-15.1, 0.2, 0.1, -14.8]})
    rows = es.draw_rows("d", episodes, probes, 1, 5, pocket_cut_mm=-7.5)
    assert rows["instance_id"].tolist() == ["a", "b", "c"]
    assert rows["surprise_k1"].tolist() == [2.5, 0.3, 0.4] and rows["surprise_k5"].tolist() == [2.6, 1.0, 3.0]
    assert rows["escaped_final"].tolist() == [True, False, False]
    assert rows["first_tap_pocket"].tolist() == [True, False, True]


def test_pool_halves_split_by_instance_index_not_row_order():
    instances = pd.DataFrame({"instance_id": ["p2", "p0", "p3", "p1"], "instance_index": [2, 0, 3, 1]})
    episodes = pd.DataFrame({"instance_id": ["p3", "p0", "p1", "p2"], "k": 1})
    probes = pd.DataFrame({"instance_id": ["p0", "p3"], "j": 1})
    (e0, p0), (e1, p1) = es.pool_halves(episodes, probes, instances)
    assert sorted(e0["instance_id"]) == ["p0", "p1"] and sorted(e1["instance_id"]) == ["p2", "p3"]
    assert p0["instance_id"].tolist() == ["p0"] and p1["instance_id"].tolist() == ["p3"]


def _rows() -> pd.DataFrame:
    # draw b_test: the escape (i0) is the most surprised at k = 1 (AUC 1) and the least at k = 5 (AUC 0);
    # draw a: surprise ties at k = 1 (AUC 0.5), the escape the most surprised at k = 5 (AUC 1)
    rows = []
    for draw, s1, s5 in (("b_test", [3.0, 1.0, 2.0], [0.5, 1.0, 2.0]), ("a", [1.0, 1.0, 1.0], [4.0, 1.0, 2.0])):
        for i in range(3):
            rows.append({"draw": draw, "instance_id": f"{draw}{i}", "repeat": 0, "surprise_k1": s1[i],
                         "surprise_k5": s5[i], "escaped_final": i == 0, "first_tap_pocket": i in (0, 1)})
    return pd.DataFrame(rows)


def test_surprise_summary_per_draw_and_the_span_over_draws():
    out = es.summary(_rows(), (1, 5), **BOOT)
    assert out["draws"] == 2 and out["b_test.n"] == 3 and out["a.n_escaped"] == 1
    assert out["b_test.auc_k1"][0] == pytest.approx(1.0) and out["b_test.auc_k5"][0] == pytest.approx(0.0)
    assert out["a.auc_k1"][0] == pytest.approx(0.5) and out["a.auc_k5"][0] == pytest.approx(1.0)
    assert (out["auc_k1.min"], out["auc_k1.max"]) == pytest.approx((0.5, 1.0))
    assert (out["auc_k5.min"], out["auc_k5.max"]) == pytest.approx((0.0, 1.0))
    assert out["b_test.first_tap_pocket.escaped"] == 1.0 and out["b_test.first_tap_pocket.rest"] == 0.5
    assert (out["n_escaped.min"], out["n_escaped.max"]) == (1, 1)


def test_e106_needs_the_paper_k1_auc_inside_the_span_of_the_draws():
    e = claims.EXPERIMENTS["E106"]
    claim = {c.id: c for c in claims.CLAIMS}["T36-surprise"]
    assert ("E106", ("k=1",)) in claim.explain
    k1 = claims._pv("T36-surprise.auc_k1")
    assert e.supports({"lo": k1 - 0.1, "hi": k1 + 0.01})
    assert not e.supports({"lo": 0.46, "hi": k1 - 0.01})  # every draw below the paper's value
    assert not e.supports({"lo": k1 + 0.01, "hi": 0.99})


def test_effective_epsilon_is_exact_for_each_reading():
    eps, w, s = 0.01, 19.0, 0.5
    c = 1 / (s * math.sqrt(2 * math.pi))
    odds = lambda e: e / (1 - e)  # noqa: E731
    assert em.effective_epsilon("ours", eps, w, s) == pytest.approx(eps, rel=1e-12)
    # q0 per metre is 1000 x the density per mm: the floor's odds grow 1000-fold
    assert odds(em.effective_epsilon("q0_per_metre", eps, w, s)) == pytest.approx(1000 * odds(eps), rel=1e-12)
    assert odds(em.effective_epsilon("p_per_metre", eps, w, s)) == pytest.approx(odds(eps) / 1000, rel=1e-12)
    # the unnormalized kernel (peak 1) against the density's peak c
    assert odds(em.effective_epsilon("kernel", eps, w, s)) == pytest.approx(odds(eps) * c, rel=1e-12)
    # q0 = 1 (a mass) against the density per mm: w times the density 1 / w
    assert odds(em.effective_epsilon("mass_density", eps, w, s)) == pytest.approx(odds(eps) * w, rel=1e-12)
    assert odds(em.effective_epsilon("mass_kernel", eps, w, s)) == pytest.approx(odds(eps) * w * c, rel=1e-12)


def test_mixture_summary_pairs_by_seed_and_covering_reads_the_range():
    rows = pd.DataFrame({"seed": [1, 1, 2, 2], "reading": ["ours", "q0_per_metre"] * 2, "epsilon": 0.01,
                         "effective_epsilon": [0.01, 0.91, 0.01, 0.91], "right": [0.10, 0.10, 0.12, 0.12],
                         "mixed": [0.10, 0.15, 0.11, 0.20], "changed": [0.0, 0.5, 0.1, 0.6]})
    out = em.summary(rows)
    assert out["seeds"] == 2 and out["right.failure.mean"] == pytest.approx(0.11)
    assert out["ours.paired_cost.min"] == pytest.approx(-0.01) and out["ours.paired_cost.max"] == pytest.approx(0.0)
    assert out["q0_per_metre.paired_cost.min"] == pytest.approx(0.05)
    assert out["q0_per_metre.paired_cost.max"] == pytest.approx(0.08)
    assert out["q0_per_metre.changed_aims.mean"] == pytest.approx(0.55)
    assert "kernel.paired_cost.min" not in out  # a reading not run publishes nothing
    assert em.covering(out, 0.065) == ["q0_per_metre"] and em.covering(out, 0.09) == []


def test_e107_needs_the_paper_cost_inside_some_readings_seed_range():
    e = claims.EXPERIMENTS["E107"]
    assert "E107" in {c.id: c for c in claims.CLAIMS}["T44-mixture-cost"].explain
    cost = claims._pv("T44-mixture-cost.mixture") - claims._pv("T44-mixture-cost.right")
    none = {f"{a}{s}": v for a in ("o", "k", "mk", "md", "m", "mp", "pm") for s, v in (("lo", -0.01), ("hi", 0.01))}
    assert not e.supports(none)
    assert e.supports({**none, "mlo": cost - 0.01, "mhi": cost + 0.01})
    assert e.supports({**none, "klo": cost, "khi": cost})
    assert not e.supports({**none, "mlo": cost + 0.001, "mhi": cost + 0.02})
