"""E144..E146 (ex20): the misread band, the design's exact exposure, band hits of stored taps, the
post-stratified cells and the rules, on hand cases (exact answers)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import probecommit.studies.claims as C
from probecommit.studies.explain import ex20_band as B
from probecommit.tasks.insertion.model import PAPER_DELTA_MM, TIP_RADIUS_MM

DESIGN = {"x_low": -10.0, "x_high": 10.0, "c_low": 0.7, "c_high": 1.3, "r": TIP_RADIUS_MM, "delta": PAPER_DELTA_MM,
          "repeats": 4.0}


def test_band_edges_hand_cases():
    # c = 1: hg = 4.6, so the band is 3.4 <= |u - x| < 5.505 (the model's edge in, the simulator's out).
    d = np.array([3.4, 3.39, 5.5, 5.505, -4.0, 0.0])
    assert B.in_band(d, np.zeros(6), np.ones(6), TIP_RADIUS_MM, PAPER_DELTA_MM).tolist() == [
        True, False, True, False, True, False]


def test_design_probability_one_position_is_the_band_measure():
    # One tap position, c fixed at 1: a trajectory hits iff 3.4 <= |x| < 5.505, measure 2 x 2.105 / 20, at every k
    # and for any of the repeats alike (the same position every time).
    design = {**DESIGN, "c_low": 1.0, "c_high": 1.0}
    probs = B.design_probabilities([0.0], design, budgets=(1, 3))
    for k in (1, 3):
        assert probs[k][0] == pytest.approx(0.2105, abs=1e-3) and probs[k][1] == pytest.approx(0.2105, abs=1e-3)


def test_design_probability_matches_a_monte_carlo_of_the_design():
    positions = np.arange(-12.0, 12.0 + 1e-9, 3.0)
    probs = B.design_probabilities(positions, DESIGN, budgets=(1, 2, 8))
    rng = np.random.default_rng(0)
    n = 200_000
    x, c = rng.uniform(-10, 10, n), rng.uniform(0.7, 1.3, n)
    hits = np.zeros(n, dtype=bool)
    for k in range(1, 9):
        hits |= B.in_band(positions[rng.integers(9, size=n)], x, c, TIP_RADIUS_MM, PAPER_DELTA_MM)
        if k in probs:
            assert hits.mean() == pytest.approx(probs[k][0], abs=0.005)
    assert probs[1][0] == pytest.approx(0.147, abs=5e-4)  # E112's exact P(band) at the first tap
    assert all(probs[k][1] > probs[k][0] for k in probs)


def _episodes_and_taps():
    inst = pd.DataFrame({"instance_id": ["a", "b"], "true_x_hole": [0.0, 0.0], "true_c": [1.0, 1.0]})
    # a: taps at 0 (pocket, model right) then 4 (band); b: taps at 9 then 12 (top, off the band).
    probes = pd.DataFrame({"instance_id": ["a", "a", "b", "b"], "repeat": [0, 0, 0, 0], "j": [1, 2, 1, 2],
                           "u": [0.0, 4.0, 9.0, 12.0], "y": [-15.0, -15.0, 0.0, 0.0]})
    ep = pd.DataFrame({"instance_id": ["a", "a", "b", "b"], "repeat": [0] * 4, "k": [1, 2, 1, 2],
                       "method": "probe_robust", "variant": "deployed", "realized": [0.0, 1.0, 0.0, 0.0],
                       "predicted": [0.0, 0.25, 0.0, 0.5], "covered": [True, False, True, True],
                       "escaped": [False, True, False, False]})
    return ep, probes, inst


def test_band_rows_hit_is_cumulative_over_taps():
    ep, probes, inst = _episodes_and_taps()
    rows = B.band_rows(ep, probes, inst, "d", DESIGN, budgets=(1, 2))
    assert rows.sort_values(["instance_id", "k"])["hit"].tolist() == [False, True, False, False]
    assert (rows["r"] == TIP_RADIUS_MM).all() and (rows["draw"] == "d").all()


def test_post_stratified_cells_hand_case():
    ep, probes, inst = _episodes_and_taps()
    rows = B.band_rows(ep, probes, inst, B.FROZEN, DESIGN, budgets=(1, 2))
    out = B.frozen_keys(rows, {1: (0.3, 0.6), 2: (0.25, 0.5)}, resamples=50, seed=1)
    # k = 2: a hit the band (optimism 0.75, not covered), b did not (optimism -0.5, covered).
    assert out["share.k2"] == 0.5 and out["gap_hit.k2"] == 0.75 and out["gap_free.k2"] == -0.5
    assert out["optimism_std.k2"] == pytest.approx(0.25 * 0.75 + 0.75 * -0.5)
    assert out["cluster_coverage_std.k2"] == pytest.approx(0.5 * 0.0 + 0.5 * 1.0)
    assert out["optimism.k2"] == pytest.approx(0.125) and out["cluster_coverage.k2"] == 0.5
    # k = 1: nobody hit the band, so the hit stratum is empty and the standardized cell is undefined.
    assert out["share.k1"] == 0.0 and np.isnan(out["optimism_std.k1"])
    assert out["optimism_std_lo.k2"] <= out["optimism_std.k2"] <= out["optimism_std_hi.k2"]


def test_keys_are_a_function_of_the_stored_rows():
    ep, probes, inst = _episodes_and_taps()
    rows = pd.concat([B.band_rows(ep, probes, inst, B.FROZEN, DESIGN, budgets=(1, 2)),
                      B.band_rows(ep.assign(k=ep["k"] * 4), probes.assign(j=probes["j"] * 4), inst, "analytic_draw_00",
                                  DESIGN, budgets=(4, 8))], ignore_index=True)
    boot = {"resamples": 40, "seed": 3}
    first, again = B.keys(rows, boot), B.keys(rows.copy(), boot)
    assert first.keys() == again.keys()
    assert all(first[k] == again[k] or (np.isnan(first[k]) and np.isnan(again[k])) for k in first)
    assert first["draws.count"] == 1


def _v(**kw):
    return {"lo": 0.1, "hi": 0.2, "sh": 0.3, "pd": 0.4, **kw}


def test_rules_need_the_paper_inside_and_a_low_band_share(monkeypatch):
    monkeypatch.setattr(C, "_pv", lambda key: 0.15)
    cell = C.EXPERIMENTS["E144[optimism original k=3]"].supports
    assert cell(_v()) and not cell(_v(hi=0.14)) and not cell(_v(sh=0.5))
    cover = C.EXPERIMENTS["E146[cluster_coverage original k=5]"].supports
    assert cover(_v()) and not cover(_v(lo=0.16)) and not cover(_v(sh=0.4))
    monkeypatch.setattr(C, "_pv", lambda key: 0.216)
    t12 = C.EXPERIMENTS["E145"].supports
    assert t12({"e": 0.17, "sh": 0.5, "pd": 0.6}) and not t12({"e": 0.16, "sh": 0.5, "pd": 0.6})
    assert not t12({"e": 0.2, "sh": 0.6, "pd": 0.6})


def test_claims_name_the_experiments():
    audit = C.claim_by_id("tab:audit") if hasattr(C, "claim_by_id") else next(c for c in C.CLAIMS if c.id == "tab:audit")
    named = {e if isinstance(e, str) else e[0] for e in audit.explain}
    assert {f"E144[optimism original k={k}]" for k in (1, 2, 3, 5, 8)} <= named
    assert {f"E146[cluster_coverage original k={k}]" for k in (1, 2, 3, 5, 8)} <= named
    t12 = next(c for c in C.CLAIMS if c.id == "T12-calibrated-audit")
    assert ("E145", ("original",)) in t12.explain


def test_verify_recomputes_every_key_from_the_stored_rows(tmp_path):
    from probecommit.studies.explain import ex20

    ep, probes, inst = _episodes_and_taps()
    rows = B.band_rows(ep, probes, inst, B.FROZEN, DESIGN, budgets=(1, 2))
    boot = {"resamples": 30, "seed": 2}
    published = B.keys(rows, boot)
    rows.to_parquet(tmp_path / B.STORED)
    got = ex20.recompute(tmp_path, {"ex20_band": published}, boot)
    assert set(got) == {f"ex20_band.{k}" for k in published}
    for k, v in published.items():
        value, source = got[f"ex20_band.{k}"]
        assert source == B.STORED and (value == v or (np.isnan(value) and np.isnan(v)))
    assert ex20.STORED_BY_GROUP == {"ex20_band": B.STORED}
    (tmp_path / B.STORED).unlink()
    assert ex20.recompute(tmp_path, {"ex20_band": published}, boot) == {}  # verify then flags the missing rows
