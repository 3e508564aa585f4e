"""ex25's E174/E175 (Table II's push1d and hinge Probe-Robust cells with probes uniform over the frozen grid's span):
the interval grid, the keys on hand-built rows with exact answers (each condition's teeth), the claim's wiring and the
stored rows' round trip."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex25_uniform as eu

from .recompute_contract import assert_round_trip


def _paper(family: str) -> tuple[float, float]:
    from probecommit.studies.explain.ex16_reach import implied_k2
    from probecommit.studies.paper_values import value

    return value(f"tab:breadth.{family}.probe_robust"), implied_k2(family)


def _rows(family: str, cells: dict[str, tuple[float, float]], spread: float = 0.0) -> pd.DataFrame:
    """Per part, two instances x two repeats per budget; instance b's misses are ``1 + spread`` times a's (the ratio
    is then the same in every resample, and the cells' intervals widen with ``spread``)."""
    rows = []
    for part, (k2, k5) in cells.items():
        for k, miss in ((2, k2), (5, k5)):
            for inst, f in (("a", 1.0), ("b", 1.0 + spread)):
                rows += [{"family": family, "part": part, "instance_id": inst, "repeat": r, "k": k,
                          "realized": miss * f} for r in (0, 1)]
    return pd.DataFrame(rows)


def test_interval_grid_spans_the_frozen_grid_in_one_percent_steps():
    grid = eu.interval_grid(np.array([[1.0], [2.0], [3.0]]))
    assert len(grid) == 201 and grid[0] == 1.0 and grid[100] == 2.0 and grid[-1] == 3.0
    assert np.allclose(np.diff(grid), 0.01)
    assert eu.interval_grid(np.array([1.5, 0.5, 1.0]), 3) == (0.5, 1.0, 1.5)


def test_keys_need_both_cells_the_ratio_and_the_grid_ratio_outside():
    p5, p2 = _paper("hinge")
    good = {"stored": (0.1, 0.07), "grid": (0.1, 0.07), "interval": (p2, p5), "ends": (0.1, 0.07)}
    k = eu.keys(_rows("hinge", good))
    h = {n[len("hinge."):]: v for n, v in k.items() if n.startswith("hinge.")}
    assert h["premise_holds"] == 1 and h["interval.ratio_k2_k5"] == pytest.approx(p2 / p5)
    assert h["interval.k5_paper_inside"] == h["interval.k2_paper_inside"] == h["interval.ratio_paper_inside"] == 1
    assert h["grid_ratio_paper_outside"] == 1 and h["interval.holds"] == 1 and h["episodes"] == 4
    assert h["ends.ratio_paper_inside"] == 0 and h["ends.holds"] == 0  # each condition its own rule
    assert "push1d.interval.holds" not in k and k["points"] == 201
    same_shape = eu.keys(_rows("hinge", {**good, "grid": (p2, p5), "stored": (p2, p5)}))  # the cause removed: same ratio
    assert same_shape["hinge.grid_ratio_paper_outside"] == 0 and same_shape["hinge.interval.holds"] == 0
    flat = eu.keys(_rows("hinge", {**good, "interval": (p2, p2 / 1.5)}, spread=0.5))  # k2 inside, ratio 1.5
    assert flat["hinge.interval.k2_paper_inside"] == 1 and flat["hinge.interval.ratio_paper_inside"] == 0
    assert flat["hinge.interval.holds"] == 0
    off = eu.keys(_rows("hinge", {**good, "grid": (0.1, 0.07 * 1.06)}))  # premise 6 % > 5 %
    assert off["hinge.premise_holds"] == 0 and off["hinge.interval.holds"] == 0
    without_ends = eu.keys(_rows("hinge", {n: v for n, v in good.items() if n != "ends"}))
    assert "hinge.ends.holds" not in without_ends and without_ends["hinge.interval.holds"] == 1


def test_push1d_premise_is_exact():
    p5, p2 = _paper("push1d")
    k = eu.keys(_rows("push1d", {"stored": (0.12, 0.085), "grid": (0.12, 0.085 * (1 + 1e-6)), "ends": (p2, p5)}))
    assert k["push1d.premise_holds"] == 0 and k["push1d.ends.holds"] == 0
    k = eu.keys(_rows("push1d", {"stored": (0.12, 0.085), "grid": (0.12, 0.085), "ends": (p2, p5)}))
    assert k["push1d.premise_holds"] == 1 and k["push1d.ends.holds"] == 1


def test_interval_grid_ends_grid():
    assert eu.ends_grid(np.array([[0.5], [1.0], [1.5]])) == (0.5, 1.5)


def test_e174_to_e177_speak_to_the_probe_cells_and_need_every_condition():
    breadth = next(c for c in claims.CLAIMS if c.id == "tab:breadth")
    spoken = {e[0]: e[1] for e in breadth.explain if isinstance(e, tuple)}
    assert spoken["E174"] == spoken["E177"] == ("push1d probe_robust",)
    assert spoken["E175"] == spoken["E176"] == ("hinge probe_robust",)
    assert claims.EXPERIMENTS["E176"].keys["holds"].endswith("ex25_uniform.hinge.ends.holds")
    all_hold = {"ok": 1, "holds": 1, "in5": 1, "in2": 1, "inq": 1, "outq": 1}
    for number in ("E174", "E175", "E176", "E177"):
        e = claims.EXPERIMENTS[number]
        assert e.supports(all_hold)
        for name in all_hold:
            assert not e.supports({**all_hold, name: 0})


def test_stored_rows_round_trip(tmp_path):
    from probecommit.studies.explain import ex25

    p5, p2 = _paper("push1d")
    rows = pd.concat([_rows("push1d", {"stored": (0.12, 0.085), "grid": (0.12, 0.085), "interval": (p2, p5),
                                       "ends": (0.12, 0.08)}),
                      _rows("hinge", {"stored": (0.1, 0.07), "grid": (0.1, 0.07), "interval": (0.1, 0.08)})])
    keys = eu.keys(rows)
    assert ex25.recompute(tmp_path, {"ex25_uniform": keys})[2]  # published without its rows
    assert_round_trip(tmp_path, ex25.recompute, "ex25_uniform", eu.STORED, rows, keys)
