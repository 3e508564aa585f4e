"""E112..E114 (ex14): the band probability, the readings' replay, the summaries and the rules on hand cases."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

import probecommit.studies.claims as C
from probecommit.core.belief import ParticleFilter, jitter_resampled
from probecommit.runner.inference import ProbeBatch, build_trace
from probecommit.studies.explain import ex14_escape as E
from probecommit.studies.explain import ex14_summary as S
from probecommit.tasks.insertion.model import PAPER_DELTA_MM, TIP_RADIUS_MM, InsertionModel, half_gap


def test_band_length_hand_cases():
    # a centred tap, constant half-gap 4: two sides [2.8, 4.905) of 2.105 mm each, inside the box
    assert E.band_length(0.0, np.array([4.0]), -1.2, 0.905, -10, 10)[0] == pytest.approx(4.21)
    # the tap at -12: only the side towards the box, [-9.2, -7.095)
    assert E.band_length(-12.0, np.array([4.0]), -1.2, 0.905, -10, 10)[0] == pytest.approx(2.105)
    # cut by the box edge: [8.8, 10.905) -> [8.8, 10]
    assert E.band_length(6.0, np.array([4.0]), -1.2, 0.905, -10, 10)[0] == pytest.approx(1.2 + 2.105)
    assert E.p_band([0.0], (-10, 10), (0.7, 1.3), lambda c: 0 * c + 4.0, -1.2, 0.905, grid=11) == pytest.approx(0.2105)


def test_band_probability_matches_monte_carlo():
    taps = InsertionModel.probe_grid[:, 0]
    exact = E.p_band(taps, (-10, 10), (0.7, 1.3), half_gap, -TIP_RADIUS_MM, PAPER_DELTA_MM)
    rng = np.random.default_rng(3)
    n = 400_000
    x, c, u = rng.uniform(-10, 10, n), rng.uniform(0.7, 1.3, n), rng.choice(taps, n)
    mc = E.in_band(u, x, half_gap(c), -TIP_RADIUS_MM, PAPER_DELTA_MM).mean()
    assert abs(exact - mc) < 4 * np.sqrt(exact * (1 - exact) / n)


def test_duplicates_reading_leaves_first_copies_unjittered():
    particles = np.arange(12, dtype=float).reshape(1, 6, 2)
    parents = np.array([[0, 0, 1, 3, 3, 3]])
    noise = np.ones((1, 6, 2))
    rec = E._Recorder(jitter_resampled, duplicates_only=True)
    out = rec(particles, np.array([0]), parents, noise, np.array([0.5, 0.5]), np.array([-100.0, -100.0]), np.array([100.0, 100.0]))
    copies = particles[0, parents[0]]
    first = np.array([True, False, True, True, False, False])
    assert np.array_equal(out[0, first], copies[first])
    assert np.array_equal(out[0, ~first], copies[~first] + 0.5)
    assert np.array_equal(rec.copies[1][0], copies)


def _beliefs(n_particles=256):
    model = InsertionModel()
    pf = ParticleFilter.gaussian(model, 0.5, n_particles=n_particles)
    truths = np.array([[-8.0, 1.0], [2.0, 0.8], [7.5, 1.2]])
    u = np.array([[-12.0, -6.0, 0.0], [0.0, 3.0, 3.0], [6.0, 9.0, 12.0]])[:, :, None]
    pocket = np.abs(u[:, :, 0] - truths[:, :1]) < half_gap(truths[:, 1:]) + PAPER_DELTA_MM
    y = np.where(pocket, -15.0, 0.0)[:, :, None]
    batch = ProbeBatch("s", np.array(["a", "b", "c"]), np.arange(3), np.zeros(3, int), truths, u, y)
    return SimpleNamespace(batch=batch, pfilter=pf, config=SimpleNamespace(seed=11))


def test_stated_reading_is_the_filter_and_prejitter_only_relabels():
    b = _beliefs()
    rows = E.replay_rows(b, "stated", [1, 2, 3])
    trace = build_trace(b.pfilter, b.batch, 11, [1, 2, 3])
    for k in (1, 2, 3):
        at = rows[rows["k"] == k]
        x = trace.states[k].particles[:, :, 0]
        assert np.array_equal(at["hull_lo"].to_numpy(), x.min(axis=1))
        assert np.array_equal(at["hull_hi"].to_numpy(), x.max(axis=1))
    pre = E.replay_rows(b, "prejitter", [1, 2, 3])
    assert np.array_equal(pre["max_surprise"].to_numpy(), rows["max_surprise"].to_numpy())  # same belief
    same = ~pre["resampled"].to_numpy()
    assert np.array_equal(pre["hull_lo"].to_numpy()[same], rows["hull_lo"].to_numpy()[same])
    with pytest.raises(ValueError):
        E.reading_filter(b.pfilter, "nope")


def _rows(escapes: dict[str, float], clusters=10, repeats=20):
    parts = []
    for reading in E.READINGS:
        for k in (1, 8):
            for i in range(clusters):
                n_esc = int(round(escapes[reading] * repeats))
                esc = np.arange(repeats) < (n_esc if k == 1 else 2 * n_esc)
                parts.append(pd.DataFrame({"run": "random", "reading": reading, "instance_id": f"i{i}", "repeat": np.arange(repeats),
                                           "k": k, "escaped": esc, "in_band": np.arange(repeats) < 5}))
    return pd.concat(parts, ignore_index=True)


def test_escape_keys_select_the_first_reproducing_reading():
    rows = _rows({"stated": 0.0, "prejitter": 0.25, "duplicates": 0.05, "every_step": 0.05})
    out = S.escape_keys(rows, 0.2, 0.05, 0.10, dict(resamples=50, seed=0))
    assert out["stated.escape_k1"] == 0.0 and out["duplicates.escape_k1"] == pytest.approx(0.05)
    assert out["duplicates.reproduces"] == 1 and out["prejitter.reproduces"] == 0
    assert out["selected"] == 3 and out["n_reproducing"] == 2
    assert out["implied_escape_given_band"] == pytest.approx(0.25)
    assert out["duplicates.escape_given_band_k1"] == pytest.approx(0.2)  # 1 of the 5 band rows of each cluster
    assert out["duplicates.escape_off_band_k1"] == 0.0


def test_optimism_strata_add_up():
    rng = np.random.default_rng(0)
    n = 80
    t = pd.DataFrame({"run": "random", "reading": np.repeat(E.READINGS, n), "instance_id": np.tile([f"i{i % 20}" for i in range(n)], 4),
                      "repeat": np.tile(np.arange(n) // 20, 4), "k": 1, "escaped": rng.random(4 * n) < 0.2,
                      "covered": rng.random(4 * n) < 0.8, "realized": (rng.random(4 * n) < 0.3).astype(float),
                      "predicted": rng.random(4 * n)})
    out = S.audit_keys(t, (1,), dict(resamples=20, seed=0))
    for r in E.READINGS:
        s = out[f"{r}.escape_share.k1"]
        assert out[f"{r}.optimism.k1"] == pytest.approx(s * out[f"{r}.gap_escaped.k1"] + (1 - s) * out[f"{r}.gap_covered.k1"])


def test_rules_read_the_selected_reading():
    e113 = C.EXPERIMENTS["E113[optimism original k=8]"]
    p = C._pv("tab:audit.optimism_original.8")
    base = {f"{t}{i}": 0.0 for t in ("lo", "hi", "m") for i in range(1, 5)}
    assert not e113.supports({**base, "sel": 0, "lo3": p - 0.1, "hi3": p + 0.1})
    assert e113.supports({**base, "sel": 3, "lo3": p - 0.1, "hi3": p + 0.1})
    assert not e113.supports({**base, "sel": 2, "lo3": p - 0.1, "hi3": p + 0.1})
    t12 = C.EXPERIMENTS["E113[T12 original]"]
    q = C._pv("T12-calibrated-audit.optimism_original")
    assert t12.supports({**base, "sel": 4, "m4": q + 0.04}) and not t12.supports({**base, "sel": 4, "m4": q + 0.06})
    assert C.EXPERIMENTS["E112"].supports({"sel": 2}) and not C.EXPERIMENTS["E112"].supports({"sel": 0})
    a = C._pv("T36-surprise.auc_k1")
    assert C.EXPERIMENTS["E114[k=1]"].supports({**base, "sel": 1, "lo1": a - 0.01, "hi1": a + 0.01})
    assert not C.EXPERIMENTS["E114[k=1]"].supports({**base, "sel": 0, "lo1": a - 0.01, "hi1": a + 0.01})


def test_draw_keys_span_the_draws():
    rows = pd.DataFrame({"run": ["draw_00"] * 4 + ["draw_01"] * 4 + ["random"] * 2, "k": 1,
                         "in_band": [True, True, False, False, True, False, False, False, True, True],
                         "escaped": [True, False, False, False, True, False, False, False, True, True]})
    out = S.draw_keys(rows)
    assert out["draws.n"] == 2
    assert (out["draws.band_share.min"], out["draws.band_share.max"]) == (0.25, 0.5)
    assert (out["draws.escape_given_band_k1.min"], out["draws.escape_given_band_k1.max"]) == (0.5, 1.0)
    assert (out["draws.escape_k1.min"], out["draws.escape_k1.max"]) == (0.25, 0.25)
    assert S.draw_keys(rows[rows["run"] == "random"])["draws.n"] == 0
