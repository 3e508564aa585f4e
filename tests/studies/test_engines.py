"""Cross-engine study functions: the check harness, both scans, Table VIII's layout."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.studies.engines import (
    TABLE_VARIANTS,
    check_engines,
    default_check_queries,
    engines_table,
    scan_boundary,
    scan_capture_window,
    table_variants,
)
from probecommit.tasks.insertion.model import TIP_RADIUS_MM
from probecommit.tasks.insertion.sim_base import AnalyticInsertionSimulator, InsertionSimulator

TRUTHS = [(0.0, 1.0), (-3.3, 0.75), (6.1, 1.25)]


class WrongChamfer(InsertionSimulator):
    """A planted disagreement: an engine whose tip sticks on the chamfer (boundary hg - r)."""

    engine = "wrong"

    def tap_reading(self, x_hole, c, u):
        return -15.0 if abs(u - x_hole) < 4.0 + 0.6 * c - TIP_RADIUS_MM else 0.0

    def peg_depth(self, x_hole, c, a):
        return 15.0 if abs(a - x_hole) < 0.6 * c + 1.1 else 0.0


class Bare:
    """Named queries only (no base class, no cache)."""

    def __init__(self, offset, scale):
        self.offset, self.scale = offset, scale

    def tap_reading(self, x_hole, c, u):
        return -15.0 if abs(u - x_hole) < 4.0 + 0.6 * c + self.offset else 0.0

    def peg_depth(self, x_hole, c, a):
        return 15.0 if abs(a - x_hole) < self.scale * (0.6 * c + 1.1) else 0.0


def test_check_agrees_on_the_designed_scene_and_flags_a_planted_disagreement():
    table = check_engines({"ideal": AnalyticInsertionSimulator(), "wrong": WrongChamfer()})
    assert list(table["query"]) == list(default_check_queries()["query"])
    chamfer = table["query"] == "tap on the chamfer"
    assert not table.loc[chamfer, "agree"].item()
    assert table.loc[chamfer, "disagreeing"].item() == "wrong"
    assert table.loc[~chamfer, "agree"].all()
    assert table.attrs["tolerance"] == 0.5
    # The deployed model reads top on the chamfer: that is the paper's missed band.
    assert table.loc[chamfer, "deployed_model"].item() == 0.0


def test_check_names_simulators_by_engine_and_rejects_duplicates():
    table = check_engines([AnalyticInsertionSimulator()])
    assert "analytic" in table.columns and table["agree"].all()
    with pytest.raises(ValueError, match="twice"):
        check_engines([AnalyticInsertionSimulator(), AnalyticInsertionSimulator()])


def test_check_treats_nan_as_disagreement():
    class Broken(WrongChamfer):
        def peg_depth(self, x_hole, c, a):
            return float("nan")

    table = check_engines({"broken": Broken()})
    assert not table.loc[table["kind"] == "peg_depth", "agree"].any()


@pytest.mark.parametrize("offset", [0.929, -0.209, 0.905])
def test_boundary_scan_recovers_a_known_offset(offset):
    result = scan_boundary(Bare(offset, 1.0), TRUTHS, tolerance=1e-4)
    assert len(result.scans) == 2 * len(TRUTHS)
    assert np.allclose(result.scans["offset"], offset, atol=1e-4)


def test_boundary_scan_accepts_an_instance_frame():
    truths = pd.DataFrame({"instance_id": ["a", "b"], "true_x_hole": [1.0, -2.0], "true_c": [0.8, 1.2]})
    result = scan_boundary(AnalyticInsertionSimulator(boundary_offset=0.5), truths)
    assert set(result.scans["instance_id"]) == {"a", "b"}
    assert abs(result.delta - 0.5) < 1e-3


@pytest.mark.parametrize("scale", [1.21, 0.55, 1.0])
def test_capture_scan_recovers_a_known_ratio(scale):
    result = scan_capture_window(Bare(0.905, scale), TRUTHS, tolerance=1e-4)
    assert len(result.sides) == 2 * len(TRUTHS)
    assert np.allclose(result.truths["ratio"], scale, atol=1e-3)
    s = result.summary()
    assert abs(s["ratio_mean"] - scale) < 1e-3 and s["ratio_sd"] < 1e-3 and s["truths"] == len(TRUTHS)


def test_capture_scan_asymmetric_and_failed_centre():
    class Lopsided(Bare):
        def peg_depth(self, x_hole, c, a):
            if c > 1.2:
                return 0.0  # never enters, even centred
            return 15.0 if -1.0 < a - x_hole < 2.0 else 0.0

    result = scan_capture_window(Lopsided(0.0, 1.0), [(0.0, 1.0), (0.0, 1.25)], tolerance=1e-4)
    first = result.sides.loc[result.sides["instance_id"] == "t0"].set_index("side")["half_width"]
    assert abs(first["left"] - 1.0) < 1e-3 and abs(first["right"] - 2.0) < 1e-3
    assert abs(result.truths["window"].iloc[0] - 1.5) < 1e-3
    assert result.truths["window"].iloc[1] == 0.0
    assert not result.sides["enters_beyond"].any()


def test_capture_scan_flags_a_non_contiguous_window():
    class Snag(Bare):
        def peg_depth(self, x_hole, c, a):
            d = abs(a - x_hole)
            return 15.0 if d < 0.6 or 1.0 < d < 1.5 else 0.0

    result = scan_capture_window(Snag(0.0, 1.0), [(0.0, 1.0)], tolerance=1e-4)
    assert np.allclose(result.sides["half_width"], 0.6, atol=1e-3)
    assert result.sides["enters_beyond"].all() and result.summary()["sides_entering_beyond"] == 2


def test_table_variants_and_layout():
    v = table_variants(own_delta=0.3)
    assert v == {"deployed": -1.2, "mj_offset": 0.905, "own_scan": 0.3}
    audits = {}
    for engine in ("pybullet", "sapien"):
        for i, variant in enumerate(TABLE_VARIANTS):
            audits[(engine, variant)] = pd.DataFrame({
                "k": [1, 8], "escape": [0.0, 0.1 * i], "coverage": [0.9, 0.8], "optimism": [0.0, 0.2],
                "realized": [0.5, 0.3 + (engine == "sapien")]})
    table = engines_table(audits)
    assert list(table.index) == ["support escape", "episode coverage", "optimism e_k", "failure"]
    assert table[("pybullet", "mj_offset")]["support escape"] == pytest.approx(0.1)
    assert table[("sapien", "own_scan")]["failure"] == pytest.approx(1.3)
    with pytest.raises(ValueError, match="one audit row"):
        engines_table({("x", "deployed"): pd.DataFrame({"k": [1]})})


@pytest.mark.parametrize("engine", ["pybullet", "sapien"])
def test_check_on_real_engines(engine):
    pytest.importorskip(engine)
    table = check_engines([engine])
    assert table["agree"].all(), table[["query", engine]].to_string()
