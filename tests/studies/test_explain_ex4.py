"""ex4's explain computations on hand cases: Table II's single-width rule (E35..E40) and the prices
from the paper's own curve (E48)."""

from __future__ import annotations

import math

import pytest

from probecommit.studies import claims
from probecommit.studies.explain.ex4_breadth import single_width
from probecommit.studies.explain.ex4_pricing import break_even_grid, consistent_curves, family_keys
from probecommit.studies.pricing import break_even


def _row(**cells: tuple[float, float]) -> dict[str, float]:
    return {f"{c}{s}": v for c, (lo, hi) in cells.items() for s, v in (("_lo", lo), ("_hi", hi))}


def test_single_width_counts_cells_inside_one_width_at_a_time():
    paper = {"blind_bayes": 0.5, "probe_robust": 0.06, "price.five_below": 0.02}
    rows = {0.5: _row(blind_bayes=(0.1, 0.2), probe_robust=(0.05, 0.07)),
            1.25: _row(blind_bayes=(0.4, 0.6), probe_robust=(0.08, 0.1))}
    assert single_width(rows, paper) == {"single_width.best_cells_inside": 1.0, "single_width.best_scale": 0.5,
                                         "single_width.all_inside": 0.0}
    rows[2.0] = _row(blind_bayes=(0.45, 0.55), probe_robust=(0.06, 0.09))  # an interval's end counts as inside
    assert single_width(rows, paper) == {"single_width.best_cells_inside": 2.0, "single_width.best_scale": 2.0,
                                         "single_width.all_inside": 1.0}


@pytest.mark.parametrize("curve", [(0.5, 0.2, 0.1), (0.3, 0.28, 0.2), (0.035, 0.0115, 0.010), (0.1, 0.2, 0.3)])
def test_break_even_grid_is_break_even_elementwise(curve):
    p = break_even(*curve)
    blind, five = break_even_grid(*curve)
    assert (float(blind), float(five)) == (p.blind_above, p.five_below)


def test_a_curve_s_own_prices_are_found_and_prices_off_by_a_fifth_are_not():
    p = break_even(0.5, 0.2, 0.1)  # convex: blind above (0.5 - 0.2) / 2 = 0.15, five below (0.2 - 0.1) / 3
    assert (p.blind_above, p.five_below) == pytest.approx((0.15, 0.1 / 3))
    hit = consistent_curves((p.blind_above, p.five_below), m5=0.1, m0=0.5, m0_floor=0.4)
    assert hit["consistent"] == 1 and hit["m2_lo"] <= 0.2 <= hit["m2_hi"]
    assert consistent_curves((1.2 * p.blind_above, p.five_below), m5=0.1, m0=0.5, m0_floor=0.4)["consistent"] == 0
    # m0 free: the two prices fix m0 = m2 + 2 * 0.15 and m2 = 0.1 + 3 * five; the floor can rule it out
    free = consistent_curves((p.blind_above, p.five_below), m5=0.1, m0=None, m0_floor=0.4)
    assert free["consistent"] == 1 and free["m0_lo"] <= 0.5 <= free["m0_hi"]
    assert consistent_curves((p.blind_above, p.five_below), m5=0.1, m0=None, m0_floor=0.7)["consistent"] == 0


def test_family_keys_read_the_other_blind_arm_only_where_both_are_printed():
    cells = {"blind_bayes": 0.252, "blind_robust": 0.307, "probe_robust": 0.221}
    d = (0.307 - 0.221) / 5  # two probes never optimal: both prices are the chord
    out = family_keys("x", cells, (d, d))
    assert out["x.consistent"] == 1 and out["x.m0_printed"] == 1 and out["x.blind_bayes_reading.consistent"] == 0
    assert "x.blind_bayes_reading.consistent" not in family_keys("y", {"blind_bayes": 0.3, "probe_robust": 0.03},
                                                                 (0.17, 0.012))


def test_the_breadth_rows_need_one_width_for_the_whole_row():
    e = claims.EXPERIMENTS["E36"]
    good = {"n": 5, "inside": 3.0, "cells": 3.0, "mpl": 0.01, "red": 1.0, "one": 3.0, "at": 0.5, "all": 1.0}
    assert e.supports(good)
    assert not e.supports({**good, "one": 2.0, "all": 0.0})  # the span holds every cell, no single width does
    assert not e.supports({**good, "red": 0.0})


def test_e48_speaks_to_every_priced_family_and_needs_a_consistent_curve():
    by_id = {c.id: c for c in claims.CLAIMS}
    wired = {e[0] for e in by_id["T01-pricing"].explain if not isinstance(e, str)}
    assert {f"E48[{f}]" for f in claims.PRICED} <= wired
    e = claims.EXPERIMENTS["E48[darts]"]
    v = {"ok": 1.0, "lo": 0.011, "hi": 0.012, "m0lo": 0.0345, "m0hi": 0.0355, "printed": 1.0, "o0": 0.17,
         "o2": 0.02, "o5": 0.018, "alt": 0.0}
    assert e.supports(v) and not e.supports({**v, "ok": 0.0})
    assert "alt" not in claims.EXPERIMENTS["E48[hinge]"].keys
    assert not math.isnan(v["lo"])


def test_e49_needs_no_worsening_and_half_improving_at_the_top_resolution():
    e = claims.EXPERIMENTS["E49"]
    v = {"w1": -0.34, "w2": -0.11, "w4": 0.0, "n4": 6, "up4": 3, "tie4": 3, "down4": 0}
    assert e.supports(v)
    assert not e.supports({**v, "down4": 1, "w4": -0.0125})  # one seed of eighty still fails
    assert not e.supports({**v, "n4": 13, "up4": 10})  # no truth worsens, but not half improve
    by_id = {c.id: c for c in claims.CLAIMS}
    assert "E49" in by_id["T09-grasp"].explain


def test_resolution_config_divides_both_sigmas_and_runs_the_analytic_scene():
    from probecommit.studies.explain.ex4_grasp import resolution_config

    c = resolution_config(4.0, quick=True)
    assert c.simulator.engine == "analytic" and c.simulator.noise_sigma == 0.5 and c.model.sigma == 0.5
    assert c.name == "grasp_analytic_resolution4"


def test_cone_keys_recompute_a_row_per_width_and_the_single_width_rule():
    import pandas as pd

    from probecommit.studies.explain.ex4_cone import keys

    rows = []
    for s, (bb, br, pr) in ((0.5, (0.25, 0.30, 0.22)), (1.0, (0.7, 0.6, 0.1))):
        for i in range(4):
            for rep in range(2):
                for method, k, miss in (("blind_bayes", 0, bb), ("blind_robust", 0, br), ("probe_robust", 5, pr)):
                    rows.append({"instance_id": f"i{i}", "repeat": rep, "k": k, "method": method, "status": "ok",
                                 "realized": miss, "realized_elliptic": miss / 2, "scale": s})
    out = keys(pd.DataFrame(rows), 1e-5, dict(resamples=50, seed=0))
    assert out["premise_holds"] == 1 and keys(pd.DataFrame(rows), 1e-3, dict(resamples=50, seed=0))["premise_holds"] == 0
    assert out["s0.5.probe_robust"] == pytest.approx(0.22) and out["s1.elliptic_probe_robust"] == pytest.approx(0.05)
    assert out["s0.5.paired"] == pytest.approx(0.03)
    # every arm constant: each interval is its point, so 0.252 / 0.307 / 0.221 are not inside at any width
    assert out["single_width.best_cells_inside"] == 0 and out["single_width.all_inside"] == 0


def test_e50_needs_the_premise_and_one_width_for_the_whole_row():
    e = claims.EXPERIMENTS["E50"]
    v = {"d": 1e-4, "ok": 1.0, "pr": 0.2, "lo": 0.18, "hi": 0.23, "el": 0.09, "bb": 0.26, "br": 0.3, "one": 3.0,
         "at": 0.5, "all": 1.0, "plo": 0.17, "phi": 0.2}
    assert e.supports(v)
    assert not e.supports({**v, "ok": 0.0}) and not e.supports({**v, "all": 0.0, "one": 2.0})
    by_id = {c.id: c for c in claims.CLAIMS}
    assert ("E50", ("push2d ",)) in by_id["tab:breadth"].explain


@pytest.mark.slow
def test_reexecuting_stored_actions_in_the_stored_scene_gives_the_stored_misses(tmp_path):
    """Same scene, same actions: the re-execution path reproduces the study's own outcomes exactly, so under the
    pyramidal cone it changes the cone alone."""
    from probecommit.runner.study import run_study
    from probecommit.studies.breadth import paper_config, quick_config
    from probecommit.studies.explain.ex4_cone import Scene, premise, reexecuted

    config = quick_config(paper_config("push2d"))
    run_study(config, tmp_path / "push2d", workers=1, threads=1)
    rows = reexecuted(tmp_path / "push2d", Scene("elliptic"), 1.0)
    assert len(rows) > 0  # equal but for the last bit (hypot here, norm in the study)
    assert rows["realized"].to_numpy() == pytest.approx(rows["realized_elliptic"].to_numpy(), abs=1e-12, rel=0)
    assert premise([tmp_path / "push2d"], Scene("elliptic"), Scene("elliptic")) == 0.0


@pytest.mark.slow
def test_grasp_resolution_step_counts_every_feasible_truth_once(tmp_path):
    from probecommit.studies.explain import ex4_grasp

    out, rows = ex4_grasp.run(tmp_path, [4.0], quick=True)
    assert out == ex4_grasp.keys(rows)  # verify counts the same keys again from the stored rows
    assert out["factors"] == [4.0]
    assert out["c4.n_improve"] + out["c4.n_tie"] + out["c4.n_worse"] == out["c4.n_truths"] == out["c4.n_feasible"]
    assert "c1.worst_difference" not in out  # E47's run is not under this folder
