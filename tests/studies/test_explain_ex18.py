"""ex18's E132 (T14's optimistic share as a count of splits): hand cases with exact answers."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from probecommit.studies import claims
from probecommit.studies.explain import ex18_share as ex18
from probecommit.studies.paper_values import value


def _fisher_two_sided(a: int, b: int, c: int, d: int) -> float:
    """Fisher's exact two-sided p by enumeration: every table with the same margins at most as likely."""
    row, col, n = a + b, a + c, a + b + c + d
    prob = lambda x: math.comb(col, x) * math.comb(n - col, row - x) / math.comb(n, row)  # noqa: E731
    seen = prob(a)
    return sum(prob(x) for x in range(max(0, row + col - n), min(row, col) + 1) if prob(x) <= seen * (1 + 1e-7))


def test_count_keys_exact_cases():
    got = ex18.count_keys(0, 5, 5)
    assert got["optimistic"] == 0 and got["share"] == 0 and got["sd"] == 0
    assert got["cp_lo"] == 0 and math.isclose(got["cp_hi"], 1 - 0.025 ** (1 / 5), rel_tol=1e-9)
    assert math.isclose(got["fisher_p"], 2 / math.comb(10, 5), rel_tol=1e-9)  # the two extreme tables
    got = ex18.count_keys(24, 50, 32)
    assert math.isclose(got["fisher_p"], _fisher_two_sided(24, 26, 32, 18), rel_tol=1e-9)
    assert math.isclose(got["sd"], math.sqrt(0.48 * 0.52 / 50))
    assert got["cp_lo"] < 0.48 < got["cp_hi"]
    assert ex18.count_keys(32, 50, 32)["fisher_p"] == 1.0


def test_paper_count_is_its_percent_of_the_splits():
    assert value("T14-resplits.margin_optimistic_percent") == 64
    assert ex18.paper_count(50) == 32 and ex18.paper_count(2) == 1


def _ex15_rows(pool: str, opt: list[float], e: np.ndarray) -> pd.DataFrame:
    n = len(opt)
    return pd.DataFrame({"pool": pool, "index": range(n), "level_a1": np.linspace(0.5, 1.0, n),
                         "coverage_a3": 0.8, "c5_failure": 0.3, "c5_optimistic": opt,
                         **{f"c15_optimism_k{k + 1}": e[:, k] for k in range(e.shape[1])}})


def test_rows_from_reads_each_margin_reading():
    e = np.array([[-0.1, 0.2], [0.1, -0.05], [-0.1, -0.2], [0.3, 0.1]])
    union = _ex15_rows("B_union_cover", [1.0, 0.0, 0.0, 1.0], e)
    other = _ex15_rows("pool_draw_00_paper_schedule", [np.nan] * 4, e)
    rows = ex18.rows_from([union, None, other])
    assert list(rows["pool"]) == ["B_union_cover"] * 4  # a pool without the study's calibration is left out
    assert list(rows["c5"]) == [1, 0, 0, 1]
    assert list(rows["c15_k5"]) == [1, 0, 0, 1]  # the last budget (k2 here) above zero
    assert list(rows["c15_mean"]) == [1, 1, 0, 1]
    assert list(rows["c15_any"]) == [1, 1, 0, 1]
    keys = ex18.summary(rows)
    assert keys["B_union_cover.splits"] == 4 and keys["B_union_cover.c5.optimistic"] == 2
    assert keys["paper.optimistic"] == ex18.paper_count(4) == 3
    assert math.isclose(keys["B_union_cover.level"], 0.75)
    assert math.isclose(keys["B_union_cover.c15_mean.fisher_p"], _fisher_two_sided(3, 1, 3, 1))


def _values(**over: float) -> dict[str, float]:
    v = {"f": value("T14-resplits.failure_mean"), "l": value("T14-resplits.level_mean"),
         "c": value("T14-resplits.heldout_cluster_coverage"), "p": 0.2}
    return {**v, **over}


def test_e132_needs_the_three_numbers_inside_and_the_counts_agreeing():
    assert claims._ex18_share_holds(_values())
    assert not claims._ex18_share_holds(_values(p=0.049))
    assert claims._ex18_share_holds(_values(p=0.05))
    assert not claims._ex18_share_holds(_values(l=value("T14-resplits.level_mean") + 0.11))
    assert not claims._ex18_share_holds(_values(c=value("T14-resplits.heldout_cluster_coverage") - 0.06))
    assert not claims._ex18_share_holds(_values(f=value("T14-resplits.failure_mean") + 0.03))


def test_t14_names_e132_for_its_three_failing_comparisons():
    t14 = next(c for c in claims.CLAIMS if c.id == "T14-resplits")
    named = {number: labels for number, labels in t14.explain}
    assert named["E132"] == ("level mean", "held-out cluster coverage", "margin optimistic")
    assert "E132" in claims.EXPERIMENTS


def test_force_ceiling_cuts_both_grids_and_restores_them():
    from probecommit.studies.explain import ex18_grasp
    from probecommit.tasks.grasp.model import ACTION_FORCES, GraspModel

    frozen_actions, frozen_probes = GraspModel.action_grid.copy(), GraspModel.probe_grid.copy()
    with ex18_grasp.force_ceiling(2.0):
        assert GraspModel.probe_grid.ravel().tolist() == [0.25, 0.5, 1.0, 2.0]
        assert GraspModel.action_grid.max() <= 2.0 and GraspModel.action_grid[0, 0] == ACTION_FORCES[0]
        assert len(GraspModel.action_grid) == int(np.sum(ACTION_FORCES <= 2.0))
    assert np.array_equal(GraspModel.action_grid, frozen_actions) and np.array_equal(GraspModel.probe_grid, frozen_probes)
    try:
        with ex18_grasp.force_ceiling(3.0):
            raise RuntimeError("inside")
    except RuntimeError:
        pass
    assert np.array_equal(GraspModel.action_grid, frozen_actions)  # restored when the block fails too
    assert ex18_grasp.label(2.5) == "cap25" and ex18_grasp.label(5.0) == "cap50"
    assert [ex18_grasp.label(c) for c in ex18_grasp.CEILINGS] == list(claims.EX18_CEILINGS)


def _truth_rows(successes: dict[str, tuple[float, float]], ceiling: float, infeasible: int = 0) -> pd.DataFrame:
    """Rows as ``breadth.truth_rows`` gives them: per truth, Blind-Bayes and Probe-Robust(8) success over 4 seeds."""
    rows = []
    for n, (truth, (blind, probe)) in enumerate(successes.items()):
        for rep in range(4):
            rows.append({"instance_id": f"i{n}", "repeat": rep, "method": "blind_bayes", "k": 0, "status": "ok",
                         "realized": 1.0 - blind, "feasible": True, "truth": truth})
            rows.append({"instance_id": f"i{n}", "repeat": rep, "method": "probe_robust", "k": 8, "status": "ok",
                         "realized": float(rep >= 4 * probe), "feasible": True, "truth": truth})
    for j in range(infeasible):
        rows.append({"instance_id": f"x{j}", "repeat": 0, "method": "blind_bayes", "k": 0, "status": "ok",
                     "realized": 1.0, "feasible": False, "truth": f"x{j}"})
    return pd.DataFrame(rows).assign(ceiling=ceiling)


def test_grasp_summary_counts_signs_per_ceiling():
    from probecommit.studies.explain import ex18_grasp

    rows = pd.concat([_truth_rows({"a": (0.0, 0.75), "b": (1.0, 1.0), "c": (1.0, 0.5)}, 2.0, infeasible=2),
                      _truth_rows({"a": (0.0, 1.0)}, 5.0)], ignore_index=True)
    got = ex18_grasp.summary(rows)
    assert got["cap20.ceiling"] == 2.0 and got["cap20.n_feasible"] == 3 and got["cap20.n_instances"] == 5
    assert (got["cap20.n_improve"], got["cap20.n_tie"], got["cap20.n_worse"]) == (1, 1, 1)
    assert got["cap20.improve_max"] == 0.75 and got["cap20.worst_difference"] == -0.5
    assert (got["cap50.n_feasible"], got["cap50.n_improve"], got["cap50.n_worse"]) == (1, 1, 0)


def _caps(**over: tuple[int, int]) -> dict[str, float]:
    v: dict[str, float] = {}
    for c in claims.EX18_CEILINGS:
        f, w = over.get(c, (13, 3))
        v.update({f"{c}f": f, f"{c}w": w})
    return v


def test_e133_needs_six_give_or_take_one_feasible_and_no_worsening_at_one_ceiling():
    assert not claims._ex18_grasp_holds(_caps())
    assert not claims._ex18_grasp_holds(_caps(cap20=(5, 1), cap25=(7, 2)))  # E133's full-data outcome
    assert claims._ex18_grasp_holds(_caps(cap20=(5, 0)))
    assert claims._ex18_grasp_holds(_caps(cap25=(7, 0)))
    assert not claims._ex18_grasp_holds(_caps(cap30=(8, 0)))  # no worsening, but eight feasible
    assert not claims._ex18_grasp_holds(_caps(cap20=(5, 1), cap30=(8, 0)))  # the two conditions at one ceiling


def test_t09_names_e133():
    t09 = next(c for c in claims.CLAIMS if c.id == "T09-grasp")
    assert "E133" in t09.explain and "E133" in claims.EXPERIMENTS
