"""ex27's E182..E184 (Table II's hinge row with the commit a torque): the keys on hand-built rows with exact answers
(each condition's teeth), the claim's wiring and the stored rows' round trip."""

from __future__ import annotations

import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex27_torque as et

from .recompute_contract import assert_round_trip


def _paper() -> tuple[float, float, float]:
    from probecommit.studies.explain.ex16_reach import implied_k2
    from probecommit.studies.paper_values import value

    return value("tab:breadth.hinge.probe_robust"), implied_k2("hinge"), value("tab:breadth.hinge.blind_bayes")


def _rows(cells: dict[str, tuple[float, float, float]], scene: float = 0.001, spread: float = 0.0) -> pd.DataFrame:
    """Per part ``(blind_bayes, k2, k5)``: two instances x two repeats per cell; instance b's misses are ``1 + spread``
    times a's; every torque part gets two premise rows with ``scene`` as the larger difference."""
    rows = []
    for part, (bb, k2, k5) in cells.items():
        for method, k, miss in (("blind_bayes", 0, bb), ("probe_robust", 2, k2), ("probe_robust", 5, k5)):
            for inst, f in (("a", 1.0), ("b", 1.0 + spread)):
                rows += [{"family": "hinge", "part": part, "method": method, "instance_id": inst, "repeat": r,
                          "k": k, "realized": miss * f} for r in (0, 1)]
        if part != "stored":
            rows += [{"family": "hinge", "part": f"scene.{part}", "method": "scene", "instance_id": f"corner{i}",
                      "repeat": 0, "k": -1, "realized": d} for i, d in enumerate((scene / 2, scene))]
    return pd.DataFrame(rows)


def test_keys_need_every_cell_the_ratio_the_stored_ratio_outside_and_the_premise():
    p5, p2, pb = _paper()
    good = {"stored": (0.42, 0.107, 0.076), "impulse": (pb, p2, p5), "d025": (0.42, 0.107, 0.076)}
    k = et.keys(_rows(good))
    assert k["impulse.holds"] == 1 and k["impulse.ratio_k2_k5"] == pytest.approx(p2 / p5)
    assert k["impulse.premise_holds"] == 1 and k["impulse.scene_max_diff"] == pytest.approx(0.001)
    assert k["stored_ratio_paper_outside"] == 1 and k["episodes"] == 4 and k["impulse.push_s"] == 0.0
    assert k["d025.k5_paper_inside"] == 0 and k["d025.holds"] == 0  # each duration its own rule
    assert "d1.holds" not in k and k["paper.bb"] == pb
    blind_off = et.keys(_rows({**good, "impulse": (pb * 2, p2, p5)}))  # the row's other cell broken
    assert blind_off["impulse.bb_paper_inside"] == 0 and blind_off["impulse.holds"] == 0
    flat = et.keys(_rows({**good, "impulse": (pb, p2, p2 / 1.5)}, spread=0.5))  # k2 inside, ratio 1.5
    assert flat["impulse.k2_paper_inside"] == 1 and flat["impulse.ratio_paper_inside"] == 0
    assert flat["impulse.holds"] == 0
    same_shape = et.keys(_rows({**good, "stored": (0.42, p2, p5)}))  # the cause removed gives the same ratio
    assert same_shape["stored_ratio_paper_outside"] == 0 and same_shape["impulse.holds"] == 0
    off = et.keys(_rows(good, scene=0.006))  # MuJoCo 6 mrad from the closed form > 5 mrad
    assert off["impulse.premise_holds"] == 0 and off["impulse.holds"] == 0


def test_e182_to_e184_speak_to_the_hinge_probe_cell_and_need_every_condition():
    breadth = next(c for c in claims.CLAIMS if c.id == "tab:breadth")
    spoken = {e[0]: e[1] for e in breadth.explain if isinstance(e, tuple)}
    assert spoken["E182"] == spoken["E183"] == spoken["E184"] == ("hinge probe_robust",)
    assert claims.EXPERIMENTS["E183"].keys["holds"].endswith("ex27_torque.d025.holds")
    all_hold = {"ok": 1, "holds": 1, "in5": 1, "in2": 1, "inq": 1, "inb": 1, "outq": 1}
    for number in ("E182", "E183", "E184"):
        e = claims.EXPERIMENTS[number]
        assert e.supports(all_hold)
        for name in all_hold:
            assert not e.supports({**all_hold, name: 0})


def test_quick_torque_rerun_is_seeded_like_the_run():
    a, b = et.torque_episodes("d025", True), et.torque_episodes("d025", True)
    assert set(a["method"]) == {"blind_bayes", "probe_robust"} and (a["status"] == "ok").all()
    assert a["realized"].tolist() == b["realized"].tolist()


def test_stored_rows_round_trip(tmp_path):
    from probecommit.studies.explain import ex27

    p5, p2, pb = _paper()
    rows = _rows({"stored": (0.42, 0.107, 0.076), "impulse": (pb, p2, p5), "d025": (0.5, 0.11, 0.09),
                  "d1": (0.5, 0.12, 0.1)})
    keys = et.keys(rows)
    assert ex27.recompute(tmp_path, {"ex27_torque": keys})[2]  # published without its rows
    assert_round_trip(tmp_path, ex27.recompute, "ex27_torque", et.STORED, rows, keys)
