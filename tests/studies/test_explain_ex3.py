"""Hand cases for the third explain helper's experiments (E45..): PyBullet's reported scene
properties, the draw summary, and the claims registry wiring them."""

from __future__ import annotations

import numpy as np
import pytest

from probecommit.runner.config import config_data, parse_config
from probecommit.runner.replay import load_run
from probecommit.runner.study import run_study
from probecommit.studies import claims
from probecommit.studies.explain import pybullet_x
from probecommit.studies.protocol import load_protocol


def test_draw_range_by_hand():
    r = pybullet_x.draw_range([0.3, 0.1, 0.2])
    assert r["count"] == 3 and r["mean"] == pytest.approx(0.2) and r["sd"] == pytest.approx(0.1)
    assert (r["min"], r["max"]) == (0.1, 0.3)
    # Linear interpolation: position 0.025 * 2 = 0.05 between 0.1 and 0.2.
    assert r["p025"] == pytest.approx(0.105) and r["p975"] == pytest.approx(0.295)


def test_gamma_scales_have_the_asked_mean_and_sd_and_stay_positive():
    s = pybullet_x.gamma_scales(1.21, 0.69, 200_000, seed=0)
    assert s.min() > 0
    assert s.mean() == pytest.approx(1.21, abs=0.01) and s.std() == pytest.approx(0.69, abs=0.01)
    assert np.array_equal(s[:10], pybullet_x.gamma_scales(1.21, 0.69, 10, seed=0))


def test_e45_is_wired_and_its_rule_can_fail():
    e = claims.EXPERIMENTS["E45"]
    by_id = {c.id: c for c in claims.CLAIMS}
    for cid in ("T19-pybullet-escape", "tab:engines"):
        assert "E45" in [x if isinstance(x, str) else x[0] for x in by_id[cid].explain]
    paper = claims._pv("T19-pybullet-escape.k8")
    base = {"lo": paper - 0.1, "hi": paper - 0.01, "dlo": paper - 0.1, "dhi": paper - 0.02}
    assert not e.supports(base)
    assert e.supports({**base, "hi": paper + 0.01})
    assert e.supports({**base, "dhi": paper})


def test_the_emulated_scene_at_the_stored_runs_boundary_escapes_on_the_same_episodes(tmp_path):
    """Two paths: a stored analytic run at the paper's PyBullet boundary, and pybullet_x's emulation of it
    (capture window 1.21 instead of 1): same readings, so the same escaped episodes at every budget."""
    p = load_protocol()
    data = config_data(p.run_config("pybullet_B_test_random", "B", "B_test", "random"))
    data["instances"] = {**data["instances"], "count": 6}
    data["repeats"], data["unit_instances"] = 2, 2
    data["belief"] = {**data["belief"], "particles": 128}
    data["simulator"] = {**data["simulator"], "engine": "analytic", "boundary_offset": 0.929, "capture_scale": 1.0}
    run_study(parse_config(data), tmp_path / "engines" / "runs" / "pybullet_B_test_random", workers=1, threads=1)
    rows: dict = {}
    out = pybullet_x.run(tmp_path, tmp_path / "explain" / "runs", dict(resamples=50, seed=0), draws=2, stored_rows=rows)
    assert out["same_escape_as_stored_every_k"] == 1
    stored = load_run(tmp_path / "engines" / "runs" / "pybullet_B_test_random").episodes
    again = pybullet_x.stored_keys(stored, rows[pybullet_x.STORED], int(load_run(tmp_path / "engines" / "runs" / "pybullet_B_test_random").config.probes.budget), dict(resamples=50, seed=0))
    assert again == {k: out[k] for k in again} and len(rows[pybullet_x.STORED]) == 2
    assert out["capture_moves_readings"] == 0 and out["capture_moves_escape_k8"] == 0.0
    assert out["emulated.escape_k8"] == out["stored.escape_k8"]
    assert out["draws.escape_k8.count"] == 2
    assert pybullet_x.run(tmp_path / "nothing", tmp_path / "r", dict(resamples=50, seed=0)) == {}


def test_unpaired_differences_by_hand():
    from probecommit.studies.explain.mixture_x import unpaired_differences

    d = unpaired_differences([0.2, 0.3], [0.1, 0.15])
    assert sorted(d.tolist()) == pytest.approx([0.05, 0.2])  # 0.2 - 0.15 and 0.3 - 0.1; same-seed pairs left out


def test_e46_and_e47_are_wired_and_their_rules_can_fail():
    by_id = {c.id: c for c in claims.CLAIMS}
    assert "E46" in by_id["T44-mixture-cost"].explain and "E47" in by_id["T09-grasp"].explain
    cost = claims._pv("T44-mixture-cost.mixture") - claims._pv("T44-mixture-cost.right")
    assert claims.EXPERIMENTS["E46"].supports({"uhi": cost + 0.001})
    assert not claims.EXPERIMENTS["E46"].supports({"uhi": cost - 0.001})
    assert claims.EXPERIMENTS["E47"].supports({"down": 0}) and not claims.EXPERIMENTS["E47"].supports({"down": 1})


def test_reseeded_replay_at_the_same_seed_is_the_stored_run_and_another_seed_differs(tmp_path):
    """Two paths: a replay of a run under its own seed (via ``reseeded``) gives its stored episodes; the
    mixture summary at that seed then has zero spread of the right model's failure."""
    from probecommit.runner.replay import load_run, replay_episodes
    from probecommit.studies.explain import mixture_x

    p = load_protocol()
    data = config_data(p.run_config("faults_base", "B", "B_test_random", "random"))
    data["instances"] = {**data["instances"], "count": 4}
    data["repeats"], data["unit_instances"] = 2, 2
    data["belief"] = {**data["belief"], "particles": 64}
    data["simulator"] = {**data["simulator"], "engine": "analytic"}
    run_study(parse_config(data), tmp_path / "base", workers=1, threads=1)
    base = load_run(tmp_path / "base")
    k = int(base.config.probes.budget)
    same, _ = replay_episodes(mixture_x.reseeded(base, base.config.seed), None, chunk_instances=48)
    cols = ["instance_id", "repeat", "k", "action", "realized"]
    stored = mixture_x._final(base.episodes, k)[cols].reset_index(drop=True)
    assert mixture_x._final(same, k)[cols].reset_index(drop=True).equals(stored)
    mix = {"likelihood": "mixture", "epsilon": 0.01, "mixture_low": -17.0, "mixture_high": 2.0}
    out, rows = mixture_x.run(base, mix, [base.config.seed, base.config.seed], k)
    assert mixture_x.summary(rows) == out and len(rows) == 2
    assert out["right.failure.sd"] == 0.0 and out["reseeded_changed_aims.mean"] == 0.0
    assert out["right.failure.mean"] == pytest.approx(float(stored["realized"].mean()))


@pytest.mark.slow
def test_grasp_on_the_model_exact_scene_counts_every_feasible_truth_once(tmp_path):
    from probecommit.studies.explain import grasp_x

    rows = grasp_x.run(tmp_path, quick=True)
    out = grasp_x.keys(rows)
    assert grasp_x.keys(rows.sample(frac=1.0, random_state=0)) == out  # the stored rows, in any order, give the keys
    assert out["analytic.n_truths"] == out["analytic.n_feasible"] <= out["analytic.n_instances"]
    assert out["analytic.n_improve"] + out["analytic.n_tie"] + out["analytic.n_worse"] == out["analytic.n_truths"]
