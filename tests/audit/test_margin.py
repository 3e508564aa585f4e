"""The margin search and the distribution-free alternative."""

import math

import numpy as np
import pandas as pd
import pytest

from probecommit.audit.margin import (
    GAMMA_GRID,
    distribution_free_margin,
    instance_optimism,
    optimism_margin,
    select_margin,
)


def test_grid_is_exactly_one_to_point_three_in_steps_of_point_02():
    assert len(GAMMA_GRID) == 36
    assert GAMMA_GRID[0] == 1.0 and GAMMA_GRID[-1] == 0.3  # exact floats, no drift
    assert list(GAMMA_GRID) == [round(1.0 - 0.02 * i, 2) for i in range(36)]
    assert 0.62 in GAMMA_GRID and 0.74 in GAMMA_GRID


def _episodes(pred, real, n=10):
    return pd.DataFrame({"instance_id": [f"i{j // 2}" for j in range(n)], "repeat": [j % 2 for j in range(n)],
                         "k": 1, "predicted": pred, "realized": real, "status": "ok"})


def test_picks_the_largest_gamma_satisfying_the_rule():
    calls = []

    def evaluate(gamma):
        calls.append(gamma)
        # Predicted failure rises as the window shrinks; realized stays at 0.51.
        return _episodes(1.2 - gamma, 0.51)

    res = select_margin(evaluate)
    assert res.gamma == 0.68 and res.satisfied  # 1.2 - 0.68 = 0.52 >= 0.51 > 1.2 - 0.70
    assert calls == [round(1.0 - 0.02 * i, 2) for i in range(17)]  # stops at the first (largest) success
    assert list(res.search["satisfied"]) == [False] * 16 + [True]


def test_rule_averages_over_all_episodes_and_budgets_and_need_not_be_monotone():
    def evaluate(gamma):
        ok = gamma in (0.9, 0.5)
        t = pd.concat([_episodes(0.2, 0.1 if ok else 0.3).assign(k=1), _episodes(0.2, 0.3).assign(k=2)])
        return t.assign(predicted=t["predicted"] + (0.11 if ok else 0.0))

    res = select_margin(evaluate, exhaustive=True)
    assert res.gamma == 0.9
    assert set(res.search.loc[res.search["satisfied"], "gamma"]) == {0.9, 0.5}
    assert len(res.search) == 36
    # Ties count as satisfied (mean predicted == mean realized).
    assert select_margin(lambda g: _episodes(0.3, 0.3)).gamma == 1.0


def test_no_gamma_satisfies_warns_and_returns_smallest():
    with pytest.warns(RuntimeWarning, match="no margin"):
        res = select_margin(lambda g: _episodes(0.1, 0.9))
    assert res.gamma == 0.3 and not res.satisfied


def test_failed_rows_are_ignored_by_the_rule():
    t = _episodes(0.5, 0.5)
    t.loc[0, ["realized", "status"]] = [np.nan, "failed"]
    assert select_margin(lambda g: t).gamma == 1.0


def test_distribution_free_margin_by_hand():
    # e_{i,k} = mean over repeats of realized - predicted.
    rows = []
    e = {("a", 1): [0.1, 0.3], ("a", 2): [0.0, 0.0], ("b", 1): [-0.2, 0.0], ("b", 2): [0.5, 0.5],
         ("c", 1): [0.0, 0.2], ("c", 2): [0.1, -0.1], ("d", 1): [0.4, 0.4], ("d", 2): [0.0, 0.2]}
    for (i, k), diffs in e.items():
        for r, d in enumerate(diffs):
            rows.append({"instance_id": i, "repeat": r, "k": k, "predicted": 0.2, "realized": 0.2 + d})
    t = pd.DataFrame(rows)
    opt = instance_optimism(t)
    assert opt.loc["a", 1] == pytest.approx(0.2) and opt.loc["b", 2] == pytest.approx(0.5)
    # Worst budget: a 0.2, b 0.5, c 0.1, d 0.4. M = 4, alpha = 0.2 -> q = 4 -> 0.5.
    assert distribution_free_margin(t, 0.2) == pytest.approx(0.5)
    # alpha = 0.5 -> q = ceil(2.5) = 3 -> third smallest = 0.4.
    assert distribution_free_margin(t, 0.5) == pytest.approx(0.4)
    # Too few instances for the level: +inf.
    assert math.isinf(distribution_free_margin(t[t.instance_id != "d"], 0.2))
    # From each part's optimism (whole instances per part), as the calibration keeps it chunk by chunk.
    parts = pd.concat([instance_optimism(t.loc[t.instance_id.isin(ids)]) for ids in (["c", "a"], ["d", "b"])])
    pd.testing.assert_frame_equal(parts.sort_index(), opt)
    assert optimism_margin(parts, 0.5) == distribution_free_margin(t, 0.5)
