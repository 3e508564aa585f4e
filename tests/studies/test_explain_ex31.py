"""ex31's E193 (Table III's original arm read one tap later): hand cases with exact answers, same-seed equality,
the rule's wiring and verify's round trip."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex20_band, ex31_shift
from probecommit.studies.explain.stored import recompute_bootstrapped
from probecommit.studies.paper_values import value

from .recompute_contract import assert_bootstrapped_round_trip

DESIGN = {"x_low": -10.0, "x_high": 10.0, "c_low": 0.7, "c_high": 1.3, "r": 1.2, "delta": 0.905, "repeats": 4.0}
BOOT = {"resamples": 50, "seed": 7}


def _rows(seed: int = 0, taps: tuple[int, ...] = ex31_shift.TAPS, instances: int = 24) -> pd.DataFrame:
    """Band rows of the stored form: every instance's four repeats at each tap count, hits nested in the taps."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(instances):
        for rep in range(4):
            first = int(rng.integers(1, 25))  # the tap that first hits the band (7 or later: none within six)
            for t in taps:
                hit = first <= t
                out.append({"draw": ex20_band.FROZEN, "instance_id": f"i{i:02d}", "repeat": rep, "k": t,
                            "realized": float(rng.random() < (0.8 if hit else 0.3)), "predicted": float(rng.random()),
                            "covered": bool(not hit or rng.random() < 0.6), "escaped": bool(hit and rng.random() < 0.3),
                            "hit": hit, **DESIGN})
    return pd.DataFrame(out)


def test_taps_are_table_iii_budgets_one_later_and_claims_agree():
    assert ex31_shift.TAPS == tuple(k + 1 for k in ex31_shift.PAPER_BUDGETS) == (2, 3, 4, 6)
    assert max(ex31_shift.TAPS) <= 8  # the random run's last tap
    assert claims.EX31_SHIFTED == tuple(zip(ex31_shift.PAPER_BUDGETS, ex31_shift.TAPS))


def test_escape_keys_hand_case():
    rows = pd.DataFrame({"k": [2] * 4, "hit": [True, True, False, False], "escaped": [True, False, False, False]})
    got = ex31_shift.escape_keys(rows, {2: (0.25, 0.5)})
    assert got == {"escape.k2": 0.25, "escape_hit.k2": 0.5, "escape_free.k2": 0.0, "escape_std.k2": 0.125}


def test_keys_are_ex20s_frozen_cells_at_the_shifted_taps_and_same_seed_equal():
    rows = _rows()
    a, b = ex31_shift.keys(rows, BOOT), ex31_shift.keys(_rows(), BOOT)
    assert a == pytest.approx(b, nan_ok=True)
    assert a["shift"] == 1 and not set(ex31_shift.LEFT_OUT) & set(a)
    from probecommit.tasks.insertion.model import InsertionModel

    grid = [float(u) for u in np.asarray(InsertionModel.probe_grid, dtype=float).reshape(-1)]
    p = ex20_band.design_probabilities(grid, DESIGN, ex31_shift.TAPS)
    ref = ex20_band.frozen_keys(rows, p, BOOT["resamples"], BOOT["seed"])
    for t in ex31_shift.TAPS:
        for name in ("optimism_std", "optimism_std_lo", "optimism_std_hi", "cluster_coverage_std", "p_design"):
            assert math.isclose(a[f"{name}.k{t}"], ref[f"{name}.k{t}"])
        at = rows[rows["k"] == t]
        assert math.isclose(a[f"escape.k{t}"], at["escaped"].mean())
    assert a["p_design.k2"] < a["p_design.k3"] < a["p_design.k4"] < a["p_design.k6"]


def _resolved(width: float) -> dict[str, float]:
    """E193's resolved keys with every interval ``width`` either side of the paper's cell."""
    v: dict[str, float] = {}
    for k, _ in claims.EX31_SHIFTED:
        o, c = value(f"tab:audit.optimism_original.{k}"), value(f"tab:audit.cluster_coverage_original.{k}")
        v.update({f"lo{k}": o - width, f"hi{k}": o + width, f"clo{k}": c - width, f"chi{k}": c + width})
    return v


def test_e193_rule_is_joint_over_the_eight_cells():
    e = claims.EXPERIMENTS["E193"]
    assert e.supports(_resolved(0.01))
    for name in ("hi5", "chi1", "lo3", "clo2"):
        v = _resolved(0.01)
        v[name] = v[name] - 0.02 if name.startswith(("hi", "chi")) else v[name] + 0.02
        assert not e.supports(v), name


def test_e193_is_registered_for_table_iii_original_k2_optimism_only():
    audit = next(c for c in claims.CLAIMS if c.id == "tab:audit")
    assert ("E193", ("optimism original k=2",)) in claims.explanations(audit)
    assert set(claims.EXPERIMENTS["E193"].keys.values()) >= {f"explain:results.ex31_shift.optimism_std_hi.k{t}"
                                                             for t in ex31_shift.TAPS}


def test_verify_recomputes_every_key_from_the_stored_rows(tmp_path):
    rows = _rows(3)
    assert_bootstrapped_round_trip(tmp_path, ex31_shift, rows, ex31_shift.keys(rows, BOOT), BOOT)
    assert recompute_bootstrapped(tmp_path, {}, ex31_shift.GROUP, ex31_shift.STORED, lambda r: {}) == {}


def test_wired_into_verify_and_the_explain_target():
    from probecommit.report import recompute
    from probecommit.studies.explain import study

    assert "ex31_shift" in recompute.BOOTSTRAPPED and ex31_shift.STORED_BY_GROUP == {ex31_shift.GROUP: ex31_shift.STORED}
    assert study.ex31_shift is ex31_shift
