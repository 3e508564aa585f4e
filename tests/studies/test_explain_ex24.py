"""E168-E170 (ex24): the tap-aware jitter kernel, the per-tap bands, the weighted AUC and its post-stratification,
the split of escapes by cause, the keys and the rules on hand cases (exact answers)."""

from __future__ import annotations

from itertools import product

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import probecommit.studies.claims as C
from probecommit.core.belief import ParticleFilter, jitter_resampled
from probecommit.studies.explain import ex21_band
from probecommit.studies.explain import ex24_band as B
from tests.studies.two_levels import TwoLevels, tap_batch


def test_tap_kernel_hand_cases():
    particles = np.array([[[0.0], [1.0], [2.0]]])
    parents, rows, noise = np.array([[0, 0, 2]]), np.array([0]), np.ones((1, 3, 1))
    scale, low, high = np.array([0.25]), np.array([-5.0]), np.array([5.0])
    tap1 = B._TapKernel(jitter_resampled, "tap1_unjittered")
    assert tap1(particles, rows, parents, noise, scale, low, high)[0, :, 0].tolist() == [0.0, 0.0, 2.0]
    tap1.tap = 2  # every later resampling is jittered as stated
    assert tap1(particles, rows, parents, noise, scale, low, high)[0, :, 0].tolist() == [0.25, 0.25, 2.25]
    var = B._TapKernel(jitter_resampled, "variance")  # sqrt(0.25) = 0.5
    assert var(particles, rows, parents, noise, scale, low, high)[0, :, 0].tolist() == [0.5, 0.5, 2.5]
    stated = B._TapKernel(jitter_resampled, "stated")
    assert stated(particles, rows, parents, noise, scale, low, high)[0, :, 0].tolist() == [0.25, 0.25, 2.25]


def test_taps_stated_is_ex21s_and_tap1_differs_only_where_tap1_resampled():
    pf = ParticleFilter.gaussian(TwoLevels(0.25), 0.5, n_particles=64)
    # trajectory 0 reads the pocket at tap 1 (resamples there), trajectory 1 reads top (no resampling at tap 1)
    batch = tap_batch([[0.0, 0.5, 3.0], [4.5, 0.0, 2.0]], [[0.1, 0.0, 10.0], [10.0, 0.2, 9.9]])
    rngs = lambda: [np.random.default_rng(i) for i in range(2)]  # noqa: E731
    ours = list(ex21_band._log_space(pf, "stated", batch, rngs(), 3))
    stated = list(B.taps(pf, "stated", batch, rngs(), 3))
    for a, b in zip(ours, stated):
        assert np.array_equal(a[1], b[1]) and np.array_equal(a[3], b[3])
    tap1 = list(B.taps(pf, "tap1_unjittered", batch, rngs(), 3))
    assert stated[0][2].tolist() == [True, False]
    assert not np.array_equal(tap1[0][1][0], stated[0][1][0])  # the copies of tap 1's resampling stay unjittered
    assert np.array_equal(tap1[0][1][1], stated[0][1][1])
    copies = stated[0][4][1][0, :, 0]
    assert set(np.round(tap1[0][1][0, :, 0], 12)) <= set(np.round(copies, 12))
    first = list(B.taps(pf, "first_unjittered", batch, rngs(), 3))  # E151's: each trajectory's first resampling
    assert np.array_equal(first[0][1][0], tap1[0][1][0])


def test_tap_bands_hand_case():
    # hg 4, inner -1, outer 1: band where 3 <= |u - x| < 5
    u = np.array([[0.0, 6.0], [0.0, 10.0]])
    got = B.tap_bands(u, np.array([4.0, 2.0]), np.array([4.0, 4.0]), -1.0, 1.0)
    assert got.tolist() == [[True, False], [False, False]]
    assert B.tap_bands(np.array([[1.0], [9.0]]), np.array([5.0, 5.0]), np.array([4.0, 4.0]), -1.0, 1.0).tolist() == [
        [True], [True]]


def test_weighted_auc_hand_cases():
    # positives 2, 1 against negatives 1, 0: (2 > 1) + (2 > 0) + (1 = 1) / 2 + (1 > 0) = 3.5 of 4
    s, y = np.array([2.0, 1.0, 1.0, 0.0]), np.array([True, True, False, False])
    assert B.weighted_auc(s, y, np.ones(4)) == pytest.approx(0.875)
    # weight 3 on the negative at 1: (3 + 1 + 1.5 + 1) / (2 x 4)
    assert B.weighted_auc(s, y, np.array([1.0, 1.0, 3.0, 1.0])) == pytest.approx(6.5 / 8)
    assert B.weighted_auc(np.array([np.inf, 1.0]), np.array([True, False]), np.ones(2)) == 1.0
    assert np.isnan(B.weighted_auc(s, np.zeros(4, bool), np.ones(4)))


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 3), st.booleans(), st.integers(1, 3)), min_size=2, max_size=12))
def test_weighted_auc_is_the_pairwise_sum(cases):
    s, y, w = (np.array(c, dtype=float if i != 1 else bool) for i, c in enumerate(zip(*cases)))
    if not y.any() or y.all():
        assert np.isnan(B.weighted_auc(s, y, w))
        return
    num = sum(w[i] * w[j] * ((s[i] > s[j]) + 0.5 * (s[i] == s[j])) for i, j in product(np.flatnonzero(y),
                                                                                       np.flatnonzero(~y)))
    assert B.weighted_auc(s, y, w) == pytest.approx(num / (w[y].sum() * w[~y].sum()))


def _part() -> pd.DataFrame:
    return pd.DataFrame({"draw": "a", "in_band": [True, False, False, False],
                         "escaped_final": [True, True, False, False], "surprise_k1": [3.0, 0.1, 0.2, 0.05]})


def test_post_stratified_auc():
    part = _part()
    # p = the draw's own exposure (1/4): the unweighted AUC, (1 + 1 + 0 + 1) / 4
    assert B.post_stratified_auc(part, 0.25) == pytest.approx(0.75)
    # p = 1/2: the band escape weighs 2, the others 2/3: (2 (2/3 + 2/3) + (2/3)(0 + 2/3)) / ((2 + 2/3)(4/3))
    assert B.post_stratified_auc(part, 0.5) == pytest.approx((8 / 3 + 4 / 9) / (32 / 9))
    assert np.isnan(B.post_stratified_auc(part.assign(in_band=False), 0.5))


def test_decomposition():
    part = pd.DataFrame({"draw": ["a", "a", "a", "b", "b"], "escaped_final": [True, True, True, True, False],
                         "in_band": [True, True, False, False, True],
                         "band_at_first_resample": [True, False, True, False, True]})
    out = B.decomposition(part, ["a", "b"])
    assert (out["a.escapes.band1"], out["a.escapes.first_resample_band"], out["a.escapes.other"]) == (2, 1, 0)
    assert (out["b.escapes.band1"], out["b.escapes.first_resample_band"], out["b.escapes.other"]) == (0, 0, 1)
    assert (out["all.escapes.band1"], out["all.escapes.other"]) == (2, 1)


def _rows() -> pd.DataFrame:
    base = {"instance_id": ["p", "q", "r", "s"], "repeat": [0, 0, 0, 0], "in_band": [True, True, False, False],
            "surprise_k1": [3.0, 3.0, 0.1, 0.2], "surprise_final": [3.0, 3.0, 0.1, 4.0],
            "escaped_k1": [True, False, False, False], "first_resample_tap": [1, 1, 3, 0],
            "band_at_first_resample": [True, True, True, False], "stored_escaped_final": [True, False, False, True],
            "first_tap": -12.0, "x_low": -10.0, "x_high": 10.0, "c_low": 0.7, "c_high": 1.3, "tip_radius": 1.2,
            "sim_offset": 0.905}
    parts = []
    for reading in B.READINGS:
        esc = [True, False, False, True] if reading == "stated" else [True, True, True, False]
        for draw in ("b_test", "a"):
            parts.append(pd.DataFrame({**base, "reading": reading, "draw": draw, "escaped_final": esc}))
    return pd.concat(parts, ignore_index=True)


def test_keys_exact():
    out = B.keys(_rows(), resamples=20, seed=0)
    assert out["draws"] == 2 and out["stated_reproduces_stored"] == 1
    assert out["p_band"] == pytest.approx(2.105 / 20)  # the band lies inside the prior box for every c
    assert out["stated.b_test.n_escaped"] == 2 and out["tap1_unjittered.share.min"] == 1.0
    assert out["stated.b_test.auc_k1"][0] == pytest.approx(0.625)
    assert (out["tap1_unjittered.all.escapes.band1"], out["tap1_unjittered.all.escapes.first_resample_band"]) == (4, 2)
    assert out["stated.all.escapes.other"] == 2 and out["b_test.exposure"] == 0.5
    assert out["exposure.min"] == out["exposure.max"] == 0.5
    # exposure 1/2 against p ~ 0.105: band rows weigh 0.21, the others 1.79; escapes p (band, 3.0) and s (0.2)
    # against q (band, 3.0) and r (0.1): (0.21 (0.5 x 0.21 + 1.79) + 1.79 (0 + 1.79)) / ((0.21 + 1.79)(0.21 + 1.79))
    p = out["p_band"]
    wb, wo = p / 0.5, (1 - p) / 0.5
    want = (wb * (0.5 * wb + wo) + wo * wo) / ((wb + wo) ** 2)
    assert out["stated.b_test.auc_k1_post"] == pytest.approx(want)
    assert out["stated.auc_k1_post.min"] == out["stated.auc_k1_post.max"] == pytest.approx(want)
    broken = _rows().assign(stored_escaped_final=False)
    assert B.keys(broken, resamples=20, seed=0)["stated_reproduces_stored"] == 0


def test_rules():
    p1 = C._pv("T36-surprise.auc_k1")
    base = {"w0": 1, "imp": 0.9, "plo": 0.4, "phi": 0.6}
    for r in ("stated", "first_unjittered", *C.EX24_MODES.values()):
        base.update({f"{r}slo": 0.1, f"{r}shi": 0.3, f"{r}alo": 0.4, f"{r}ahi": 0.6})
    e168, e169, e170 = (C.EXPERIMENTS[n] for n in ("E168", "E169", "E170"))
    assert not e168.supports(base) and not e169.supports(base) and not e170.supports(base)
    held = {**base, "tap1_unjitteredslo": 0.8, "tap1_unjitteredshi": 0.95, "tap1_unjitteredahi": p1 + 0.01}
    assert e168.supports(held) and not e169.supports(held)
    assert not e168.supports({**held, "w0": 0}) and not e168.supports({**held, "imp": 0.99})
    assert not e168.supports({**held, "tap1_unjitteredahi": p1 - 0.01})
    var = {**base, "varianceslo": 0.8, "varianceshi": 0.95, "varianceahi": p1 + 0.01}
    assert e169.supports(var) and not e168.supports(var)
    assert e170.supports({**base, "phi": p1 + 0.01}) and not e170.supports({**base, "plo": p1 + 0.01, "phi": 0.9})
    t36 = next(c for c in C.CLAIMS if c.id == "T36-surprise")
    assert all(dict(e for e in t36.explain if isinstance(e, tuple))[n] == ("k=1",) for n in ("E168", "E169", "E170"))
