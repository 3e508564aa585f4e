"""ex39's E218 (PyBullet's capture window against a compliant plate contact): the keys by hand, the rule at its
edges, the grid and the contact it sets, the step's wiring, a compliant plate widening a real PyBullet window,
registration, and verify's recomputation from the stored rows."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex39_pybullet as ex39
from probecommit.studies.paper_values import value
from probecommit.tasks.insertion.model import capture_half_width

from .recompute_contract import assert_stored_summary_round_trip

PAPER_DELTA = value("T18-engine-scans.pybullet_offset")
PAPER_SD = value("T18-engine-scans.pybullet_ratio_sd")
TRUTHS = (("t0", 1.0, 1.0), ("t1", -2.0, 0.5))


def _point(name: str, index: int, offsets: tuple[float, float], ratios: tuple[float, float],
           beyond: float = 0.0) -> pd.DataFrame:
    """One point's scan rows as ``studies.engines.scan_rows`` writes them: every side of a truth at the same
    offset (``offsets`` per truth), each truth's window at ``ratio x w(c)``."""
    rows = []
    for (iid, x, c), off, r in zip(TRUTHS, offsets, ratios):
        w = float(capture_half_width(c))
        for side in ("left", "right"):
            rows.append({"kind": "boundary", "instance_id": iid, "x_hole": x, "c": c, "side": side, "offset": off})
            rows.append({"kind": "capture_side", "instance_id": iid, "x_hole": x, "c": c, "side": side,
                         "half_width": r * w, "enters_beyond": beyond})
        rows.append({"kind": "capture", "instance_id": iid, "x_hole": x, "c": c, "w": w, "window": r * w, "ratio": r})
    k, z = (float("nan"), float("nan")) if name == ex39.RIGID else (1e3, 0.1)
    return pd.DataFrame(rows).assign(engine="pybullet", point=name, index=index, stiffness=k, zeta=z)


def _rows(chosen_sd_ratios: tuple[float, float], chosen_offset: float = PAPER_DELTA) -> pd.DataFrame:
    return pd.concat([_point(ex39.RIGID, 0, (0.9, 0.9), (1.0, 1.0)),
                      _point("k1000_z010", 4, (chosen_offset, chosen_offset), chosen_sd_ratios),
                      _point("k300_z010", 6, (0.9, 0.9), (0.7, 0.8), beyond=1.0),
                      _point(ex39.PUBLISHED, -1, (0.9, 0.9), (1.0, 1.0))], ignore_index=True)


def test_summary_by_hand():
    keys = ex39.summary(_rows((1.0, 1.4)))
    assert keys["points"] == 3 and keys["rigid.ratio_mean"] == 1.0 and keys["rigid.ratio_sd"] == 0.0
    assert keys["k300_z010.sides_entering_beyond"] == 4 and keys["k300_z010.ratio_min"] == pytest.approx(0.7)
    assert keys["chosen.index"] == 4 and keys["chosen.stiffness"] == 1e3 and keys["chosen.zeta"] == 0.1
    assert keys["chosen.ratio_mean"] == pytest.approx(1.2) and keys["chosen.ratio_sd"] == pytest.approx(0.4 / np.sqrt(2))
    assert keys["chosen.delta"] == pytest.approx(PAPER_DELTA) and keys["chosen.delta_sd"] == 0.0
    assert keys["boundary_ok"] == 1 and keys["spread_ok"] == int(0.4 / np.sqrt(2) >= 0.5 * PAPER_SD) and \
        keys["holds"] == keys["spread_ok"]
    assert keys["rigid_equals_published"] == 1
    moved = _rows((1.0, 1.4))
    moved.loc[(moved["point"] == ex39.PUBLISHED) & (moved["kind"] == "boundary"), "offset"] += 1e-6
    assert ex39.summary(moved)["rigid_equals_published"] == 0
    assert "rigid_equals_published" not in ex39.summary(moved[moved["point"] != ex39.PUBLISHED])


def test_the_rule_at_its_edges():
    sd_edge = 0.5 * PAPER_SD * np.sqrt(2)  # two truths at 1.2 -+ this / 2 have SD exactly half the paper's
    at = ex39.summary(_rows((1.2 - sd_edge / 2, 1.2 + sd_edge / 2), PAPER_DELTA + ex39.BOUNDARY_TOLERANCE_MM - 1e-9))
    assert at["boundary_ok"] == 1 and at["spread_ok"] == int(at["chosen.ratio_sd"] >= 0.5 * PAPER_SD) and \
        at["chosen.ratio_sd"] == pytest.approx(0.5 * PAPER_SD)
    narrow = ex39.summary(_rows((1.19, 1.23)))
    assert narrow["boundary_ok"] == 1 and narrow["spread_ok"] == 0 and narrow["holds"] == 0
    wide = ex39.summary(_rows((0.6, 1.8), PAPER_DELTA + 0.06))
    assert wide["spread_ok"] == 1 and wide["boundary_ok"] == 0 and wide["holds"] == 0
    both = ex39.summary(_rows((0.6, 1.8), PAPER_DELTA - 0.04))
    assert both["holds"] == 1
    assert claims.EXPERIMENTS["E218"].supports({"ok": 1}) and not claims.EXPERIMENTS["E218"].supports({"ok": 0})


def test_the_point_nearest_the_papers_ratio_is_chosen_ties_to_the_grid_order():
    rows = pd.concat([_point(ex39.RIGID, 0, (0.9, 0.9), (1.21, 1.21)), _point("k1000_z010", 4, (0.9, 0.9), (1.21, 1.21))])
    assert ex39.summary(rows)["chosen.index"] == 0


def test_the_grid_and_the_contact_it_sets():
    grid = ex39.grid()
    assert len(grid) == 13 and grid[0][0] == ex39.RIGID and np.isnan(grid[0][1])
    assert [g[0] for g in grid[1:7]] == [f"k{k:.0f}_z010" for k in (1e5, 1e4, 3e3, 1e3, 5e2, 3e2)]
    assert ex39.plate_contact(float("nan"), float("nan")) is None
    assert ex39.plate_contact(1e3, 1.0) == {"contactStiffness": 1e3, "contactDamping": pytest.approx(2 * np.sqrt(1e3 * 0.05))}
    assert ex39.label(500.0, 0.1) == "k500_z010" and ex39.label(1e5, 1.0) == "k100000_z100"


def test_the_step_reads_the_published_truths_and_stores_the_published_rows(monkeypatch, tmp_path):
    published = _point(ex39.RIGID, 0, (0.9, 0.9), (1.0, 1.0)).drop(columns=["point", "index", "stiffness", "zeta"])
    (tmp_path / "engines" / "results").mkdir(parents=True)
    published.to_parquet(tmp_path / "engines" / "results" / "engine_scans.parquet")
    seen = []

    def fake(truths, k, z, scan, sigma):
        seen.append((len(truths), k, z))
        ratio = 1.0 if np.isnan(k) else 1.0 + 100.0 / k
        return _point(ex39.RIGID, 0, (0.9, 0.9), (ratio, ratio))[published.columns].head(len(truths) * 5), 0.0

    monkeypatch.setattr(ex39, "point_rows", fake)
    job = SimpleNamespace(root=Path(tmp_path), quick=True, cfg={"ex39_truths": 24, "ex39_truths_quick": 1},
                          p=SimpleNamespace(scan={}, noise_sigma=0.5), progress=lambda *a: None,
                          stored={}, res=defaultdict(dict))
    ex39.run(job)
    assert len(seen) == 13 and all(n == 1 for n, _, _ in seen)
    rows = job.stored[ex39.STORED]
    assert set(rows.loc[rows["point"] == ex39.PUBLISHED, "instance_id"]) == {"t0"}
    assert job.res[ex39.GROUP] == ex39.summary(rows) and job.res[ex39.GROUP]["rigid_equals_published"] == 1
    empty = SimpleNamespace(**{**vars(job), "root": Path(tmp_path) / "none", "res": defaultdict(dict), "stored": {}})
    ex39.run(empty)
    assert not empty.res and not empty.stored


def test_a_compliant_plate_widens_pybullets_window():
    """Hand case on the engine: an aim 2 % outside w(c) rests on the rigid plate's top and enters through the
    compliant one (k = 1e3 N/m, zeta 0.1), while the tap still reads the top 0.5 mm outside the boundary."""
    pytest.importorskip("pybullet")
    from probecommit.studies.engines import make_simulator

    x, c = 0.0, 1.0
    aim = x + 1.02 * float(capture_half_width(c))
    rigid = make_simulator("pybullet")
    soft = make_simulator("pybullet", plate_contact=ex39.plate_contact(1e3, 0.1))
    try:
        assert rigid.peg_depth(x, c, aim) < 1.0 and soft.peg_depth(x, c, aim) > 9.0
        assert rigid.peg_depth(x, c, x) > 14.0 and soft.peg_depth(x, c, x) > 14.0
        from probecommit.tasks.insertion.model import half_gap

        top = x + float(half_gap(c)) + PAPER_DELTA + 0.5
        assert rigid.tap_reading(x, c, top) > -1.0 and soft.tap_reading(x, c, top) > -1.0
    finally:
        rigid.close()
        soft.close()


def test_e218_is_registered_for_t18s_pybullet_ratio_and_its_keys_exist():
    t18 = next(c for c in claims.CLAIMS if c.id == "T18-engine-scans")
    assert ("E218", (f"{claims.EXACT}PyBullet capture ratio",)) in claims.explanations(t18)
    keys = {f"{claims.X}{ex39.GROUP}.{k}" for k in ex39.summary(_rows((1.0, 1.4)))}
    assert {k for k in claims.EXPERIMENTS["E218"].keys.values() if not k.startswith("paper:")} <= keys


def test_verify_recomputes_the_group_from_its_stored_rows(tmp_path):
    assert_stored_summary_round_trip(tmp_path, ex39, _rows((1.0, 1.4)))
