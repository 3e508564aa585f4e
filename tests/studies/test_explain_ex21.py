"""E150/E151 (ex21): the jitter kernel's modes, the linear-space weights against ours, the keys and the rules on hand
cases (exact answers)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import probecommit.studies.claims as C
from probecommit.core.belief import ParticleFilter, jitter_resampled
from probecommit.studies.explain import ex21_band as B
from tests.studies.two_levels import TwoLevels, tap_batch


def _filter(n: int = 8) -> ParticleFilter:
    return ParticleFilter.gaussian(TwoLevels(), 0.5, n_particles=n)


def test_copies_modes_hand_cases():
    particles = np.array([[[0.0], [1.0], [2.0]]])
    parents, rows = np.array([[0, 0, 2]]), np.array([0])
    noise = np.ones((1, 3, 1))
    scale, low, high = np.array([0.5]), np.array([-5.0]), np.array([5.0])
    stated = B._Copies(jitter_resampled, "stated", 1)
    assert stated(particles, rows, parents, noise, scale, low, high)[0, :, 0].tolist() == [0.5, 0.5, 2.5]
    assert stated.copies[1][0, :, 0].tolist() == [0.0, 0.0, 2.0]  # the copies before their jitter
    first = B._Copies(jitter_resampled, "first", 1)
    assert first(particles, rows, parents, noise, scale, low, high)[0, :, 0].tolist() == [0.0, 0.0, 2.0]
    assert first(particles, rows, parents, noise, scale, low, high)[0, :, 0].tolist() == [0.5, 0.5, 2.5]
    nxt = B._Copies(jitter_resampled, "next", 1)
    out = nxt(particles, rows, parents, noise, scale, low, high)
    assert out[0, :, 0].tolist() == [0.0, 0.0, 2.0]
    assert nxt.move(out, scale, low, high)[0, :, 0].tolist() == [0.5, 0.5, 2.5]
    assert nxt.move(out, scale, low, high) is out  # nothing pending: no move


def test_contradicted_all():
    pf = _filter()
    particles = np.array([[[3.0], [4.0]], [[0.2], [4.0]]])
    got = B._contradicted_all(pf, particles, np.array([0.0, 0.0]), np.array([0.3, 0.3]))  # both read pocket
    assert got.tolist() == [True, False]


def test_linear_float64_equals_log_space_when_no_tap_contradicts_every_particle():
    pf, batch = _filter(64), tap_batch([[0.0, 2.0, -3.0]] * 3, [[0.1, 9.8, 10.2]] * 3)
    rngs = lambda: [np.random.default_rng(i) for i in range(3)]  # noqa: E731
    ours = list(B._log_space(pf, "stated", batch, rngs(), 3))
    lin = list(B._linear(pf, np.float64, batch, rngs(), 3))
    for a, b in zip(ours, lin):
        assert a[0] == b[0] and np.array_equal(a[2], b[2]) and np.allclose(a[1], b[1]) and np.allclose(a[3], b[3])


def test_a_tap_contradicting_every_particle():
    # every particle far from 0 but one tap reads the pocket there: log space keeps the weights, linear resets;
    # float32 gives +inf surprise (the predictive density underflows), float64 a finite one
    pf, batch = _filter(4), tap_batch([[0.0]], [[0.0]])
    state = pf.initial([np.random.default_rng(0)])
    assert np.all(np.abs(state.particles[0, :, 0]) > 1.0) or pytest.skip("a particle near 0 in this draw")
    [(_, _, res64, s64, _, every)] = list(B._linear(pf, np.float64, batch, [np.random.default_rng(0)], 1))
    [(_, _, _, s32, _, _)] = list(B._linear(pf, np.float32, batch, [np.random.default_rng(0)], 1))
    assert every.tolist() == [True] and np.isfinite(s64[0]) and s32[0] == np.inf and not res64[0]


def _rows() -> pd.DataFrame:
    base = {"instance_id": ["p", "q", "r", "s"], "repeat": [0, 0, 0, 0], "in_band": [True, True, False, False],
            "surprise_k1": [3.0, 3.0, 0.1, 0.2], "surprise_final": [3.0, 3.0, 0.1, 4.0],
            "escaped_prejitter_k1": [True, True, False, False], "escaped_k1": [True, False, False, False],
            "hull_lo_k1": [-10.0, -10.0, 0.0, 0.0], "hull_hi_k1": [-7.0, -6.5, 1.0, 1.0],
            "copies_hi_k1": [-8.5, -8.5, 1.0, 1.0], "resampled_k1": [True, True, False, False],
            "hull_lo_final": [-10.0, -10.0, 0.0, 0.5], "hull_hi_final": [-7.0, -6.0, 1.0, 1.0],
            "all_contradicted_taps": [0, 0, 1, 0], "stored_escaped_final": [True, False, False, True]}
    parts = []
    for reading in B.READINGS:
        esc = [True, False, False, True] if reading != "first_unjittered" else [True, True, False, True]
        for draw in ("b_test", "a"):
            parts.append(pd.DataFrame({**base, "reading": reading, "draw": draw, "escaped_final": esc}))
    return pd.concat(parts, ignore_index=True)


def test_keys_exact():
    out = B.keys(_rows(), resamples=20, seed=0)
    assert out["draws"] == 2 and out["w0_reproduces_stored"] == 1
    assert out["stated.b_test.n_escaped"] == 2 and out["stated.b_test.n_band_escaped"] == 1
    assert out["stated.share.min"] == 0.5 and out["first_unjittered.share.max"] == 1.0
    # escaped p (3.0) and s (0.2) against q (3.0), r (0.1) at k = 1: pairs 0.5 + 1 + 0 + 1 of 4
    assert out["stated.b_test.auc_k1"][0] == pytest.approx(0.625) and out["stated.auc_k1.min"] == pytest.approx(0.625)
    assert out["stated.b_test.auc_final"][0] == pytest.approx(0.875)
    assert out["trace.b_test.band_share.prejitter_k1"] == 1.0 and out["trace.a.band_share.k1"] == 0.5
    assert out["trace.band.hull_unchanged_share"] == 0.5 and out["trace.band.n"] == 4
    assert out["trace.band.tail_reach_mm"] == pytest.approx(1.75) and out["trace.all_contradicted_taps"] == 2
    assert out["trace.band.all_contradicted_taps"] == 0
    broken = _rows().assign(stored_escaped_final=False)
    assert B.keys(broken, resamples=20, seed=0)["w0_reproduces_stored"] == 0


def test_rules():
    p1, p5 = C._pv("T36-surprise.auc_k1"), C._pv("T36-surprise.auc_k5")
    base = {"w0": 1, "imp": 0.9}
    for r in (*C.EX21_READINGS, "stated", "first_unjittered"):
        base.update({f"{r}slo": 0.1, f"{r}shi": 0.3, f"{r}alo": 0.4, f"{r}ahi": 0.6, f"{r}flo": 0.6, f"{r}fhi": 0.8})
    e1, e5 = C.EXPERIMENTS["E150[k=1]"], C.EXPERIMENTS["E150[k=5]"]
    assert not e1.supports(base) and not e5.supports(base)
    held = {**base, "move_nextslo": 0.8, "move_nextshi": 0.95, "move_nextahi": p1 + 0.01}
    assert e1.supports(held) and not e5.supports(held)  # k = 5 needs the paper's 0.54 in J1's span
    assert e5.supports({**held, "move_nextflo": p5 - 0.01})
    assert not e1.supports({**held, "w0": 0})
    ours = {**base, "statedslo": 0.8, "statedshi": 0.95, "statedahi": p1 + 0.01}
    assert not e1.supports(ours)  # ours is not a reading
    f1, f5 = C.EXPERIMENTS["E151[k=1]"], C.EXPERIMENTS["E151[k=5]"]
    removed = {**base, "first_unjitteredslo": 0.8, "first_unjitteredshi": 0.95, "first_unjitteredahi": p1 + 0.01}
    assert f1.supports(removed) and not f5.supports(removed)
    assert f5.supports({**removed, "first_unjitteredflo": p5 - 0.01})
    assert not f1.supports({**removed, "imp": 0.99})
