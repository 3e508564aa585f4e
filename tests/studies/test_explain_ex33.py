"""ex33's E199, E200 (the margin items under a placement error on the committed aim): hand cases with exact answers,
same-seed equality, a vanishing error giving the stored outcomes, the rules at their edges, verify's round trip."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import norm

from probecommit.studies import claims
from probecommit.studies.explain import ex33_aim as ex33
from probecommit.studies.paper_values import value
from probecommit.tasks.insertion.model import capture_half_width

#: Two instances' truths: w(c) = 0.6 c + 1.1 is 1.7 mm for a, 1.5 mm for b (c = 1 and 2/3).
TRUTHS = pd.DataFrame({"true_x_hole": [0.0, 5.0], "true_c": [1.0, 2.0 / 3.0]}, index=pd.Index(["a", "b"],
                                                                                                 name="instance_id"))


def test_failure_probability_hand_cases():
    w = float(capture_half_width(1.0))  # 1.7 up to rounding; the edge itself fails (the open window)
    assert ex33.failure_probability(np.array([0.0, w - 0.01, w, -w]), 0.0, 1.0, 0.0).tolist() == [0, 0, 1, 1]
    centred = ex33.failure_probability(np.array([0.0]), 0.0, 1.0, 0.5)[0]
    assert math.isclose(centred, 2 * norm.cdf(-w / 0.5), rel_tol=1e-12)
    # At the window's edge half the landings fall outside, plus the far edge's tail.
    edge = ex33.failure_probability(np.array([w]), 0.0, 1.0, 0.5)[0]
    assert math.isclose(edge, 0.5 + norm.cdf(-2 * w / 0.5), rel_tol=1e-12)
    far = ex33.failure_probability(np.array([-10.0, 10.0]), 0.0, 1.0, 0.5)
    assert far.tolist() == [1.0, 1.0]
    assert math.isclose(ex33.failure_probability(np.array([0.3]), 0.0, 1.0, 0.4)[0],
                        ex33.failure_probability(np.array([-0.3]), 0.0, 1.0, 0.4)[0], rel_tol=1e-12)


def _table(values: dict[tuple[str, int], tuple[float, float, float]], failed: tuple[str, int] | None = None):
    """One gamma's table at k = 5: (instance, repeat) -> (predicted, realized, aim)."""
    return pd.DataFrame([{"instance_id": i, "repeat": r, "k": 5, "status": "failed" if (i, r) == failed else "ok",
                          "predicted": p, "realized": f, "action": a} for (i, r), (p, f, a) in values.items()])


def _grid() -> ex33.AimGrid:
    """Two gammas. At 1.00 instance a's aims miss its window (realized 1, predicted 0.25): optimistic; at 0.98 every
    aim is centred (realized 0, predicted 0.5). Instance b is centred at both."""
    hi = _table({("a", 0): (0.25, 1.0, 3.0), ("a", 1): (0.25, 1.0, 3.0), ("b", 0): (0.25, 0.0, 5.0),
                 ("b", 1): (0.25, 0.0, 5.0)})
    lo = _table({("a", 0): (0.5, 0.0, 0.0), ("a", 1): (0.5, 0.0, 0.0), ("b", 0): (0.5, 0.0, 5.0),
                 ("b", 1): (0.5, 0.0, 5.0)}, failed=("b", 1))
    return ex33.AimGrid([1.0, 0.98], [hi, lo], TRUTHS)


def test_aim_grid_hand_case_failed_rows_masked_and_q_zero_is_stored():
    g = _grid()
    assert g.episodes["instance_id"].tolist() == ["a", "a", "b", "b"]
    assert g.ok.tolist() == [[1, 1, 1, 1], [1, 1, 1, 0]]
    assert g.aim[0].tolist() == [3.0, 3.0, 5.0, 5.0] and g.p[1].tolist() == [0.5, 0.5, 0.5, 0.0]
    assert g.q(0.0) is g.r and g.r[0].tolist() == [1.0, 1.0, 0.0, 0.0]
    q = g.q(0.5)
    assert q[1, 3] == 0.0 and math.isclose(q[1, 0], 2 * norm.cdf(-1.7 / 0.5), rel_tol=1e-12)
    assert g.member(np.array(["b"])).tolist() == [False, False, True, True]


def test_stop_rows_takes_the_largest_passing_gamma():
    g = _grid()
    a, b = g.member(np.array(["a"])), g.member(np.array(["b"]))
    # On a's episodes 1.00 fails (2 > 0.5) and 0.98 passes (0 <= 1): held-out b at 0.98 is 0 - 0.5 (one ok episode).
    assert ex33.stop_rows(g, a, b, g.r) == {"gamma": 0.98, "cal": -0.5, "held": -0.5, "optimistic": 0.0}
    # On b's episodes 1.00 passes: held-out a there is 1 - 0.25, optimistic.
    assert ex33.stop_rows(g, b, a, g.r) == {"gamma": 1.0, "cal": -0.25, "held": 0.75, "optimistic": 1.0}


def test_split_rows_same_seed_equal_and_modes():
    g = _grid()
    one = ex33.split_rows(g, 4, np.array(["a"]), np.array(["b"]), 0.9, np.random.default_rng(3), 5)
    two = ex33.split_rows(g, 4, np.array(["a"]), np.array(["b"]), 0.9, np.random.default_rng(3), 5)
    assert one == two
    assert [(r["mode"], r["sigma"]) for r in one[:4]] == [("mean", s) for s in (*ex33.BESIDE, ex33.SIGMA)]
    assert [r["draw"] for r in one[4:]] == list(range(5)) and all(r["mode"] == "drawn" for r in one[4:])
    assert one[0]["gamma"] == 0.98 and all(r["index"] == 4 and r["level"] == 0.9 for r in one)


@settings(max_examples=15, deadline=None)
@given(st.integers(min_value=0, max_value=2 ** 31 - 1))
def test_a_vanishing_error_draws_the_stored_outcomes(seed):
    """Aims at least 0.05 mm from every window edge and an error of SD 1e-4 mm: every failure probability is 0 or 1,
    so every drawn and noise-averaged row is the stored one (the window test is MuJoCo's, decisions.md)."""
    rng = np.random.default_rng(seed)
    ids = [f"i{j}" for j in range(6)]
    truths = pd.DataFrame({"true_x_hole": rng.uniform(-5, 5, 6), "true_c": rng.uniform(0.7, 1.3, 6)},
                          index=pd.Index(ids, name="instance_id"))
    tables = []
    for gamma in (1.0, 0.98, 0.96):
        rows = {}
        for i, (x, c) in zip(ids, truths.to_numpy()):
            w = 0.6 * c + 1.1
            for r in range(2):
                aim = x + float(rng.choice([-1, 1])) * (w + float(rng.choice([-0.3, -0.05, 0.05, 0.3])))
                rows[(i, r)] = (float(rng.uniform(0, 1)) * (1.2 - gamma), float(abs(aim - x) >= w), aim)
        tables.append(_table(rows))
    g = ex33.AimGrid([1.0, 0.98, 0.96], tables, truths)
    assert np.array_equal(ex33.failure_probability(g.aim, g.x[None, :], g.c[None, :], 1e-4), g.r)
    old, ex33.SIGMA = ex33.SIGMA, 1e-4
    try:
        rows = ex33.split_rows(g, 0, np.array(ids[:3]), np.array(ids[3:]), 0.5, np.random.default_rng(seed), 3)
    finally:
        ex33.SIGMA = old
    keep = ("gamma", "cal", "held", "optimistic")
    vanishing = [r for r in rows if r["sigma"] in (0.0, 1e-4)]  # the stored outcomes, the draws, their mean
    assert len(vanishing) == 5 and all({k: r[k] for k in keep} == {k: rows[0][k] for k in keep} for r in vanishing)


def test_cells_replace_ok_realized_by_the_failure_probability():
    table = pd.DataFrame({"method": "probe_robust", "variant": "deployed", "instance_id": ["a", "a", "b", "b"],
                          "repeat": [0, 1, 0, 1], "k": 2, "status": ["ok", "ok", "ok", "failed"],
                          "predicted": [0.1, 0.1, 0.2, 0.2], "realized": [0.0, 0.0, 1.0, 1.0],
                          "action": [0.0, 1.7, 5.0, 5.0], "covered": True, "escaped": False})
    plain = ex33.cells(table, TRUTHS, 0.6, 0.0, [2], 50, 7)
    assert plain[["sigma", "gamma", "k"]].iloc[0].tolist() == [0.0, 0.6, 2]
    assert math.isclose(plain["optimism"].iloc[0], (2 * (0.0 - 0.1) + (1.0 - 0.2)) / 3)  # over the ok episodes
    noisy = ex33.cells(table, TRUTHS, 0.6, 0.5, [2], 50, 7)
    q = ex33.failure_probability(np.array([0.0, 1.7, 5.0]), np.array([0.0, 0.0, 5.0]), np.array([1.0, 1.0, 2 / 3]), 0.5)
    assert math.isclose(noisy["optimism"].iloc[0], (q.sum() - 0.4) / 3, rel_tol=1e-12)


def _share(flags: list[float]) -> pd.DataFrame:
    n = len(flags)
    drawn = pd.DataFrame({"part": "share", "index": range(n), "level": 0.5, "mode": "drawn", "sigma": ex33.SIGMA,
                          "draw": 0, "gamma": 0.5, "cal": -0.01, "held": [0.1 if f else -0.1 for f in flags],
                          "optimistic": flags})
    mean = [drawn.assign(mode="mean", sigma=s, draw=-1, optimistic=0.0, held=-0.1) for s in (*ex33.BESIDE, ex33.SIGMA)]
    return pd.concat([drawn, *mean], ignore_index=True)


def test_e199_rule_is_the_claims_tolerance_on_the_drawn_share():
    for ones, holds in ((27, 1.0), (37, 1.0), (26, 0.0), (38, 0.0)):
        keys = ex33.share_keys(_share([1.0] * ones + [0.0] * (50 - ones)))
        assert keys["holds"] == holds, (ones, keys["share"])
        assert keys["splits"] == 50 and keys["draws"] == 1 and keys["plain.mean_share"] == 0.0
        assert math.isclose(keys["s010.mean_held"], -0.1) and keys["mean_gamma"] == 0.5 and keys["sigma"] == 0.5


def _cells(k2: tuple[float, float], k3: tuple[float, float]) -> pd.DataFrame:
    frames = []
    for s in (*ex33.BESIDE, ex33.SIGMA):
        frames.append(pd.DataFrame({"part": "cells", "sigma": s, "gamma": 0.56, "k": [2, 3],
                                    "optimism": [sum(k2) / 2, sum(k3) / 2], "lo": [k2[0], k3[0]],
                                    "hi": [k2[1], k3[1]]}))
    return pd.concat(frames, ignore_index=True)


def test_e200_rule_needs_both_paper_cells_inside():
    p2, p3 = (float(value(f"tab:audit.optimism_calibrated.{k}")) for k in (2, 3))
    keys = ex33.table_keys(_cells((p2 - 0.01, p2 + 0.01), (p3 - 0.01, p3 + 0.01)))
    assert keys["holds"] == 1.0 and keys["gamma"] == 0.56 and keys["plain.gamma"] == 0.56
    assert math.isclose(keys["s025.optimism.k3"], p3) and keys["sigma"] == 0.5
    assert ex33.table_keys(_cells((p2 - 0.01, p2 + 0.01), (p3 + 0.001, p3 + 0.1)))["holds"] == 0.0
    assert ex33.table_keys(_cells((p2 - 0.1, p2 - 0.001), (p3 - 0.01, p3 + 0.01)))["holds"] == 0.0


def test_e199_e200_registered_for_their_comparisons():
    for number in ("E199", "E200"):
        e = claims.EXPERIMENTS[number]
        assert e.supports({"ok": 1.0}) and not e.supports({"ok": 0.0})
    t14 = next(c for c in claims.CLAIMS if c.id == "T14-resplits")
    assert ("E199", ("margin optimistic",)) in claims.explanations(t14)
    audit = next(c for c in claims.CLAIMS if c.id == "tab:audit")
    assert ("E200", ("optimism calibrated k=2", "optimism calibrated k=3")) in claims.explanations(audit)


def test_verify_recomputes_the_group_from_its_stored_rows(tmp_path):
    from probecommit.report import recompute

    assert ("ex33_aim", ex33.STORED, "ex33_aim") in recompute.STORED_SUMMARIES
    p2, p3 = (float(value(f"tab:audit.optimism_calibrated.{k}")) for k in (2, 3))
    rows = pd.concat([_share([1.0, 0.0]), _cells((p2, p2), (p3, p3))], ignore_index=True)
    rows.to_parquet(tmp_path / ex33.STORED)
    again = ex33.summary(pd.read_parquet(tmp_path / ex33.STORED))
    assert again == ex33.summary(rows) and again["share.share"] == 0.5 and again["table.holds"] == 1.0
    keys = set(claims.EXPERIMENTS["E199"].keys.values()) | set(claims.EXPERIMENTS["E200"].keys.values())
    assert {k.split("ex33_aim.", 1)[1] for k in keys} <= set(again)
