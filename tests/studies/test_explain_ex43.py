"""ex43's E232 (Table III's calibrated columns read as set calibration alone): hand cases with exact answers, the
re-commit on a small analytic run against its stored commits, same-seed equality, the rule's wiring and verify's
round trip."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex43_setonly
from probecommit.studies.paper_values import value

from .recompute_contract import assert_bootstrapped_round_trip

BOOT = {"resamples": 40, "seed": 7}
T_K = {1: 0.3, 2: 1.0, 3: 1.0, 5: 1.0, 8: 1.0}


def _hand_rows() -> pd.DataFrame:
    """Two instances x two repeats at every budget, both arms; the set arm predicts 0.25 and realizes 0.5 on every
    episode, the margin arm predicts 0.75 and realizes 0.5 on instance a and 1.0 on instance b; a's repeat 1 is not
    covered."""
    out = []
    for arm, gamma in zip(ex43_setonly.ARMS, (1.0, 0.56)):
        for k in ex43_setonly.BUDGETS:
            for inst in ("a", "b"):
                for rep in (0, 1):
                    pred, real = (0.25, 0.5) if arm == "set" else (0.75, 0.5 if inst == "a" else 1.0)
                    out.append({"instance_id": inst, "repeat": rep, "k": k, "method": "probe_robust",
                                "variant": "deployed", "status": "ok", "predicted": pred, "realized": real,
                                "covered": not (inst == "a" and rep == 1), "escaped": False, "arm": arm,
                                "gamma": gamma, "threshold": T_K[k]})
    return pd.DataFrame(out)


def test_keys_by_hand_and_same_seed_equal():
    out = ex43_setonly.keys(_hand_rows(), BOOT)
    for k in ex43_setonly.BUDGETS:
        s = f".k{k}"
        assert out[f"set.optimism{s}"] == pytest.approx(0.25, abs=1e-15)
        assert out[f"set.optimism_lo{s}"] == pytest.approx(0.25, abs=1e-15)  # no spread between instances
        assert out[f"set_margin.optimism{s}"] == pytest.approx(0.0, abs=1e-15)  # (-0.25 + 0.25) / 2
        assert out[f"set_margin.predicted{s}"] == 0.75 and out[f"set.realized{s}"] == 0.5
        assert out[f"set.cluster_coverage{s}"] == 0.5 and out[f"set.coverage{s}"] == 0.75
        assert out[f"t{s}"] == T_K[k]
    assert out["gamma"] == 0.56
    assert ex43_setonly.keys(_hand_rows(), BOOT) == out


def test_published_calibration_and_the_check_read_table_iii():
    table = [{"k": k, "threshold": t, **{f"{c}_calibrated": 0.1 * k for c in ex43_setonly.CELLS}} for k, t in T_K.items()]
    results = {"table_audit": {"table": table}, "table_insertion": {"margin_random": 0.56}}
    assert ex43_setonly.published_calibration(results) == (T_K, 0.56)
    out = {f"set_margin.{c}.k{k}": 0.1 * k for k in T_K for c in ex43_setonly.CELLS}
    assert ex43_setonly.check_published(out, table) == []
    out["set_margin.optimism.k3"] += 1e-9
    assert ex43_setonly.check_published(out, table) == ["optimism k=3"]


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    """A small analytic random run with eight taps, committed at nu = 0.8 with the model's window."""
    from tests.conftest import table_iii_like_run

    return table_iii_like_run(tmp_path_factory.mktemp("ex43"))


def test_the_set_arm_at_nu_is_the_stored_commit_and_the_margin_arm_at_one_is_the_set_arm(small_run):
    """At t_k = nu and gamma = 1 both arms are the run's own commit: the stored episodes' predictions and outcomes."""
    nu = {k: 0.8 for k in ex43_setonly.BUDGETS}
    rows = ex43_setonly.committed_rows(small_run, nu, 1.0)
    again = ex43_setonly.committed_rows(small_run, nu, 1.0)
    pd.testing.assert_frame_equal(rows, again)
    cols = ["instance_id", "repeat", "k", "predicted", "realized", "covered"]
    key = ["instance_id", "repeat", "k"]
    stored = small_run.episodes
    stored = stored[(stored["method"] == "probe_robust") & stored["k"].isin(ex43_setonly.BUDGETS)]
    stored = stored[cols].sort_values(key).reset_index(drop=True)
    for arm in ex43_setonly.ARMS:
        got = rows[rows["arm"] == arm][cols].sort_values(key).reset_index(drop=True)
        got["instance_id"] = got["instance_id"].astype(str)
        assert np.array_equal(got[key].to_numpy(), stored[key].to_numpy().astype(object))
        for c in ("predicted", "realized", "covered"):
            assert np.array_equal(got[c].to_numpy(float), stored[c].to_numpy(float)), (arm, c)
    shrunk = ex43_setonly.committed_rows(small_run, nu, 0.5)
    assert (shrunk.loc[shrunk["arm"] == "set_margin", "predicted"].to_numpy()
            >= shrunk.loc[shrunk["arm"] == "set", "predicted"].to_numpy() - 1e-12).all()  # a narrower window fails more


def _resolved(width: float) -> dict[str, float]:
    v: dict[str, float] = {}
    for k in claims.AUDIT_K:
        o = value(f"tab:audit.optimism_calibrated.{k}")
        v.update({f"lo{k}": o - width, f"hi{k}": o + width})
    return v


def test_rule_needs_both_cells_and_keeps_the_passing_ones():
    e = claims.EXPERIMENTS["E232"]
    assert e.supports(_resolved(0.01))
    for name in ("hi2", "lo3", "lo1", "hi8"):
        v = _resolved(0.01)
        v[name] = v[name] - 0.02 if name.startswith("hi") else v[name] + 0.02
        assert not e.supports(v), name
    v = _resolved(0.01)
    v["hi5"] = v["lo5"] = 9.0  # k = 5 is beside the rule
    assert e.supports(v)
    audit = next(c for c in claims.CLAIMS if c.id == "tab:audit")
    assert ("E232", ("=optimism calibrated k=2", "=optimism calibrated k=3")) in claims.explanations(audit)


def test_verify_recomputes_every_key_from_the_stored_rows(tmp_path):
    from probecommit.report import recompute

    rows = _hand_rows()
    assert_bootstrapped_round_trip(tmp_path, ex43_setonly, rows, ex43_setonly.keys(rows, BOOT), BOOT)
    assert "ex43_setonly" in recompute.BOOTSTRAPPED
