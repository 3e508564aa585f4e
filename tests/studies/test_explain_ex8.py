"""ex8's explain experiments (E73..): hand cases with exact answers, the rule's teeth, the stored-rows round trip."""

from __future__ import annotations

import pandas as pd
import pytest

from probecommit.studies import claims


def _rows(truths: dict[str, tuple[bool, int, int]], seeds: int = 80, part: str | None = None) -> pd.DataFrame:
    """Truth-labelled rows as ``breadth.truth_rows`` gives them: ``truth -> (feasible, blind success 0/1,
    probed failures of ``seeds``)``."""
    rows = []
    for t, (feasible, blind, fails) in truths.items():
        for rep in range(seeds):
            rows.append({"instance_id": t, "repeat": rep, "method": "blind_bayes", "k": 0, "status": "ok",
                         "realized": float(1 - blind), "feasible": feasible, "truth": t})
            rows.append({"instance_id": t, "repeat": rep, "method": "probe_robust", "k": 8, "status": "ok",
                         "realized": float(rep < fails), "feasible": feasible, "truth": t})
    out = pd.DataFrame(rows)
    return out.assign(part=part) if part else out


def test_paper_decomposition_is_the_papers_own_arithmetic():
    from probecommit.studies.explain.ex8_grasp import paper_keys

    k = paper_keys()
    assert k["paper.n_feasible"] == 6 and k["paper.n_held"] == 2  # 0.333 x 6
    assert k["paper.improve_middle"] == pytest.approx(6 * 0.692 - 2 - 0.36 - 0.96)
    assert k["paper.consistent"] == 1


def test_part_keys_count_held_truths_their_failures_and_the_chance_of_two_ties():
    from probecommit.studies.explain.ex8_grasp import part_keys

    rows = _rows({"held": (True, 1, 2), "missed": (True, 0, 60), "other": (True, 0, 8), "out": (False, 0, 80)})
    k = part_keys(rows)
    assert k["n_feasible"] == 3 and k["n_held"] == 1  # the infeasible truth is not read
    assert k["held_failures"] == 2 and k["held_episodes"] == 80 and k["held_failure_rate"] == pytest.approx(2 / 80)
    assert k["paper_ties_chance"] == pytest.approx((1 - 2 / 80) ** 160)
    assert k["other_failure_rate"] == pytest.approx(68 / 160) and k["failure_rate"] == pytest.approx(70 / 240)
    assert k["lowest_probe_success"] == pytest.approx(0.25) and k["highest_probe_success"] == pytest.approx(0.975)
    assert k["n_worse"] == 1 and k["n_worse_not_held"] == 0  # the held truth loses 2 of 80


def test_keys_read_every_run_and_the_rule_needs_ties_and_a_low_truth_in_one_run():
    from probecommit.studies.explain.ex8_grasp import keys

    sharp = {"held": (True, 1, 0), "a": (True, 0, 1), "b": (True, 0, 2)}  # ties, but every truth near 1
    spread = {"held": (True, 1, 30), "a": (True, 0, 60), "b": (True, 0, 2)}  # a low truth, but no ties
    mujoco = _rows(spread).assign(family="grasp")
    ex4 = pd.concat([_rows(spread, part="frozen"), _rows(spread, part="c2"), _rows(sharp, part="c4")])
    out = keys(mujoco, ex4, _rows(sharp, part="c4_particles"))
    assert out["runs"] == 4 and out["runs_with_ties"] == 1 and out["runs_with_low_truth"] == 3
    assert out["runs_with_both"] == 0
    assert out["c4.paper_ties_chance"] == 1 and out["c4_particles.factor"] == 4
    both = {"held": (True, 1, 0), "a": (True, 0, 60)}  # the paper's pattern: a tie and a low truth
    ex4_both = pd.concat([_rows(spread, part="frozen"), _rows(both, part="c2"), _rows(sharp, part="c4")])
    assert keys(mujoco, ex4_both, _rows(sharp))["runs_with_both"] == 1


def test_e73_supports_only_when_one_run_has_both():
    e = claims.EXPERIMENTS["E73"]
    v = {name: 0.5 for name in e.keys}
    e.template.format(**v)  # every template field is a key
    assert not e.supports({**v, "both": 0.0}) and e.supports({**v, "both": 1.0})
    assert "E73" in {c.id: c for c in claims.CLAIMS}["T09-grasp"].explain


def test_recompute_needs_the_stored_rows(tmp_path):
    from probecommit.studies.explain import ex8

    (tmp_path / "explain").mkdir()
    values, sources, problems = ex8.recompute(tmp_path / "explain", {"ex8_grasp": {"runs": 4.0}})
    assert values == {} and sources == {} and problems == [
        "explain/ex8_grasp_rows.parquet: missing (the rows ex8_grasp's keys are recomputed from)"]
    assert ex8.recompute(tmp_path / "explain", {})[2] == []


def test_recompute_gives_the_step_keys_from_stored_rows(tmp_path):
    from probecommit.studies.explain import ex4_grasp, ex8, ex8_grasp

    explain, breadth = tmp_path / "explain", tmp_path / "breadth"
    explain.mkdir(), breadth.mkdir()
    spread = {"held": (True, 1, 30), "a": (True, 0, 60)}
    mujoco = _rows(spread).assign(family="grasp")
    ex4 = pd.concat([_rows(spread, part=p) for p in ("frozen", "c2", "c4")], ignore_index=True)
    own = _rows(spread, part="c4_particles")
    mujoco.to_parquet(breadth / "sign_flip_rows.parquet")
    ex4.to_parquet(explain / ex4_grasp.STORED)
    own.to_parquet(explain / ex8_grasp.STORED)
    readings = _paired_readings(bias=0.01)
    readings.to_parquet(explain / "ex8_pybullet_readings.parquet")
    values, _, problems = ex8.recompute(explain, {"ex8_grasp": {}, "ex8_pybullet": {}})
    assert problems == []
    from probecommit.studies.explain.ex8_pybullet import keys as pybullet_keys

    assert values == {**{f"ex8_grasp.{k}": v for k, v in ex8_grasp.keys(mujoco, ex4, own).items()},
                      **{f"ex8_pybullet.{k}": v for k, v in pybullet_keys(readings).items()}}


@pytest.mark.slow
def test_grasp_particle_rerun_counts_every_feasible_truth(tmp_path):
    from probecommit.studies.explain import ex8_grasp

    out, rows = ex8_grasp.run(tmp_path, tmp_path / "runs", None, quick=True)
    assert out == {}  # no Table II rows under this root: no keys, the rerun's rows still come back
    assert set(rows["part"]) == {"c4_particles"} and rows["feasible"].notna().all()


def _paired_readings(bias: float = 0.0, engine: float = 0.0) -> pd.DataFrame:
    """Paired push2d readings at one truth and pulse: the MuJoCo-fitted model's prediction plus +-sigma noise (so
    the cell's mean residual is exactly ``bias``), PyBullet ``engine`` metres off MuJoCo."""
    from probecommit.runner.build import build_model
    from probecommit.studies.breadth import paper_config

    model = build_model(paper_config("push2d_pybullet"))
    theta = [0.4, 1.0, 1.75]
    pred = model.predict([[2.0]], [[theta]])[0, 0]
    rows = []
    for j, sign in enumerate((1.0, -1.0) * 8):
        y = pred + sign * model.sigma + bias
        rows.append({"instance_id": "i0", "repeat": 0, "j": j, "u_mujoco": 2.0, "u_pybullet": 2.0,
                     "y_0_mujoco": y[0] - engine,
                     "y_0_pybullet": y[0], "y_1_mujoco": y[1], "y_1_pybullet": y[1],
                     "true_mu": theta[0], "true_m": theta[1], "true_k_d": theta[2]})
    return pd.DataFrame(rows)


def test_pybullet_keys_measure_engine_difference_and_model_bias_exactly():
    from probecommit.studies.explain.ex8_pybullet import keys

    k = keys(_paired_readings())
    assert k["readings"] == 16 and k["cells"] == 2 and k["sigma_m"] == 0.05
    assert k["engine_max_difference_m"] == 0 and k["model_max_cell_bias_m"] == pytest.approx(0, abs=1e-12)
    assert k["model_residual_sd_m"] == pytest.approx(0.05)  # +-sigma on both dimensions
    assert k["premise_holds"] == 1
    off = keys(_paired_readings(bias=0.05))  # 16 readings: SE = sigma / 4, so the bias is 4 SE
    assert off["model_max_cell_bias_m"] == pytest.approx(0.05) and off["model_max_cell_bias_se"] == pytest.approx(4.0)
    assert off["premise_holds"] == 0
    apart = keys(_paired_readings(engine=0.006))  # more than a tenth of sigma between the engines
    assert apart["engine_max_difference_m"] == pytest.approx(0.006) and apart["premise_holds"] == 0
    other = _paired_readings().assign(u_mujoco=1.0)  # different pulses: not paired runs
    assert keys(other)["pulses_match"] == 0 and keys(other)["premise_holds"] == 0


def test_e74_needs_the_premise_and_the_residual_model_value_inside():
    e = claims.EXPERIMENTS["E74"]
    v = {"d": 0.002, "n": 540.0, "sd": 0.05, "b": 0.01, "bse": 1.5, "ok": 1.0, "pr": 0.09, "lo": 0.055, "hi": 0.129}
    e.template.format(**v)
    assert e.supports(v)
    assert not e.supports({**v, "ok": 0.0}) and not e.supports({**v, "hi": 0.11})
    explain = dict((n, labels) for n, labels in (x for x in {c.id: c for c in claims.CLAIMS}["tab:breadth"].explain
                                                 if isinstance(x, tuple)))
    assert explain["E74"] == ("push2d_pybullet probe_robust",)


def test_pybullet_step_needs_both_frozen_runs(tmp_path):
    from probecommit.studies.explain import ex8_pybullet

    assert ex8_pybullet.run(tmp_path)[0] == {} and ex8_pybullet.recompute(tmp_path) == {}


def _blind_rows(truths: list[list[float]], actions: dict[str, list[float]], target: float = 1.0) -> pd.DataFrame:
    """push1d blind episodes at one target: every arm's actions (one per repeat) on every truth, realized from the
    model (so the premise is exact)."""
    from probecommit.studies.explain.ex8_blind import _model

    model = _model("push1d")
    rows = []
    for i, theta in enumerate(truths):
        for method, acts in actions.items():
            for rep, a in enumerate(acts):
                miss = float(model.loss([[a]], [theta], [target])[0, 0])
                rows.append({"instance_id": f"i{i}", "repeat": rep, "method": method, "realized": miss, "action": a,
                             "true_mu": theta[0], "true_m": theta[1], "true_k_d": theta[2], "ctx_target": target})
    return pd.DataFrame(rows)


def test_blind_model_cell_and_redraws_are_the_models_misses():
    import numpy as np

    from probecommit.studies.explain.ex8_blind import _model, model_cell, redraw_cells

    model = _model("push1d")
    rows = _blind_rows([[0.3, 0.8, 1.0], [0.5, 1.2, 2.0]], {"blind_bayes": [2.0, 2.0], "blind_robust": [1.5, 2.5]})
    bb = rows[rows["method"] == "blind_bayes"]
    assert model_cell(bb, model) == pytest.approx(bb["realized"].mean(), rel=1e-12)
    cells = redraw_cells(rows[rows["method"] == "blind_robust"], model, n_truths=2, draws=5, seed=7)
    theta = model.prior_low + (model.prior_high - model.prior_low) * np.random.default_rng(7).random((10, 3))
    per_truth = np.mean([model.loss([[a]], theta, [1.0])[0] for a in (1.5, 2.5, 1.5, 2.5)], axis=0)
    assert cells == pytest.approx(per_truth.reshape(5, 2).mean(axis=1), rel=1e-12)


def test_blind_keys_compare_the_papers_cell_with_the_central_interval():
    from probecommit.studies.explain.ex8_blind import keys

    rows = _blind_rows([[0.3, 0.8, 1.0], [0.5, 1.2, 2.0]], {"blind_bayes": [2.0], "blind_robust": [2.2]})
    out = keys(rows.assign(family="push1d"), draws=200)
    assert out["push1d.premise_holds"] == 1 and out["push1d.n_truths"] == 2 and out["push1d.cells"] == 1
    lo, hi = out["push1d.blind_bayes.draws.p025"], out["push1d.blind_bayes.draws.p975"]
    assert lo < out["push1d.blind_bayes.draws.mean"] < hi
    assert out["push1d.blind_bayes.paper_inside"] == float(lo <= 0.491 <= hi) == out["push1d.cells_inside"]
    bad = rows.assign(realized=rows["realized"] * 1.05, family="push1d")  # the scene 5 % off the model
    assert keys(bad, draws=20)["push1d.premise_holds"] == 0


def test_e75_to_e78_need_the_premise_every_cell_and_the_ratio():
    for number, two in (("E75", False), ("E76", True), ("E77", False), ("E78", True)):
        e = claims.EXPERIMENTS[number]
        v = {name: 1.0 for name in e.keys} | {"cells": 2.0 if two else 1.0, "inside": 2.0 if two else 1.0}
        e.template.format(**v)
        assert e.supports(v) and not e.supports({**v, "ok": 0.0}) and not e.supports({**v, "inside": 0.0})
        if two:
            assert not e.supports({**v, "qin": 0.0})
    explain = {n: labels for n, labels in (x for x in {c.id: c for c in claims.CLAIMS}["tab:breadth"].explain
                                           if isinstance(x, tuple))}
    assert explain["E76"] == ("push2d blind_bayes", "push2d blind_robust")
    assert explain["E77"] == ("push2d_pybullet blind_bayes",)
