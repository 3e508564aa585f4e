"""Hand cases for the ex1 explain experiments (issue 36): class surprise, the draw audit's
spread, and the per-cell Table III experiments (E13-E18)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from probecommit.studies import claims as C
from probecommit.studies import paper_values as P
from probecommit.studies.explain.draw_audit import spread
from probecommit.studies.explain.surprise_variants import class_surprise
from tests.studies.test_claims import _lookup


def test_class_surprise_is_minus_log_of_the_weight_predicting_the_class_read():
    w = np.array([[0.25, 0.25, 0.5], [0.1, 0.2, 0.7]])
    predicts = np.array([[True, False, False], [True, True, True]])
    out = class_surprise(w, predicts, np.array([True, False]))
    assert out[0] == pytest.approx(-math.log(0.25))  # pocket read, a quarter of the weight predicts it
    assert out[1] == math.inf  # top read, no particle predicts it
    assert class_surprise(w, predicts, np.array([False, True]))[0] == pytest.approx(-math.log(0.75))


def test_spread_is_min_max_mean_per_cell():
    out = spread([{"a": 1.0, "b": 0.0}, {"a": 3.0, "b": -1.0}, {"a": 2.0, "b": 4.0}])
    assert out == {"a.min": 1.0, "a.max": 3.0, "a.mean": 2.0, "b.min": -1.0, "b.max": 4.0, "b.mean": 1.0}


def test_each_table_III_cell_is_explained_only_by_its_own_range():
    audit = next(c for c in C.CLAIMS if c.id == "tab:audit")
    d = f"{C.X}instance_generator.draws."
    values = {f"{d}count": 12}
    # Every cell's paper value inside its range, except cluster coverage original k=1 (paper 0.79).
    for k in C.AUDIT_K:
        for col in ("cluster_coverage", "optimism"):
            for arm in ("original", "calibrated"):
                p = P.value(f"tab:audit.{col}_{arm}.{k}")
                lo, hi = (p + 0.01, p + 0.02) if (col, arm, k) == ("cluster_coverage", "original", 1) else (p - 0.01, p + 0.01)
                cell = f"{col}.{arm}.k{k}"
                values.update({f"{d}audit.{cell}.min": lo, f"{d}audit.{cell}.max": hi, f"{d}audit.{cell}.mean": p,
                               f"{d}audit_check.{cell}": p})
    # Our table: every cell far from the paper's (all comparisons fail).
    for i, k in enumerate(C.AUDIT_K):
        row = f"{C.I}table_audit.table.{i}"
        for col in ("cluster_coverage", "optimism"):
            for arm in ("original", "calibrated"):
                values.update({f"{row}.{col}_{arm}": 5.0, f"{row}.{col}_lo_{arm}": 4.9, f"{row}.{col}_hi_{arm}": 5.1})
    out = C.evaluate(audit, _lookup(values), lambda p: True)
    assert out.status == "differs, unexplained" and len(out.failed) == 20
    assert "E17[cluster_coverage original k=1]" not in out.experiment and out.experiment.count("E17[") == 19
    # Move that one range over the paper's value: every cell is now spoken to.
    values[f"{d}audit.cluster_coverage.original.k1.min"] = 0.7
    assert C.evaluate(audit, _lookup(values), lambda p: True).status == "differs, explained"


def test_committed_pool_experiment_needs_the_order_to_follow_the_schedule():
    e = C.EXPERIMENTS["E13"]
    v = {"ec": 23, "nc": 231, "er": 5, "nr": 153, "ratio": 3.0, "lo": 1.1, "hi": 15.0, "pvc": 0.09, "pvr": 0.045,
         "pv": 2.0, "ours": 0.7, "pn": 50.0}
    assert e.supports(v)
    assert not e.supports({**v, "ours": 1.2})  # ours in the paper's order too: the schedule is not the cause
    assert not e.supports({**v, "pv": 0.9})  # posterior variance not reordered under the paper's schedule
    assert not e.supports({**v, "ratio": 0.9})
    assert not e.supports({**v, "ratio": 1.5})  # reordered, but not T33's "several times" (at least SEVERAL_FOLD)


def test_surprise_and_realized_experiments_test_the_paper_value():
    assert C.EXPERIMENTS["E15"].supports({"a": 0.6, "lo": 0.44, "hi": 0.75, "n": 28, "ours": 0.8})
    assert not C.EXPERIMENTS["E15"].supports({"a": 0.8, "lo": 0.7, "hi": 0.9, "n": 28, "ours": 0.8})
    assert not C.EXPERIMENTS["E16"].supports({"c1": 0.5, "lo": 0.4, "hi": 0.6, "d1": 0.46, "r1": 0.7, "c5": 0.6})
    e14 = C.EXPERIMENTS["E14"]
    assert e14.supports({"pc": 0.016, "pr": 0.281, "oc": 0.05, "orl": 0.24})
    assert not e14.supports({"pc": 0.016, "pr": 0.239, "oc": 0.05, "orl": 0.24})  # 0.074 from the paper's 0.313
    assert not e14.supports({"pc": 0.3, "pr": 0.29, "oc": 0.05, "orl": 0.24})  # claims more than it realizes


def test_fault_arm_cells_on_a_hand_table():
    import pandas as pd

    from probecommit.studies.explain.draw_faults import arm_cells, nan_spread

    rows = []
    for fault, arm, realized, predicted, escaped, surprise in (
            ("none", "fault", [0, 1], [0.5, 0.5], [False, False], [1.0, 2.0]),
            ("particles", "fault", [1, 1, 0, 0], [0.9, 0.8, 0.3, 0.2], [True, False, True, False], [3.0, 1.0, 4.0, 2.0]),
            ("particles", "tempered", [1, 0, 0, 0], [0.5] * 4, [False] * 4, [1.0] * 4)):
        for i, (r, p, e, s) in enumerate(zip(realized, predicted, escaped, surprise)):
            rows.append({"fault": fault, "arm": arm, "method": "probe_robust", "status": "ok", "k": 8,
                         "instance_id": f"i{i}", "repeat": 0, "realized": float(r), "predicted": p, "escaped": e,
                         "max_surprise": s})
    out = arm_cells(pd.DataFrame(rows), 8)
    assert out["none.fail"] == 0.5 and out["none.optimism"] == 0.0 and "none.surprise_auc" not in out  # no escape
    assert out["particles.fail"] == 0.5 and out["particles.optimism"] == pytest.approx(-0.05)
    assert out["particles.surprise_auc"] == 1.0  # both escapes (3, 4) above both others (1, 2)
    assert out["particles.tempered"] == 0.25 and out["particles_residual_improves"] == 1.0  # -0.05 < 0
    spread = nan_spread([{"a": 1.0, "b": float("nan")}, {"a": 2.0, "b": 5.0}])
    assert spread == {"a.min": 1.0, "a.max": 2.0, "a.mean": 1.5, "a.n": 2, "b.min": 5.0, "b.max": 5.0, "b.mean": 5.0,
                      "b.n": 1}


def test_draw_experiments_compare_the_paper_value_with_the_range():
    e20 = C.EXPERIMENTS["E20"]  # paper 0.62
    assert e20.supports({"lo": 0.5, "hi": 0.7, "m": 0.6, "n": 12}) and not e20.supports({"lo": 0.5, "hi": 0.6, "m": 0.55, "n": 12})
    fail = C.EXPERIMENTS["E21[boundary fail]"]  # paper 0.38
    assert fail.supports({"lo": 0.3, "hi": 0.4, "m": 0.35, "n": 12, "check": 0.3})
    assert not fail.supports({"lo": 0.2, "hi": 0.37, "m": 0.3, "n": 12, "check": 0.3})
    assert C.EXPERIMENTS["E22"].supports({"share": 0.5, "n": 12, "plo": 0, "phi": 0, "nlo": 0, "nhi": 0})
    assert not C.EXPERIMENTS["E22"].supports({"share": 0.25, "n": 12, "plo": 0, "phi": 0, "nlo": 0, "nhi": 0})


def test_gate_area_experiments():
    v = {"lo": 0.2, "hi": 0.35, "m": 0.28, "share": 0.5, "n": 12, "rlo": 0.1, "rhi": 0.2}
    assert C.EXPERIMENTS["E23"].supports(v)  # paper 0.325 inside
    assert not C.EXPERIMENTS["E23"].supports({**v, "hi": 0.3})
    e24 = {"share": 0.5, "n": 12, "m": 0.2, "rm": 0.2, "am": 0.3}
    assert C.EXPERIMENTS["E24"].supports(e24) and not C.EXPERIMENTS["E24"].supports({**e24, "share": 0.4})


def test_resplit_experiments_use_the_claims_tolerance():
    v = {"n": 50, "lv": 0.7, "cv": 0.84, "mo": 0.5, "g": 0.6}
    assert C.EXPERIMENTS["E25[level mean]"].supports({**v, "v": 0.7})  # |0.7 - 0.75| <= 0.1
    assert not C.EXPERIMENTS["E25[level mean]"].supports({**v, "v": 0.6})
    assert C.EXPERIMENTS["E25[held-out cluster coverage]"].supports({**v, "v": 0.84})  # paper 0.857, tol 0.05
    assert C.EXPERIMENTS["E25[margin optimistic]"].supports({**v, "v": 0.55})  # paper 64 %, tol 0.1
    assert not C.EXPERIMENTS["E25[margin optimistic]"].supports({**v, "v": 0.5})


def test_resplit_summary_on_a_hand_table():
    import pandas as pd

    from probecommit.studies.explain.resplits import summary

    t = pd.DataFrame({"level": [0.5, 0.7], "failure": [0.3, 0.4], "heldout_cluster_coverage": [0.8, 0.9],
                      "margin_optimistic": [True, False], "gamma": [0.6, 0.7]})
    out = summary(t)
    assert out["level_mean"] == pytest.approx(0.6) and out["level_sd"] == pytest.approx(0.1414213562)
    assert out["margin_optimistic_fraction"] == 0.5 and out["splits"] == 2 and out["gamma_mean"] == pytest.approx(0.65)
