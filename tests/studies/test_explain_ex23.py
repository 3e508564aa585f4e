"""E162, E163 (ex23): stratum weights, the weighted conformal threshold and margin, the fresh draws' and the
calibrated arm's post-stratified keys, and the rules, on hand cases (exact answers)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import probecommit.studies.claims as C
from probecommit.audit.conformal import conformal_quantile, conformal_rank
from probecommit.studies.explain import ex23_band as B
from probecommit.tasks.insertion.model import PAPER_DELTA_MM, TIP_RADIUS_MM

DESIGN = {"x_low": -10.0, "x_high": 10.0, "c_low": 0.7, "c_high": 1.3, "r": TIP_RADIUS_MM, "delta": PAPER_DELTA_MM,
          "repeats": 4.0}


def test_stratum_weights_bring_the_hit_share_to_p():
    hit = np.array([True, False, False, False])
    w = B.stratum_weights(hit, 0.5)
    assert w.tolist() == [2.0, 2.0 / 3, 2.0 / 3, 2.0 / 3]
    assert (w @ hit) / w.sum() == pytest.approx(0.5)
    assert B.stratum_weights(np.zeros(3, dtype=bool), 0.4).tolist() == [1.0, 1.0, 1.0]  # nothing to reweight


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(0.0, 1.5, allow_nan=False), min_size=1, max_size=40))
def test_equal_weights_give_the_conformal_quantile(scores):
    rank = conformal_rank(len(scores), 0.2)
    assert B.weighted_threshold(np.array(scores), np.ones(len(scores)), rank) == conformal_quantile(scores, 0.2)


def test_weighted_threshold_hand_case():
    # Four scores, rank 3 of 4: the level is 0.75. Weighting the smallest up moves the threshold down, the largest up
    # moves it up.
    s = np.array([0.1, 0.2, 0.3, 0.4])
    assert B.weighted_threshold(s, np.ones(4), 3) == 0.3
    assert B.weighted_threshold(s, np.array([3.0, 1.0, 1.0, 1.0]), 3) == 0.3  # cdf 0.5, 0.667, 0.833
    assert B.weighted_threshold(s, np.array([6.0, 1.0, 1.0, 1.0]), 3) == 0.2  # cdf 0.667, 0.778
    assert B.weighted_threshold(s, np.array([1.0, 1.0, 1.0, 3.0]), 3) == 0.4  # cdf 1/6, 1/3, 1/2, 1
    assert B.weighted_threshold(s, np.ones(4), 5) == float("inf")


def _margin_rows():
    # One budget, two trajectories (one hit). gamma 1.0: the hit trajectory is optimistic by 1, the other not;
    # gamma 0.8: both exact.
    return pd.DataFrame({"gamma": [1.0, 1.0, 0.8, 0.8], "k": 1, "hit": [True, False, True, False],
                         "predicted": [0.0, 0.5, 1.0, 0.0], "realized": [1.0, 0.0, 1.0, 0.0]})


def test_weighted_margin_depends_on_the_band_weight():
    rows = _margin_rows()
    # Unweighted (p = the share 0.5): at 1.0 predicted 0.5 < realized 1.0 -> 0.8.
    assert B.weighted_margin(rows, {1: (0.5, 0.5)}, [1.0, 0.8]) == (0.8, True)
    # The hit stratum weighted down to p = 0.2: predicted 0.8 * 0.5 = 0.4 >= realized 0.2 -> 1.0.
    assert B.weighted_margin(rows, {1: (0.2, 0.2)}, [1.0, 0.8]) == (1.0, True)
    # Nothing satisfies: the smallest margin, flagged.
    never = rows.assign(predicted=0.0)
    assert B.weighted_margin(never, {1: (0.5, 0.5)}, [1.0, 0.8]) == (0.8, False)


def _design_columns(frame: pd.DataFrame) -> pd.DataFrame:
    return frame.assign(**DESIGN)


def test_draw_keys_post_stratify_each_draw():
    # Two draws at k = 1, two trajectories each: one hit (optimism 1), one not (0). At p the standardized optimism
    # is p exactly whatever the draw's share; the raw one is the share.
    rows = []
    for draw, hits in (("d0", [True, False]), ("d1", [True, False, False, False])):
        for i, h in enumerate(hits):
            rows.append({"draw": draw, "instance_id": f"{draw}{i}", "repeat": 0, "k": 1, "realized": float(h),
                         "predicted": 0.0, "covered": True, "escaped": False, "hit": h})
    out = B.draw_keys(pd.DataFrame(rows), {1: (0.3, 0.6)} | {k: (0.3, 0.6) for k in B.BUDGETS})
    assert out["count"] == 2
    assert out["optimism_std.min.k1"] == pytest.approx(0.3) and out["optimism_std.max.k1"] == pytest.approx(0.3)
    assert out["optimism.min.k1"] == 0.25 and out["optimism.max.k1"] == 0.5
    assert out["share.min.k1"] == 0.25 and out["share.max.k1"] == 0.5


def _calibrated_rows(t2: float = 0.3) -> pd.DataFrame:
    """Four calibration instances (scores at k = 2; two exposed), margin rows at gammas 1.0 and 0.8, and test rows
    committed at the weighted threshold and the weighted margin."""
    probs = B._probabilities(_design_columns(pd.DataFrame({"x": [0]})))
    score = pd.DataFrame({"part": "score", "instance_id": list("abcd"), "k": 2, "score": [0.1, 0.2, 0.3, 0.4],
                          "hit": [False, False, True, True], "rank": 3})
    t = B.thresholds(score, probs, 3)["weighted"][2]
    margin = _margin_rows().assign(part="margin", k=2, instance_id=list("abab"), repeat=0, threshold=t)
    gamma, _ = B.weighted_margin(margin, probs, [1.0, 0.8])
    test = pd.DataFrame({"part": "test", "instance_id": list("wxyz"), "repeat": 0, "k": 2,
                         "hit": [True, False, False, False], "predicted": 0.0, "realized": [1.0, 0.0, 0.0, 0.0],
                         "gamma": gamma, "threshold": t})
    return _design_columns(pd.concat([score, margin, test], ignore_index=True)), probs, t, gamma


def test_calibrated_keys_hand_case():
    rows, probs, t, gamma = _calibrated_rows()
    p2, big_p2 = probs[2]
    # Instance weights at k = 2: exposed (share 0.5) get P/0.5, the rest (1 - P)/0.5; P > 0.5 moves the level's
    # mass toward the exposed (larger) scores.
    w = np.array([1 - big_p2, 1 - big_p2, big_p2, big_p2]) / 0.5
    cdf = np.cumsum(w) / w.sum()
    assert t == [0.1, 0.2, 0.3, 0.4][int(np.searchsorted(cdf, 0.75 - 1e-12))]
    out = B.keys(rows, dict(resamples=50, seed=1))
    assert out["calibrated.t_plain.k2"] == 0.3 and out["calibrated.t_weighted.k2"] == t
    assert out["calibrated.gamma"] == gamma and out["calibrated.rank"] == 3
    # Test: one hit trajectory of four with optimism 1, the rest 0: raw 0.25, standardized p_2 exactly.
    assert out["calibrated.optimism.k2"] == 0.25 and out["calibrated.share.k2"] == 0.25
    assert out["calibrated.optimism_std.k2"] == pytest.approx(p2)
    assert out["calibrated.cal_share_instance.k2"] == 0.5 and out["calibrated.p_design_instance.k2"] == big_p2


def test_keys_refuse_rows_committed_at_another_threshold():
    rows, *_ = _calibrated_rows()
    rows.loc[rows["part"] == "test", "threshold"] = 0.9
    with pytest.raises(ValueError, match="weighted t_k"):
        B.keys(rows, dict(resamples=10, seed=1))


def _lookup(values: dict[str, float]):
    return lambda key: values[key] if not key.startswith("paper:") else C.paper_values.value(key[6:])


def test_e162_rule_is_the_paper_inside_the_draws_standardized_range():
    e = C.EXPERIMENTS["E162"]
    base = {name: 0.2 for name in e.keys}
    p = C.paper_values.value("tab:audit.optimism_original.2")
    assert e.supports({**base, "lo": p - 0.01, "hi": p + 0.01})
    assert not e.supports({**base, "lo": p + 0.001, "hi": p + 0.05})


@pytest.mark.parametrize("k", [2, 3])
def test_e163_rule_needs_the_paper_inside_and_a_light_test_draw(k):
    e = C.EXPERIMENTS[f"E163[optimism calibrated k={k}]"]
    p = C.paper_values.value(f"tab:audit.optimism_calibrated.{k}")
    base = {name: 0.0 for name in e.keys} | {"lo": p - 0.01, "hi": p + 0.01, "sh": 0.2, "pd": 0.3}
    assert e.supports(base)
    assert not e.supports({**base, "sh": 0.31})
    assert not e.supports({**base, "hi": p - 0.001})


def test_table_iii_names_e162_and_e163_for_the_uncovered_cells():
    claim = next(c for c in C.CLAIMS if c.id == "tab:audit")
    spoken = dict(C.explanations(claim))
    assert spoken["E162"] == ("optimism original k=2",)
    assert spoken["E163[optimism calibrated k=2]"] == ("optimism calibrated k=2",)
    assert spoken["E163[optimism calibrated k=3]"] == ("optimism calibrated k=3",)
