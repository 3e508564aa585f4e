"""Commit gates: first-passage commitment, curves, areas and the committed pool."""

import numpy as np
import pandas as pd
import pytest

from probecommit.audit.gates import (
    GateSignal,
    curve_area,
    evaluate_gates,
    first_passage,
    gate_curve,
    gates_from_tables,
    operating_point,
)

NAN = np.nan
SIGNAL = np.array([[0.5, 0.3, 0.1], [0.2, 0.4, 0.2], [0.6, 0.6, 0.6], [NAN, 0.3, 0.05]])
OUTCOME = np.array([[1, 1, 0], [0, 1, 1], [1, 0, 0], [1, 0, 1]], dtype=float)
ESCAPED = np.array([False, True, False, True])


def test_first_passage_by_hand():
    np.testing.assert_array_equal(first_passage(SIGNAL, 0.05), [-1, -1, -1, 2])
    np.testing.assert_array_equal(first_passage(SIGNAL, 0.3), [1, 0, -1, 1])
    np.testing.assert_array_equal(first_passage(SIGNAL, 1.0), [0, 0, 0, 1])  # NaN never passes


def test_gate_curve_by_hand():
    c = gate_curve(SIGNAL, OUTCOME)
    np.testing.assert_allclose(c["tau"], [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    np.testing.assert_array_equal(c["n_committed"], [1, 2, 3, 3, 3, 3, 4])
    np.testing.assert_allclose(c["failure"], [1, 0.5, 1 / 3, 1 / 3, 1 / 3, 1 / 3, 0.5])
    np.testing.assert_allclose(c["commit_rate"], [0.25, 0.5, 0.75, 0.75, 0.75, 0.75, 1.0])


def test_curve_area_by_hand():
    a = curve_area(gate_curve(SIGNAL, OUTCOME))
    area = 0.25 * (1 + 0.5) / 2 + 0.25 * (0.5 + 1 / 3) / 2 + 0.25 * (1 / 3 + 0.5) / 2
    assert a["area"] == pytest.approx(area)
    assert (a["c_min"], a["c_max"]) == (0.25, 1.0)
    assert a["mean_failure"] == pytest.approx(area / 0.75)


def test_operating_point_tie_rules():
    c = gate_curve(SIGNAL, OUTCOME)
    assert operating_point(c, 0.6)["tau"] == pytest.approx(0.1)  # 0.5 is nearer than 0.75
    assert operating_point(c, 0.75)["tau"] == pytest.approx(0.2)  # smallest tau reaching 0.75
    assert operating_point(c, 0.625)["commit_rate"] == pytest.approx(0.5)  # equidistant: lower rate


def test_evaluate_gates_pool_counts_claims_and_realized():
    res = evaluate_gates([GateSignal("raw", SIGNAL, OUTCOME, SIGNAL),
                          GateSignal("oracle", OUTCOME, OUTCOME, None, deployable=False)], ESCAPED)
    raw = res.summary.set_index("signal").loc["raw"]
    assert raw["n_committed"] == 2 and raw["n_rejected"] == 2  # T0 and T3 at tau = 0.1
    assert raw["escaped_committed"] == 1 and raw["escaped_rejected"] == 1
    assert raw["claimed"] == pytest.approx((0.1 + 0.05) / 2)
    assert raw["realized"] == pytest.approx(0.5)
    oracle = res.summary.set_index("signal").loc["oracle"]
    # Every trajectory has a zero outcome somewhere: the oracle commits all at zero failure.
    assert oracle["realized"] == 0.0 and oracle["n_committed"] == 4 and np.isnan(oracle["claimed"])


def test_event_sweep_matches_brute_force_on_random_signals():
    rng = np.random.default_rng(0)
    for trial in range(20):
        t, k = rng.integers(1, 30), rng.integers(1, 7)
        sig = rng.integers(0, 6, (t, k)).astype(float) / 5  # many ties
        sig[rng.random((t, k)) < 0.1] = np.nan
        out = rng.random((t, k))
        curve = gate_curve(sig, out)
        taus = np.unique(sig[np.isfinite(sig)])
        np.testing.assert_allclose(curve["tau"], taus)
        for _, row in curve.iterrows():
            stop = first_passage(sig, row["tau"])
            committed = stop >= 0
            assert row["n_committed"] == committed.sum()
            if committed.any():
                assert row["failure"] == pytest.approx(out[np.flatnonzero(committed), stop[committed]].mean())


def _table(signal, outcome, escaped, column="predicted"):
    rows = []
    for t in range(signal.shape[0]):
        for j, k in enumerate((1, 2, 3)):
            rows.append({"instance_id": f"i{t // 2}", "repeat": t % 2, "k": k, "method": "probe_robust",
                         column: signal[t, j], "realized": outcome[t, j], "escaped": bool(escaped[t] and k == 3),
                         "post_var": 1.0 - j * 0.1 * (t + 1), "status": "ok"})
    return pd.DataFrame(rows)


def test_gates_from_tables_uses_each_executors_outcomes():
    raw = _table(np.nan_to_num(SIGNAL, nan=0.9), OUTCOME, ESCAPED)
    adjusted = _table(np.nan_to_num(SIGNAL, nan=0.9) + 0.2, 1 - OUTCOME, ESCAPED)
    res = gates_from_tables(raw, adjusted)
    s = res.summary.set_index("signal")
    assert list(s.index) == ["raw", "adjusted", "posterior_variance", "oracle"]
    assert res.budgets == [1, 2, 3] and res.n_trajectories == 4 and res.n_dropped == 0
    # The adjusted gate's failure is measured on its own (flipped) outcomes.
    adj = res.curves[res.curves.signal == "adjusted"]
    raw_c = res.curves[res.curves.signal == "raw"]
    np.testing.assert_allclose(adj["failure"].iloc[-1], 1 - raw_c["failure"].iloc[-1])
    assert s.loc["raw", "escaped_committed"] + s.loc["raw", "escaped_rejected"] == 2


def test_gates_drop_trajectories_with_a_failed_episode():
    raw = _table(np.nan_to_num(SIGNAL, nan=0.9), OUTCOME, ESCAPED)
    raw.loc[4, ["realized", "status"]] = [np.nan, "failed"]  # trajectory 1 at k = 2
    res = gates_from_tables(raw)
    assert res.n_dropped == 1 and res.n_trajectories == 3
