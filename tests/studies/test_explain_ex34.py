"""ex34's E203/E204 (Table III's original arm with one fixed tap before the random ones): hand cases with exact
answers, same-seed equality, the rerun's taps on a small analytic run, the rules' wiring and verify's round trip."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex20_band, ex34_fixed
from probecommit.studies.paper_values import value

from .recompute_contract import assert_bootstrapped_round_trip

DESIGN = {"x_low": -10.0, "x_high": 10.0, "c_low": 0.7, "c_high": 1.3, "r": 1.2, "delta": 0.905, "repeats": 4.0}
BOOT = {"resamples": 40, "seed": 7}
CELLS = (2000, 60)


def _grid() -> list[float]:
    from probecommit.tasks.insertion.model import InsertionModel

    return [float(u) for u in np.asarray(InsertionModel.probe_grid, dtype=float).reshape(-1)]


def test_a_fixed_tap_lands_in_the_band_of_its_exact_share_of_the_prior_box():
    """At -12 mm the band lies inside the box on one side only (width r + delta of 20 mm), at 0 mm on both sides."""
    width = DESIGN["r"] + DESIGN["delta"]
    for u0, sides in ((-12.0, 1), (0.0, 2)):
        p = ex20_band.design_probabilities(_grid(), DESIGN, (1,), CELLS, fixed=u0)
        assert p[1][0] == pytest.approx(sides * width / 20.0, abs=2e-3)
        assert p[1][1] == pytest.approx(p[1][0])  # a fixed tap hits in every repeat or in none


def test_a_fixed_tap_outside_every_band_delays_the_uniform_design_by_one_tap():
    p = ex20_band.design_probabilities(_grid(), DESIGN, (1, 2, 3, 5), CELLS, fixed=-100.0)
    q = ex20_band.design_probabilities(_grid(), DESIGN, (1, 2, 4), CELLS)
    assert p[1] == (0.0, 0.0)
    for k, j in ((2, 1), (3, 2), (5, 4)):
        assert p[k][0] == pytest.approx(q[j][0])
        assert p[k][1] == pytest.approx(q[j][1])
    assert ex20_band.design_probabilities(_grid(), DESIGN, (2,), CELLS) == ex20_band.design_probabilities(
        _grid(), DESIGN, (2,), CELLS, fixed=None)


def _rows(seed: int = 0, instances: int = 20) -> pd.DataFrame:
    """Band rows of the stored form for both positions, every tap count 1..9, hits nested in the taps."""
    rng = np.random.default_rng(seed)
    out = []
    for label, u0, _ in ex34_fixed.POSITIONS.values():
        for i in range(instances):
            for rep in range(4):
                first = int(rng.integers(1, 16))
                for t in range(1, ex34_fixed.TAPS + 1):
                    hit = first <= t
                    out.append({"draw": label, "instance_id": f"i{i:02d}", "repeat": rep, "k": t,
                                "realized": float(rng.random() < (0.8 if hit else 0.3)), "predicted": float(rng.random()),
                                "covered": bool(not hit or rng.random() < 0.6),
                                "escaped": bool(hit and rng.random() < 0.3), "hit": hit, **DESIGN, "fixed": u0})
    return pd.DataFrame(out)


def test_keys_are_ex20s_cells_at_both_readings_and_same_seed_equal():
    rows = _rows()
    a = ex34_fixed.keys(rows, BOOT)
    assert a == pytest.approx(ex34_fixed.keys(_rows(), BOOT), nan_ok=True)
    for label, u0, _ in ex34_fixed.POSITIONS.values():
        at = rows[rows["draw"] == label]
        p = ex20_band.design_probabilities(_grid(), DESIGN, range(1, ex34_fixed.TAPS + 1), fixed=u0)
        ref = ex20_band.frozen_keys(at[at["k"].isin(ex34_fixed.BUDGETS)], p, BOOT["resamples"], BOOT["seed"])
        plus = ex20_band.frozen_keys(at[at["k"].isin(list(ex34_fixed.PLUS.values()))], p, BOOT["resamples"],
                                     BOOT["seed"])
        assert a[f"{label}.fixed"] == u0 and a[f"{label}.f_band"] == p[1][0]
        for k in ex34_fixed.BUDGETS:
            for name in ("optimism_std", "optimism_std_lo", "cluster_coverage_std_hi", "p_design"):
                assert a[f"{label}.{name}.k{k}"] == pytest.approx(ref[f"{name}.k{k}"], nan_ok=True)
                assert a[f"{label}.plus.{name}.k{k}"] == pytest.approx(plus[f"{name}.k{k + 1}"], nan_ok=True)
        for t in range(1, ex34_fixed.TAPS + 1):
            assert math.isclose(a[f"{label}.escape.k{t}"], at.loc[at["k"] == t, "escaped"].mean())


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    """A small analytic random run with eight taps (the rerun puts its fixed tap before them)."""
    from tests.conftest import table_iii_like_run

    return table_iii_like_run(tmp_path_factory.mktemp("ex34"))


def test_the_rerun_puts_the_fixed_tap_first_and_keeps_the_stored_taps_after_it(small_run):
    from probecommit.tasks.insertion.model import half_gap

    label, u0, tag = ex34_fixed.POSITIONS["E204"]
    episodes, probes = ex34_fixed.prepended(small_run, u0, tag)
    again, probes2 = ex34_fixed.prepended(small_run, u0, tag)
    pd.testing.assert_frame_equal(episodes, again)
    pd.testing.assert_frame_equal(probes, probes2)
    stored = small_run.table("probes").sort_values(["instance_id", "repeat", "j"])
    probes = probes.sort_values(["instance_id", "repeat", "j"])
    assert (probes.loc[probes["j"] == 1, "u"] == u0).all()
    later = probes[probes["j"] > 1]
    assert np.array_equal(later["u"].to_numpy(), stored["u"].to_numpy())
    assert np.array_equal(later["y"].to_numpy(), stored["y"].to_numpy())
    # the fixed tap's reading is the analytic scene's class at the truth, plus noise far below the 15 mm step
    truth = small_run.instances.set_index("instance_id")
    first = probes[probes["j"] == 1].join(truth, on="instance_id")
    pocket = np.abs(u0 - first["true_x_hole"]) < half_gap(first["true_c"].to_numpy()) + 0.905
    assert np.array_equal(first["y"].to_numpy() < -7.5, pocket.to_numpy())
    assert sorted(episodes["k"].unique()) == list(range(1, ex34_fixed.TAPS + 1))
    rows = ex34_fixed.rows_at(small_run, "E204")
    one = rows[rows["k"] == 1].join(truth, on="instance_id")
    band = ex20_band.in_band(np.full(len(one), u0), one["true_x_hole"].to_numpy(), one["true_c"].to_numpy(), 1.2, 0.905)
    assert np.array_equal(one["hit"].to_numpy(bool), band)


def _resolved(width: float) -> dict[str, float]:
    v: dict[str, float] = {}
    for k in claims.EX34_BUDGETS:
        o, c = value(f"tab:audit.optimism_original.{k}"), value(f"tab:audit.cluster_coverage_original.{k}")
        v.update({f"lo{k}": o - width, f"hi{k}": o + width, f"clo{k}": c - width, f"chi{k}": c + width})
    return v


def test_rules_are_joint_over_the_ten_cells_and_registered_for_k2_optimism():
    audit = next(c for c in claims.CLAIMS if c.id == "tab:audit")
    for number in ("E203", "E204"):
        e = claims.EXPERIMENTS[number]
        assert e.supports(_resolved(0.01))
        for name in ("hi8", "chi1", "lo2", "clo5"):
            v = _resolved(0.01)
            v[name] = v[name] - 0.02 if name.startswith(("hi", "chi")) else v[name] + 0.02
            assert not e.supports(v), (number, name)
        assert (number, ("optimism original k=2",)) in claims.explanations(audit)
    assert {label for label, _ in claims.EX34_FIXED.values()} == {label for label, _, _ in ex34_fixed.POSITIONS.values()}


def test_verify_recomputes_every_key_from_the_stored_rows(tmp_path):
    from probecommit.report import recompute

    rows = _rows(3)
    assert_bootstrapped_round_trip(tmp_path, ex34_fixed, rows, ex34_fixed.keys(rows, BOOT), BOOT)
    assert "ex34_fixed" in recompute.BOOTSTRAPPED
