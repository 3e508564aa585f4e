"""ex16's explain experiments (E124, E125): the declared grid, the paper's implied k = 2 point, hand cases with exact
answers, the rule's teeth, the in-memory rerun against the runner, and the stored rows' round trip."""

from __future__ import annotations

import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex16_reach as er

from .recompute_contract import assert_round_trip


def _rows(family: str, cells: dict[tuple[str, int], tuple[float, float]], repeats: int = 2) -> pd.DataFrame:
    """Two instances per (part, k) with the given misses, every repeat the same (exact means)."""
    rows = []
    for (part, k), (a, b) in cells.items():
        for inst, miss in (("i0", a), ("i1", b)):
            rows += [{"family": family, "part": part, "instance_id": inst, "repeat": r, "k": k, "target": 1.0,
                      "realized": miss} for r in range(repeats)]
    return pd.DataFrame(rows)


def _cells(stored: tuple[float, float], scene: tuple[float, float], reach2: tuple[float, float],
           reach5: tuple[float, float]) -> dict[tuple[str, int], tuple[float, float]]:
    return {("stored", 2): (0.2, 0.2), ("stored", 5): stored, ("scene", 2): (0.2, 0.2), ("scene", 5): scene,
            ("reach", 2): reach2, ("reach", 5): reach5}


@pytest.mark.parametrize("family", list(er.FAMILIES))
def test_the_declared_grid_is_the_probes_whose_centre_outcome_is_each_target(family):
    from probecommit.runner.build import build_model

    model = build_model(er._config(family, None, quick=False))
    assert er.reach_grid(model, (0.5, 1.0, 1.5)) == er.FAMILIES[family][0]
    # at the prior's centre the frozen grid's largest probe stops short of the middle target: the cause under test
    assert er.reach_grid(model, (1.0,))[0] > float(model.probe_grid.max())


def test_the_papers_k2_point_follows_from_its_k5_cell_and_five_below_price():
    assert er.implied_k2("hinge") == pytest.approx(0.031 + 3 * 0.012, abs=1e-12)
    assert er.implied_k2("push1d") == pytest.approx(0.062 + 3 * 0.019, abs=1e-12)  # the price in cm


def test_keys_hand_case_inside_both_points():
    rows = _rows("hinge", _cells((0.07, 0.08), (0.07, 0.08), (0.06, 0.07), (0.03, 0.032)))
    k = er.keys(rows)
    assert k["hinge.stored.k5"] == pytest.approx(0.075) and k["hinge.scene.k5"] == pytest.approx(0.075)
    assert k["hinge.reach.k5_lo"] == pytest.approx(0.03) and k["hinge.reach.k5_hi"] == pytest.approx(0.032)
    assert k["hinge.reach.k2"] == pytest.approx(0.065) and k["hinge.reach.ratio_k2_k5"] == pytest.approx(0.065 / 0.031)
    assert k["hinge.premise_holds"] == 1 and k["hinge.premise_rel_diff"] == 0
    assert k["hinge.reach.k5_paper_inside"] == 1 and k["hinge.reach.k2_paper_inside"] == 1 and k["hinge.holds"] == 1
    assert k["hinge.episodes"] == 4 and (k["hinge.grid.0"], k["hinge.grid.2"]) == (1.54, 3.10)


def test_keys_fail_when_a_point_or_the_premise_fails():
    k2_out = er.keys(_rows("hinge", _cells((0.07, 0.08), (0.07, 0.08), (0.04, 0.05), (0.03, 0.032))))
    assert k2_out["hinge.reach.k5_paper_inside"] == 1 and k2_out["hinge.reach.k2_paper_inside"] == 0
    assert k2_out["hinge.holds"] == 0
    premise = er.keys(_rows("hinge", _cells((0.07, 0.08), (0.08, 0.09), (0.06, 0.07), (0.03, 0.032))))
    assert premise["hinge.premise_rel_diff"] == pytest.approx(0.01 / 0.075) and premise["hinge.premise_holds"] == 0
    assert premise["hinge.holds"] == 0
    exact = er.keys(_rows("push1d", _cells((0.08, 0.09), (0.08, 0.09 + 1e-6), (0.11, 0.13), (0.06, 0.065))))
    assert exact["push1d.premise_holds"] == 0  # push1d's rerun must be the stored run itself


def test_experiments_support_only_with_the_premise_and_both_points():
    for number in ("E124", "E125"):
        e = claims.EXPERIMENTS[number]
        assert e.supports({"ok": 1, "in5": 1, "in2": 1})
        assert not e.supports({"ok": 1, "in5": 1, "in2": 0}) and not e.supports({"ok": 0, "in5": 1, "in2": 1})
    breadth = next(c for c in claims.CLAIMS if c.id == "tab:breadth")
    spoken = {e[0]: e[1] for e in breadth.explain if isinstance(e, tuple)}
    assert spoken["E124"] == ("hinge probe_robust",) and spoken["E125"] == ("push1d probe_robust",)


@pytest.mark.slow
def test_the_in_memory_rerun_equals_the_runner_and_the_grid_is_used(tmp_path):
    from probecommit.runner.study import run_study

    config = er._config("hinge", "analytic", quick=True)
    stored = run_study(config, tmp_path / config.name, workers=1, threads=1).episodes
    mine = er.episodes_with_grid(config, None)
    key = ["instance_id", "repeat", "k", "method"]
    a, b = (t.sort_values(key).reset_index(drop=True) for t in (stored, mine))
    assert list(a["realized"]) == list(b["realized"]) and list(a["action"]) == list(b["action"])
    reach = er.episodes_with_grid(config, er.FAMILIES["hinge"][0]).sort_values(key).reset_index(drop=True)
    assert list(reach["realized"]) != list(a["realized"])


def test_stored_rows_round_trip_through_verify(tmp_path):
    from probecommit.studies.explain import ex16

    rows = _rows("hinge", _cells((0.07, 0.08), (0.07, 0.08), (0.06, 0.07), (0.03, 0.032)))
    assert_round_trip(tmp_path, ex16.recompute, "ex16_reach", er.STORED, rows, er.keys(rows))


def test_no_breadth_runs_no_keys(tmp_path):
    keys, rows = er.run(tmp_path)
    assert keys == {} and rows.empty
