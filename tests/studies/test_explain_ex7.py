"""Hand cases for ex7's experiments (E69..E72): the fault harness over the budget, the surprise AUC's
per-reading summary, the fresh-draw summaries, and the registry rules wiring them (each can fail)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex7_faults, ex7_robust

BOOT = dict(resamples=200, seed=0)


def _episodes() -> pd.DataFrame:
    """Two instances, one repeat, budgets 1 and 8, faults particles and none (fault arm, ok rows)."""
    rows = []
    for fault, esc, pred, real in (("particles", {1: [0, 0], 8: [1, 0]}, {1: [0.1, 0.2], 8: [0.0, 0.1]},
                                    {1: [1.0, 0.0], 8: [0.0, 0.0]}),
                                   ("none", {1: [0, 0], 8: [0, 0]}, {1: [0.1, 0.1], 8: [0.1, 0.1]},
                                    {1: [0.0, 0.0], 8: [0.0, 0.0]})):
        for k in (1, 8):
            for i in range(2):
                rows.append({"fault": fault, "arm": "fault", "method": "probe_robust", "status": "ok", "k": k,
                             "instance_id": f"i{i}", "repeat": 0, "escaped": bool(esc[k][i]),
                             "predicted": pred[k][i], "realized": real[k][i]})
    # a row of another arm and a failed row, which must be ignored
    rows.append({**rows[0], "arm": "fix", "escaped": True})
    rows.append({**rows[0], "status": "failed", "escaped": True})
    return pd.DataFrame(rows)


def test_budget_change_is_the_mean_per_episode_change():
    ep = _episodes()
    assert ex7_faults.budget_change(ep, "particles", 1, 8, "escaped", BOOT)[0] == pytest.approx(0.5)
    # optimism k=1: [0.9, -0.2], k=8: [0.0, -0.1] -> changes [-0.9, +0.1], mean -0.4
    assert ex7_faults.budget_change(ep, "particles", 1, 8, "optimism", BOOT)[0] == pytest.approx(-0.4)
    lo, hi = ex7_faults.budget_change(ep, "particles", 1, 8, "optimism", BOOT)[1:]
    assert -0.9 - 1e-12 <= lo <= -0.4 <= hi <= 0.1 + 1e-12


def test_paired_against_the_baseline_at_the_final_budget():
    # particles optimism at 8: [0.0, -0.1]; none: [-0.1, -0.1] -> differences [0.1, 0.0]
    assert ex7_faults.paired_against(_episodes(), "particles", "none", 8, "optimism", BOOT)[0] == pytest.approx(0.05)


def test_surprise_keys_rank_each_reading():
    rows = pd.DataFrame({"instance_id": ["a", "b", "c", "d"], "escaped": [True, True, False, False],
                         "density": [3.0, 4.0, 1.0, 2.0], "class": [0.0, 0.0, 1.0, 1.0]})
    out = ex7_faults.surprise_keys(rows, BOOT)
    assert out["n_escaped"] == 2
    assert out["density_auc"][0] == pytest.approx(1.0) and out["class_auc"][0] == pytest.approx(0.0)


def test_dev_draw_keys_count_the_choices():
    table = pd.DataFrame({"draw": ["d0"] * 2 + ["d1"] * 2 + ["d2"] * 2, "family": "mixture",
                          "value": [0.01, 0.05] * 3, "failure": [0.3, 0.4, 0.5, 0.4, 0.3, 0.3],
                          "chosen": [True, False, False, True, True, False]})
    out = ex7_robust.dev_draw_keys(table, paper=0.01, ours=0.05)
    assert out["count"] == 3
    assert out["share_paper"] == pytest.approx(2 / 3) and out["share_ours"] == pytest.approx(1 / 3)
    assert out["eps_0.01.share_chosen"] == pytest.approx(2 / 3)
    assert out["eps_0.05.failure_mean"] == pytest.approx((0.4 + 0.4 + 0.3) / 3)


def test_harness_draw_keys():
    table = pd.DataFrame({"draw": ["h0", "h1"], "right": [0.10, 0.12], "mixed": [0.11, 0.10],
                          "changed": [0.03, 0.05]})
    out = ex7_robust.harness_draw_keys(table)
    assert out["count"] == 2
    assert out["paired_cost.min"] == pytest.approx(-0.02) and out["paired_cost.max"] == pytest.approx(0.01)
    assert out["paired_cost.mean"] == pytest.approx(-0.005) and out["changed_aims.max"] == pytest.approx(0.05)


def _wired(number: str, claim_id: str) -> None:
    by_id = {c.id: c for c in claims.CLAIMS}
    assert number in [x if isinstance(x, str) else x[0] for x in by_id[claim_id].explain]


def test_e69_needs_escape_up_optimism_down_and_the_boundary_contrast():
    e = claims.EXPERIMENTS["E69"]
    _wired("E69", "T39-particles-signature")
    ok = {"elo": 0.06, "ohi": -0.03, "blo": 0.1}
    assert e.supports(ok)
    assert not e.supports({**ok, "elo": -0.01})
    assert not e.supports({**ok, "ohi": 0.01})
    assert not e.supports({**ok, "blo": -0.01})


def test_e70_needs_every_printed_row_inside():
    e = claims.EXPERIMENTS["E70"]
    _wired("E70", "tab:faults")
    around = lambda key: (claims._pv(key) - 0.05, claims._pv(key) + 0.05)  # noqa: E731
    v = {}
    for name, row in (("p", "particles"), ("r", "prior"), ("b", "boundary")):
        v[f"{name}lo"], v[f"{name}hi"] = around(f"tab:faults.{row}.surprise")
    assert e.supports(v)
    assert not e.supports({**v, "bhi": claims._pv("tab:faults.boundary.surprise") - 0.01})
    assert not e.supports({**v, "plo": claims._pv("tab:faults.particles.surprise") + 0.01})


def test_e71_and_e72_rules_can_fail():
    e71, e72 = claims.EXPERIMENTS["E71"], claims.EXPERIMENTS["E72"]
    _wired("E71", "T42-robust-chosen")
    _wired("E72", "T44-mixture-cost")
    share = claims.UNRESOLVED_CHOICE_SHARE
    assert e71.supports({"sp": share, "so": 0.5}) and not e71.supports({"sp": share / 2, "so": 0.5})
    assert not e71.supports({"sp": 0.5, "so": 0.0})
    cost = claims._pv("T44-mixture-cost.mixture") - claims._pv("T44-mixture-cost.right")
    assert e72.supports({"cmin": cost - 0.01, "cmax": cost + 0.01})
    assert not e72.supports({"cmin": -0.02, "cmax": cost - 0.01})
    assert np.isfinite(cost) and cost > 0


def test_an_unpredicted_class_is_stored_as_infinity_and_ranks_above_every_finite_surprise():
    """-log 0 is the largest surprise: the rows keep ``+inf`` (no finite stand-in), the AUC ranks it above the largest
    finite one and counts it as unpredicted, and ``verify``'s checks accept it in the class column only."""
    from probecommit.report import checks

    tiny = np.nextafter(0.0, 1.0)  # the smallest positive float64: its -log is the largest finite surprise
    rows = pd.DataFrame({"instance_id": list("abcd"), "escaped": [True, False, True, False],
                         "density": [1.0, 2.0, 3.0, 0.5], "class": [np.inf, 5.0, np.inf, -np.log(tiny)]})
    out = ex7_faults.surprise_keys(rows, BOOT)
    assert out["class_auc"][0] == pytest.approx(1.0) and out["n_class_unpredicted"] == 2
    # a publication made before the rows kept +inf stored 745: the same count and the same AUC
    old = ex7_faults.surprise_keys(rows.assign(**{"class": np.minimum(rows["class"], 745.0)}), BOOT)
    assert old["n_class_unpredicted"] == 2 and old["class_auc"] == out["class_auc"]
    assert -np.log(tiny) == ex7_faults.LARGEST_FINITE_SURPRISE < 745.0

    class Tally:
        def __init__(self):
            self.failed = []

        def check(self, kind, ok, message):
            if not ok:
                self.failed.append(message)

    ok, bad = Tally(), Tally()
    checks.parquet_invariants("explain", ex7_faults.STORED, rows, ok)
    checks.parquet_invariants("explain", ex7_faults.STORED, rows.assign(density=[np.inf, 2.0, 3.0, 0.5]), bad)
    assert ok.failed == [] and len(bad.failed) == 1 and "density" in bad.failed[0]
