"""The explain step's stored tables and the summaries verify recomputes from them (hand cases)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from probecommit.studies.explain import stored
from probecommit.studies.explain.breadth import compact, sweep_keys


def test_margin_keys_read_each_gamma_and_the_optimism_at_gamma_1():
    table = pd.DataFrame({"gamma": [1.0, 0.98, 1.0], "n": [4, 4, 4], "mean_predicted": [0.2, 0.3, 0.1],
                          "mean_realized": [0.5, 0.5, 0.4], "mean_predicted_covered": [0.1, 0.2, 0.0],
                          "mean_realized_covered": [0.25, 0.25, 0.0], "schedule": ["ours", "ours", "paper_schedule"]})
    keys = stored.margin_keys(table)
    assert keys["ours.g0.98.predicted"] == 0.3 and keys["ours.g1.00.realized_covered"] == 0.25
    assert keys["ours.optimism_at_gamma_1"] == pytest.approx(0.3)
    assert keys["ours.optimism_at_gamma_1_covered"] == pytest.approx(0.15)
    assert keys["paper_schedule.optimism_at_gamma_1"] == pytest.approx(0.3)
    assert len(keys) == 3 * 4 + 2 * 2


def test_draws_keys_summarize_the_fresh_draws_not_the_check_row():
    cols = {c: [9.0, 1.0, 2.0, 3.0] for c in stored.DRAW_COLUMNS}
    cols["escape_k8"] = [0.5, 0.1, 0.3, 0.2]
    table = pd.DataFrame({"split": ["B_test_random", "draw_00", "draw_01", "draw_02"], **cols})
    keys = stored.draws_keys(table)
    assert keys["draws.count"] == 3 and keys["draws.analytic_B_test_random.escape_k8"] == 0.5
    assert (keys["draws.failure_k8.mean"], keys["draws.failure_k8.sd"]) == (2.0, 1.0)
    assert (keys["draws.failure_k8.min"], keys["draws.failure_k8.max"]) == (1.0, 3.0)
    assert keys["draws.corr_share_beyond_escape_k8"] == pytest.approx(np.corrcoef([1, 2, 3], [0.1, 0.3, 0.2])[0, 1])


def test_cells_round_trip_check_spread_and_nan_spread():
    parts = {"audit": [{"a": 1.0, "b": 5.0}, {"a": 2.0, "b": 6.0}, {"a": 4.0, "b": 7.0}],
             "faults": [{"x": 0.5}, {"x": math.nan}, {"x": 0.25}],
             "gates_fresh_cal": [{"g": 1.0}, {"g": 3.0}]}
    table = stored.cells_table(parts, {"audit": 0, "faults": 0, "gates_fresh_cal": 1})
    keys = stored.cells_keys(pd.read_parquet(_roundtrip(table)))
    assert keys["draws.audit_check.a"] == 1.0 and keys["draws.audit_check.b"] == 5.0
    assert (keys["draws.audit.a.min"], keys["draws.audit.a.max"], keys["draws.audit.a.mean"]) == (2.0, 4.0, 3.0)
    assert keys["draws.faults_check.x"] == 0.5
    assert (keys["draws.faults.x.min"], keys["draws.faults.x.n"]) == (0.25, 1)  # the undefined draw is left out
    assert keys["draws.gates_fresh_cal.g.mean"] == 2.0  # every pair of fresh draws, none a check
    assert not any(k.startswith("draws.audit_fresh_cal") for k in keys)


def _roundtrip(table: pd.DataFrame):
    import io

    buffer = io.BytesIO()
    table.to_parquet(buffer, compression="zstd")
    buffer.seek(0)
    return buffer


def _episodes(n: int = 6) -> pd.DataFrame:
    rng = np.random.default_rng(3)
    rows = []
    for i in range(n):
        for r in range(2):
            for method, k in (("blind_bayes", 0), ("blind_robust", 0), ("probe_robust", 1), ("probe_robust", 2),
                              ("probe_robust", 5)):
                rows.append({"instance_id": f"i{i}", "repeat": r, "k": k, "method": method, "variant": "deployed",
                             "realized": float(rng.uniform(0.5, 1.0) if k == 0 else rng.uniform(0.0, 0.4)),
                             "predicted": 0.1, "status": "ok"})
    return pd.DataFrame(rows)


def test_compact_keeps_only_the_rows_a_table_ii_row_and_its_prices_read():
    rows = compact(_episodes(), "push1d", 0.5)
    assert sorted(set(zip(rows["method"], rows["k"]))) == [("blind_bayes", 0), ("blind_robust", 0),
                                                           ("probe_robust", 2), ("probe_robust", 5)]
    assert "predicted" not in rows and set(rows["family"]) == {"push1d"} and set(rows["scale"]) == {0.5}


def test_sweep_keys_on_the_compact_rows_equal_those_on_the_whole_episodes():
    from probecommit.studies.explain.breadth import row_and_prices

    boot = {"resamples": 50, "seed": 1}
    whole = _episodes()
    keys = sweep_keys(pd.concat([compact(whole, "push1d", 0.5), compact(whole, "push1d", 0.25)]), {}, boot)
    expected = row_and_prices(whole, "push1d", boot)
    assert {k: keys[f"push1d.s0.5.{k}"] for k in expected} == expected
    assert keys["scales"] == [0.5, 0.25] and keys["push1d.widths"] == 2
    assert keys["push1d.min_paired_lo"] == min(keys["push1d.s0.5.paired_lo"], keys["push1d.s0.25.paired_lo"])


def test_rig_boundary_summary_by_hand():
    from probecommit.studies.explain.rig import boundary_summary

    rows = pd.DataFrame({"session": [1, 2, 3], "first_resolved_mm": [8.0, math.nan, 10.0],
                         "holds_to_mm": [14.0, 14.0, 20.0], "sweep_end_mm": 20.0})
    out = boundary_summary(rows)
    assert out["sessions"] == 3 and out["share_never_resolved"] == pytest.approx(1 / 3)
    assert (out["first_resolved_mm.median"], out["first_resolved_mm.min"], out["first_resolved_mm.max"]) == (9.0, 8.0, 10.0)
    assert out["coverage_holds_to_mm.median"] == 14.0
    assert out["coverage_holds_to_mm.share_at_sweep_end"] == pytest.approx(1 / 3)


def test_mixture_summary_pairs_seeds_and_crosses_them_by_hand():
    from probecommit.studies.explain.mixture_x import summary

    rows = pd.DataFrame({"seed": [1, 2], "epsilon": 0.01, "right": [0.1, 0.2], "mixed": [0.2, 0.2],
                         "changed": [0.0, 0.5], "changed_seed": [0.25, 0.25]})
    out = summary(rows)
    assert (out["seeds"], out["epsilon"]) == (2, 0.01)
    assert out["paired_cost.mean"] == pytest.approx(0.05) and out["paired_cost.max"] == pytest.approx(0.1)
    assert (out["unpaired_cost.min"], out["unpaired_cost.max"]) == pytest.approx((0.0, 0.1))  # 0.2 - 0.2, 0.2 - 0.1
    assert (out["paired_changed_aims.mean"], out["reseeded_changed_aims.mean"]) == (0.25, 0.25)
