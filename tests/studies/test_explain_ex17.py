"""E126/E127 (ex17): the tie-break readings, the optimism decomposition, the first tap's band and the rules on
hand cases (exact answers)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import probecommit.studies.claims as C
from probecommit.studies.explain import ex17_band as B
from probecommit.studies.explain import ex17_tiebreak as T
from probecommit.tasks.insertion.model import PAPER_DELTA_MM, TIP_RADIUS_MM, half_gap


def test_tie_choice_hand_cases():
    scores = np.array([[0.2, 0.0, 0.0, 0.0, 0.3], [0.5, 0.4, 0.6, 0.4, 0.4]])
    cost = np.array([[3.0, 2.0, 1.0, 2.0, 3.0], [0.0, 5.0, 0.0, 1.0, 1.0]])
    assert T.tie_choice(scores, cost, "reference").tolist() == [2, 3]  # nearest; then the lowest index (3 before 4)
    assert T.tie_choice(scores, cost, "lowest").tolist() == [1, 1]
    assert T.tie_choice(scores, cost, "highest").tolist() == [3, 4]
    for u, want in ((0.0, [1, 1]), (0.5, [2, 3]), (0.999, [3, 4])):
        assert T.tie_choice(scores, cost, "uniform", np.full(2, u)).tolist() == want
    with pytest.raises(ValueError):
        T.tie_choice(scores, cost, "middle")


def test_reference_reading_is_the_executors_rule():
    from probecommit.core.executors import select_action

    rng = np.random.default_rng(5)
    scores = rng.integers(0, 4, size=(200, 41)) / 8.0
    cost = rng.random((200, 41))
    assert np.array_equal(T.tie_choice(scores, cost, "reference"), select_action(scores, cost))


def test_plateau_counts_and_width():
    grid = np.arange(-1.0, 1.5, 0.5)
    n, width = T.plateau(np.array([[0.2, 0.0, 0.1, 0.0, 0.3], [0.0, 0.1, 0.1, 0.1, 0.1]]), grid)
    assert n.tolist() == [2, 1] and width.tolist() == [1.0, 0.0]


def test_decomposition_adds_up_exactly():
    parts = T.decomposition([1, 0, 1], [0.25, 0.5, 0.0], [1, 1, 0], [0.5, 0.25, 0.125])
    assert parts["score"].tolist() == [0.25, -0.25, 0.125]
    assert parts["model"].tolist() == [0.0, -1.0, 1.0]
    assert parts["belief"].tolist() == [0.5, 0.75, -0.125]
    total = parts["score"] + parts["model"] + parts["belief"]
    assert total.tolist() == [0.75, -0.5, 1.0]  # realized - predicted


def test_realized_from_the_cache_else_the_analytic_window():
    # w(1) = 1.7 mm (0.6 + 1.1 in floats: a hair above): 1.75 fails, 1.5 succeeds
    depths = {(0.0, 1.0, 5.0): 15.0, (0.0, 1.0, 0.5): 2.0}
    realized, hit = T.realized_failure(np.zeros(4), np.ones(4), np.array([5.0, 0.5, 1.75, 1.5]), depths)
    assert realized.tolist() == [0.0, 1.0, 1.0, 0.0] and hit.tolist() == [True, True, False, False]


def _rows(opt_by_reading: dict[str, float]) -> pd.DataFrame:
    parts = []
    n = 40
    for reading, gap in opt_by_reading.items():
        for k in T.BUDGETS:
            realized = np.r_[np.ones(int(round(gap * n))), np.zeros(n - int(round(gap * n)))]
            parts.append(pd.DataFrame({
                "reading": reading, "instance_id": [f"i{i % 10}" for i in range(n)], "repeat": np.arange(n) // 10,
                "k": k, "aim": 0.0, "predicted": 0.0, "realized": realized, "from_cache": True, "fail_truth": realized,
                "posterior": 0.0, "escaped": False, "covered": True, "n_tied": 2, "plateau_mm": 0.5,
                "stored_realized": realized if reading == "reference" else np.nan,
                "stored_predicted": 0.0}))
    return pd.concat(parts, ignore_index=True)


def test_keys_select_the_first_reading_holding_every_budget():
    rows = _rows({"reference": 0.0, "lowest": 0.25, "highest": 0.5, "uniform": 0.25})
    boot = dict(resamples=50, seed=0)
    out = T.keys(rows, [0.25] * 5, boot)
    assert out["a0_reproduces_stored"] == 1 and out["predicted_same_every_reading"] == 1
    assert out["reference.optimism.k3"] == 0.0 and out["lowest.optimism.k3"] == pytest.approx(0.25)
    assert out["lowest.reproduces"] == 1 and out["highest.reproduces"] == 0 and out["selected"] == 2
    assert out["selected_mean_abs_optimism"] == pytest.approx(0.25)
    assert out["lowest.covered.model.k8"] == 0.0 and out["lowest.covered.belief.k8"] == pytest.approx(0.25)
    assert out["tied_share.k1"] == 1.0 and out["plateau_mm.k1"] == 0.5
    # our reading never selects itself; a failed replay check selects nothing
    assert T.keys(rows, [0.0] * 5, boot)["selected"] == 0
    broken = rows.assign(stored_realized=np.where(rows["reading"] == "reference", 1.0 - rows["realized"], np.nan))
    assert T.keys(broken, [0.25] * 5, boot)["selected"] == 0


def test_pocket_and_band_probabilities_of_the_first_tap():
    # c fixed at 1: hg = 4.6; pocket for x in (-12 - 5.505, -12 + 5.505) within [-10, 10]: 3.505 mm of 20
    assert B.p_pocket(-12.0, (-10, 10), (1.0, 1.0), PAPER_DELTA_MM, grid=3) == pytest.approx(3.505 / 20)
    from probecommit.studies.explain.ex14_escape import p_band
    assert p_band([-12.0], (-10, 10), (1.0, 1.0), half_gap, -TIP_RADIUS_MM, PAPER_DELTA_MM, grid=3) == pytest.approx(2.105 / 20)
    assert B.implied_share(0.1, 100, 10, 0.75) == pytest.approx(0.5)


def test_band_rows_and_keys():
    surprise = pd.DataFrame({"draw": ["b_test"] * 4 + ["a"] * 2, "instance_id": ["p", "q", "r", "s", "t", "t"],
                             "repeat": [0, 0, 0, 0, 0, 1], "escaped_final": [True, False, True, False, True, False],
                             "first_tap_pocket": [True, True, False, False, True, True]})
    # c = 1 (hg 4.6): the band at -12 is [-8.6, -6.495)
    truths = pd.DataFrame({"instance_id": list("pqrst"), "true_x_hole": [-8.0, -7.0, 3.0, -9.5, -6.6],
                           "true_c": [1.0] * 5})
    inputs = {"first_tap": -12.0, "x_low": -10.0, "x_high": 10.0, "c_low": 1.0, "c_high": 1.0, "sim_offset": PAPER_DELTA_MM}
    rows = B.band_rows(surprise, [truths], inputs)
    assert rows["in_band"].tolist() == [True, True, False, False, True, True]
    out = B.keys(rows, 100, 10, 0.75, ("b_test", "b_cal", "a"))
    assert out["draws"] == 2 and out["b_test.n_band"] == 2 and out["b_test.n_band_escaped"] == 1
    assert out["b_test.band_escaped_share"] == 0.5 and out["a.band_escaped_share"] == 0.5
    assert out["b_test.escapes_in_band"] == 0.5 and (out["share.min"], out["share.max"]) == (0.5, 0.5)
    assert out["p_band"] == pytest.approx(2.105 / 20) and out["expected_band"] == pytest.approx(100 * 2.105 / 20)


def test_rules():
    p = C._pv("tab:audit.optimism_original.8")
    e = C.EXPERIMENTS["E126[optimism original k=8]"]
    base = {f"{t}{i}": 0.0 for t in ("lo", "hi", "m") for i in range(1, 5)}
    assert e.supports({**base, "a0": 1, "sel": 2, "lo2": p - 0.1, "hi2": p + 0.1})
    assert not e.supports({**base, "a0": 0, "sel": 2, "lo2": p - 0.1, "hi2": p + 0.1})
    assert not e.supports({**base, "a0": 1, "sel": 0, "lo2": p - 0.1, "hi2": p + 0.1})
    assert not e.supports({**base, "a0": 1, "sel": 1, "lo1": p - 0.1, "hi1": p + 0.1})  # ours is not a reading
    q = C._pv("T12-calibrated-audit.optimism_original")
    t12 = C.EXPERIMENTS["E126[T12 original]"]
    assert t12.supports({**base, "a0": 1, "sel": 3, "m3": q + 0.04})
    assert not t12.supports({**base, "a0": 1, "sel": 3, "m3": q + 0.06})
    assert not t12.supports({**base, "a0": 1, "sel": 0, "m1": q})
    e127 = C.EXPERIMENTS["E127"]
    assert e127.supports({"imp": 0.5, "lo": 0.4, "hi": 0.6})
    assert not e127.supports({"imp": 0.8, "lo": 0.1, "hi": 0.3})
    assert not e127.supports({"imp": 1.2, "lo": 0.1, "hi": 1.5})
