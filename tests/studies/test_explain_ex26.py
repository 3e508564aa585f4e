"""ex26's E178/E179 (grasp's blind-held truths against the squeeze's duration): the patch, hand cases with exact
answers, the declared rules."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex26_grasp


def test_squeeze_scale_scales_the_slip_in_model_and_engine_and_restores_them():
    from probecommit.tasks import base
    from probecommit.tasks.grasp import model, sim_mujoco
    from probecommit.tasks.grasp.sim_base import AnalyticGraspSimulator

    frozen = model.SQUEEZE_S, sim_mujoco.SQUEEZE_S, model.GraspModel.observation_range
    slip = model.squeeze_slip_mm(0.5, 0.5, 0.2)
    with base.shared_engine_answers() as store:
        with ex26_grasp.squeeze_scale(4.0):
            assert model.SQUEEZE_S == sim_mujoco.SQUEEZE_S == pytest.approx(2.0 * frozen[0])
            assert model.squeeze_slip_mm(0.5, 0.5, 0.2) == pytest.approx(4.0 * slip)
            assert AnalyticGraspSimulator().squeeze(0.5, 0.2, 0.5) == pytest.approx(4.0 * slip)
            assert model.GraspModel.observation_range == (frozen[2][0], 4.0 * frozen[2][1])
            assert base.answer_store("grasp", "mujoco", {}) is None  # no answer of another duration is shared
        assert base.answer_store("grasp", "mujoco", {}) is not None and base._ANSWER_STORE is store
    with pytest.raises(RuntimeError):
        with ex26_grasp.squeeze_scale(2.0):
            raise RuntimeError("inside")
    assert (model.SQUEEZE_S, sim_mujoco.SQUEEZE_S, model.GraspModel.observation_range) == frozen


def _rows(truths: dict[str, tuple[float, list[tuple[float, float]]]], condition: str = "c4") -> pd.DataFrame:
    """Rows as ``ex26_grasp.condition_rows`` gives them: per truth ``(blind success, [(probed grip, realized)])``
    with F_lift 1 N, one Blind-Bayes row per probed seed."""
    rows = []
    for n, (truth, (blind, probed)) in enumerate(truths.items()):
        for rep, (grip, failed) in enumerate(probed):
            common = {"instance_id": f"i{n}", "repeat": rep, "status": "ok", "feasible": True, "truth": truth,
                      "z_true": 1.0}
            rows.append({**common, "method": "blind_bayes", "k": 0, "realized": 1.0 - blind, "action": 1.2})
            rows.append({**common, "method": "probe_robust", "k": 8, "realized": failed, "action": grip})
    return pd.DataFrame(rows).assign(condition=condition, ceiling=5.0, c=4.0)


def test_held_summary_counts_the_blind_held_truths_failures_and_crushes():
    rows = _rows({"a": (1.0, [(1.2, 0.0), (1.6, 1.0), (0.9, 1.0), (1.3, 0.0)]),  # held: one crush, one slip
                  "b": (1.0, [(1.2, 0.0), (1.2, 0.0), (1.2, 0.0), (1.2, 0.0)]),  # held, ties
                  "c": (0.0, [(1.2, 0.0), (2.0, 1.0), (2.0, 1.0), (2.0, 1.0)])})  # not held: improves by 0.25
    got = ex26_grasp.held_summary(rows.drop(columns=["condition", "ceiling", "c"]))
    assert (got["held_truths"], got["held_seeds"], got["held_failures"], got["held_crush"]) == (2, 8, 2, 1)
    assert got["held_grip_ratio"] == 1.2 and got["lowest_probed"] == 0.25
    assert got["held_tie_chance"] == pytest.approx(0.75 ** 160)
    keys = ex26_grasp.summary(rows)
    assert (keys["c4.n_feasible"], keys["c4.n_improve"], keys["c4.n_tie"], keys["c4.n_worse"]) == (3, 1, 1, 1)
    assert keys["c4.worst_difference"] == -0.5 and keys["c4.c"] == 4.0 and keys["c4.ceiling"] == 5.0


def test_held_summary_with_no_held_truth_reads_nan_not_an_error():
    got = ex26_grasp.held_summary(_rows({"c": (0.0, [(1.2, 0.0)])}).drop(columns=["condition", "ceiling", "c"]))
    assert got["held_truths"] == 0 and got["held_failures"] == 0 and math.isnan(got["held_grip_ratio"])


def test_declared_conditions_match_the_registry_prefixes():
    assert [name for name, _, _ in ex26_grasp.CONDITIONS] == list(claims.EX26_SCALES + claims.EX26_CEILINGS)
    assert [(limit, c) for _, limit, c in ex26_grasp.CONDITIONS] == [(5.0, 1.0), (5.0, 2.0), (5.0, 4.0),
                                                                      (2.0, 4.0), (2.5, 4.0)]
    for number in ("E178", "E179"):
        keys = claims.EXPERIMENTS[number].keys
        assert len(set(keys.values())) == len(keys)


def _values(**over: tuple[int, int]) -> dict[str, float]:
    v: dict[str, float] = {}
    for p in claims.EX26_SCALES + claims.EX26_CEILINGS:
        f, w = over.get(p, (13, 3))
        v.update({f"{p}f": f, f"{p}w": w})
    return v


def test_e178_needs_no_worsening_at_c4():
    holds = claims.EXPERIMENTS["E178"].supports
    assert not holds(_values(c4=(13, 1)))
    assert holds(_values(c4=(13, 0)))
    assert not holds(_values(c2=(13, 0)))  # c = 2 is published, not tested


def test_e179_needs_six_give_or_take_one_feasible_and_no_worsening_at_one_ceiling():
    holds = claims.EXPERIMENTS["E179"].supports
    assert not holds(_values(cap20_c4=(5, 1), cap25_c4=(7, 2)))  # E133's outcome at c = 1
    assert holds(_values(cap20_c4=(5, 0)))
    assert holds(_values(cap25_c4=(7, 0), cap20_c4=(5, 1)))
    assert not holds(_values(cap25_c4=(8, 0)))  # no worsening, but eight feasible
    assert not holds(_values(c4=(6, 0)))  # the frozen ceiling is E178's, not E179's


def test_t09_credits_neither_e179_nor_e178():
    """E179's rule drops the claim's "half improve" and its improvements are not the paper's spread (credA)."""
    t09 = next(c for c in claims.CLAIMS if c.id == "T09-grasp")
    assert "E179" not in t09.explain and "E178" not in t09.explain
    assert np.isfinite(claims.paper_values.value("T09-grasp.improve_min"))


def test_verify_recomputes_the_keys_from_the_stored_rows(tmp_path):
    from probecommit.report import recompute

    rows = _rows({"a": (1.0, [(1.2, 0.0), (1.6, 1.0)]), "c": (0.0, [(1.2, 0.0), (2.0, 1.0)])})
    keys = ex26_grasp.summary(rows)
    rows.to_parquet(tmp_path / ex26_grasp.STORED)
    assert ("ex26_grasp", ex26_grasp.STORED, "ex26_grasp") in recompute.STORED_SUMMARIES
    out = recompute.Recomputed()
    recompute._stored_summaries(tmp_path, {"ex26_grasp": keys}, out)
    assert {k: v for k, v in out.values.items() if k.startswith("ex26_grasp.")} == {f"ex26_grasp.{k}": v
                                                                                   for k, v in keys.items()}
    (tmp_path / ex26_grasp.STORED).unlink()
    missing = recompute.Recomputed()
    recompute._stored_summaries(tmp_path, {"ex26_grasp": keys}, missing)
    assert any(not ok and "ex26_grasp" in msg for ok, msg in missing.consistency)  # published keys need their rows
