"""ex41's E228 (PyBullet's capture window against the contact slop): the keys by hand, the rule's three parts at
their edges, the grid and the physics it sets, the step's wiring (a quick run: two points, one truth),
registration, and verify's recomputation from the stored rows."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from probecommit.engines.pybullet import MM_PHYSICS
from probecommit.studies import claims
from probecommit.studies.explain import ex39_pybullet as ex39
from probecommit.studies.explain import ex41_slop as ex41
from probecommit.studies.paper_values import value
from probecommit.tasks.insertion.model import capture_half_width

from .recompute_contract import assert_stored_summary_round_trip

PAPER_DELTA = value("T18-engine-scans.pybullet_offset")
PAPER_RATIO = value("T18-engine-scans.pybullet_ratio")
PAPER_SD = value("T18-engine-scans.pybullet_ratio_sd")
TRUTHS = (("t0", 1.0, 1.0), ("t1", -2.0, 0.5))


def _point(name: str, index: int, offset: float, ratios: tuple[float, float]) -> pd.DataFrame:
    """One point's scan rows as ``studies.engines.scan_rows`` writes them: every side at ``offset``, each truth's
    window at ``ratio x w(c)``."""
    rows = []
    for (iid, x, c), r in zip(TRUTHS, ratios):
        w = float(capture_half_width(c))
        for side in ("left", "right"):
            rows.append({"kind": "boundary", "instance_id": iid, "x_hole": x, "c": c, "side": side, "offset": offset})
            rows.append({"kind": "capture_side", "instance_id": iid, "x_hole": x, "c": c, "side": side,
                         "half_width": r * w, "enters_beyond": 0.0})
        rows.append({"kind": "capture", "instance_id": iid, "x_hole": x, "c": c, "w": w, "window": r * w, "ratio": r})
    slop = ex41.SLOP[index] if index >= 0 else float("nan")
    return pd.DataFrame(rows).assign(engine="pybullet", point=name, index=index, slop=slop)


def _rows(chosen: tuple[float, float], offset: float = PAPER_DELTA) -> pd.DataFrame:
    """Ours (1.0), the default (1.004), the 2e-4 m point (``chosen``) and the published scan (ours)."""
    return pd.concat([_point("slop1um", 0, 0.9, (1.0, 1.0)), _point("slop10um", 1, 0.9, (1.004, 1.004)),
                      _point("slop200um", 4, offset, chosen), _point(ex39.PUBLISHED, -1, 0.9, (1.0, 1.0))],
                     ignore_index=True)


def test_the_grid_names_and_physics():
    assert [n for n, _ in ex41.grid()] == ["slop1um", "slop10um", "slop30um", "slop100um", "slop200um", "slop300um"]
    assert ex41.OURS == "slop1um" and ex41.SLOP[0] == MM_PHYSICS["contactSlop"]
    p = ex41.physics(2e-4)
    assert p["contactSlop"] == 2e-4 and {k: v for k, v in p.items() if k != "contactSlop"} == \
        {k: v for k, v in MM_PHYSICS.items() if k != "contactSlop"}


def test_summary_by_hand():
    keys = ex41.summary(_rows((0.7, 1.7)))
    assert keys["points"] == 3 and keys["slop1um.ratio_mean"] == 1.0 and keys["slop10um.ratio_sd"] == 0.0
    assert keys["chosen.index"] == 4 and keys["chosen.slop"] == 2e-4
    assert keys["chosen.ratio_mean"] == pytest.approx(1.2) and keys["chosen.ratio_sd"] == pytest.approx(1 / np.sqrt(2))
    assert keys["chosen.ratio_min"] == 0.7 and keys["chosen.ratio_max"] == 1.7
    assert keys["boundary_ok"] == 1 and keys["spread_ok"] == 1 and keys["mean_ok"] == 1 and keys["holds"] == 1
    assert keys["slop1um_equals_published"] == 1 and keys["ratio_tolerance"] == 0.1


def test_each_part_of_the_rule_fails_alone():
    far = ex41.summary(_rows((0.7, 1.7), PAPER_DELTA + 0.06))
    assert far["boundary_ok"] == 0 and far["spread_ok"] == 1 and far["mean_ok"] == 1 and far["holds"] == 0
    narrow = ex41.summary(_rows((1.19, 1.23)))
    assert narrow["spread_ok"] == 0 and narrow["mean_ok"] == 1 and narrow["holds"] == 0
    # The nearest point to 1.21 still 0.15 away: wide and at the boundary, but not the paper's mean.
    low = ex41.summary(_rows((0.3, 1.82)))
    assert low["chosen.index"] == 4 and low["chosen.ratio_mean"] == pytest.approx(1.06)
    assert low["boundary_ok"] == 1 and low["spread_ok"] == 1 and low["mean_ok"] == 0 and low["holds"] == 0
    assert claims.EXPERIMENTS["E228"].supports({"ok": 1}) and not claims.EXPERIMENTS["E228"].supports({"ok": 0})


def test_the_step_runs_a_quick_sweep_and_stores_the_published_rows(monkeypatch, tmp_path):
    published = _point("slop1um", 0, 0.9, (1.0, 1.0)).drop(columns=["point", "index", "slop"])
    (tmp_path / "engines" / "results").mkdir(parents=True)
    published.to_parquet(tmp_path / "engines" / "results" / "engine_scans.parquet")
    seen = []

    def fake(truths, scan, sigma, **settings):
        slop = settings["physics"]["contactSlop"]
        seen.append((len(truths), slop))
        r = 1.0 + slop * 100
        return _point("x", 0, 0.9, (r, r))[published.columns].head(len(truths) * 5), 0.0

    monkeypatch.setattr(ex39, "scan_point", fake)
    job = SimpleNamespace(root=Path(tmp_path), quick=True, cfg={"ex41_truths": 24, "ex41_truths_quick": 1},
                          p=SimpleNamespace(scan={}, noise_sigma=0.5), progress=lambda *a: None,
                          stored={}, res=defaultdict(dict))
    ex41.run(job)
    assert seen == [(1, 1e-6), (1, 1e-5)]
    rows = job.stored[ex41.STORED]
    assert set(rows.loc[rows["point"] == ex39.PUBLISHED, "instance_id"]) == {"t0"}
    assert job.res[ex41.GROUP] == ex41.summary(rows) and job.res[ex41.GROUP]["points"] == 2
    full = SimpleNamespace(**{**vars(job), "quick": False, "res": defaultdict(dict), "stored": {}})
    seen.clear()
    ex41.run(full)
    assert [s for _, s in seen] == list(ex41.SLOP) and all(n == 2 for n, _ in seen)
    empty = SimpleNamespace(**{**vars(job), "root": Path(tmp_path) / "none", "res": defaultdict(dict), "stored": {}})
    ex41.run(empty)
    assert not empty.res and not empty.stored


def test_e228_is_registered_for_t18s_pybullet_ratio_and_its_keys_exist():
    t18 = next(c for c in claims.CLAIMS if c.id == "T18-engine-scans")
    assert ("E228", (f"{claims.EXACT}PyBullet capture ratio",)) in claims.explanations(t18)
    keys = {f"{claims.X}{ex41.GROUP}.{k}" for k in ex41.summary(_rows((0.7, 1.7)))}
    assert {k for k in claims.EXPERIMENTS["E228"].keys.values() if not k.startswith("paper:")} <= keys


def test_verify_recomputes_the_group_from_its_stored_rows(tmp_path):
    assert_stored_summary_round_trip(tmp_path, ex41, _rows((0.7, 1.7)))
