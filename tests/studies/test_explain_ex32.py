"""ex32's E196/E197 (Table II's push1d and hinge Probe-Robust cells against the action grid's floor): the floor and
half step on hand cases with exact answers, the keys on hand-built rows (each condition's teeth), the claim's wiring
and the stored rows' round trip."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex32_floor as ex

from .recompute_contract import assert_round_trip


def _model(family: str):
    from probecommit.runner.build import build_model
    from probecommit.studies.breadth import paper_config

    return build_model(paper_config(family))


@pytest.mark.parametrize("family", ["push1d", "hinge"])
def test_floor_and_half_step_on_a_target_the_grid_hits_and_one_between(family):
    """A target equal to a grid action's outcome at the truth has floor 0; one halfway between two adjacent outcomes
    has floor and half step both half their difference; one beyond the grid's reach has half step = floor."""
    model = _model(family)
    truth = np.array([(lo + hi) / 2 for lo, hi in zip(model.prior_low, model.prior_high)])
    grid = np.asarray(model.action_grid, float)[:, 0]
    d = np.asarray(model.commit_outcome(grid, *truth), float)
    j = int(np.searchsorted(d, 1.0))
    floor, half = ex.floor_and_half_step(model, truth, np.array([d[j]]))
    assert floor == pytest.approx(0.0, abs=1e-12) and half == pytest.approx((d[j + 1] - d[j]) / 2)
    mid = (d[j] + d[j + 1]) / 2
    floor, half = ex.floor_and_half_step(model, truth, np.array([mid]))
    assert floor == pytest.approx((d[j + 1] - d[j]) / 2) and half == pytest.approx(floor)
    floor, half = ex.floor_and_half_step(model, truth, np.array([d[-1] + 0.3]))
    assert floor == pytest.approx(0.3) and half == floor


def test_push2d_floor_is_the_grid_minimum_and_has_no_half_step():
    model = _model("push2d")
    truth = np.array([0.4, 1.0, 1.75])
    target = np.array([0.8, 0.1])
    floor, half = ex.floor_and_half_step(model, truth, target)
    grid = np.asarray(model.action_grid, float)
    assert floor == pytest.approx(float(np.min(np.asarray(model.loss(grid, truth[None], target))[:, 0])))
    assert np.isnan(half) and floor > 0


def _paper(family: str) -> tuple[float, float]:
    from probecommit.studies.explain.ex16_reach import implied_k2
    from probecommit.studies.paper_values import value

    return value(f"tab:breadth.{family}.probe_robust"), implied_k2(family)


def _rows(family: str, miss: dict[int, float], floor: float, half: float, model_scale: float = 1.0) -> pd.DataFrame:
    """Two instances x two repeats per budget, the budget's miss -+ 0.001 on instance a / b (its mean exact, its
    interval at least that wide)."""
    rows = [{"family": family, "instance_id": inst, "repeat": rep, "k": k, "realized": m + e,
             "model": (m + e) * model_scale, "floor": floor, "half": half}
            for k, m in miss.items() for inst, e in (("a", -0.001), ("b", 0.001)) for rep in (0, 1)]
    return pd.DataFrame(rows)


@pytest.mark.parametrize("family", ["push1d", "hinge"])
def test_keys_hold_when_the_floor_is_the_gap_and_each_condition_has_teeth(family):
    p5, p2 = _paper(family)
    h = 0.02  # ours = paper + h at both budgets: removing the half step gives the paper's points exactly
    k = ex.family_keys(_rows(family, {2: p2 + h, 5: p5 + h}, floor=1.01 * h, half=h), family)
    assert k["holds"] == 1 and k["floor_covers_gap"] == 1 and k["premise_holds"] == 1
    assert k["gap"] == pytest.approx(h) and k["removed.k5"] == pytest.approx(p5) and k["episodes"] == 4
    assert k["floor_share"] == pytest.approx(1.01 * h / (p5 + h)) and k["half_max"] == h
    small = ex.family_keys(_rows(family, {2: p2 + h, 5: p5 + h}, floor=h / 2, half=h), family)
    assert small["floor_covers_gap"] == 0 and small["removed.k5_paper_inside"] == 1 and small["holds"] == 0
    wrong_k2 = ex.family_keys(_rows(family, {2: p2 + 2 * h, 5: p5 + h}, floor=1.01 * h, half=h), family)
    assert wrong_k2["removed.k2_paper_inside"] == 0 and wrong_k2["holds"] == 0
    model_off = ex.family_keys(_rows(family, {2: p2 + h, 5: p5 + h}, 1.01 * h, h, 1 + 2 * ex.FAMILIES[family]),
                               family)
    assert model_off["premise_holds"] == 0 and model_off["holds"] == 0
    clipped = ex.family_keys(_rows(family, {2: p2 + h, 5: h / 2}, floor=h, half=h), family)
    assert clipped["removed.k5"] == 0.0  # a miss below the half step is floored at zero


def test_push2d_publishes_its_floor_only():
    k = ex.family_keys(_rows("push2d", {2: 0.2, 5: 0.1}, floor=0.01, half=np.nan), "push2d")
    assert k["floor.k5"] == pytest.approx(0.01) and k["floor_share"] == pytest.approx(0.1)
    assert "holds" not in k and "removed.k5" not in k


def test_e196_e197_speak_to_the_probe_cells_and_supports_reads_the_rule():
    breadth = next(c for c in claims.CLAIMS if c.id == "tab:breadth")
    spoken = {e[0]: e[1] for e in breadth.explain if isinstance(e, tuple)}
    assert spoken["E196"] == ("push1d probe_robust",) and spoken["E197"] == ("hinge probe_robust",)
    assert "E198" not in claims.EXPERIMENTS
    e = claims.EXPERIMENTS["E196"]
    assert e.supports({"ok": 1, "cov": 1, "in5": 1, "in2": 1, "holds": 1})
    for off in ("ok", "cov", "in5", "in2", "holds"):
        assert not e.supports({"ok": 1, "cov": 1, "in5": 1, "in2": 1, "holds": 1} | {off: 0})


def test_stored_rows_round_trip(tmp_path):
    from probecommit.studies.explain import ex32

    p5, p2 = _paper("push1d")
    rows = pd.concat([_rows("push1d", {2: p2 + 0.02, 5: p5 + 0.02}, 0.021, 0.02),
                      _rows("hinge", {2: 0.1, 5: 0.08}, 0.001, 0.002),
                      _rows("push2d", {2: 0.2, 5: 0.1}, 0.01, np.nan)], ignore_index=True)
    keys = ex.keys(rows)
    assert keys["push1d.holds"] == 1 and keys["hinge.holds"] == 0 and "push2d.holds" not in keys
    assert_round_trip(tmp_path, ex32.recompute, "ex32_floor", ex.STORED, rows, keys)
