"""ex40's E226 (PhysX solver iterations chosen by the paper's capture window, judged on its boundary): the summary
by hand from stored rows, the tie and the rule at its edges, registration, verify's recomputation, and (with SAPIEN)
that the sweep's first point is the engines study's own scene."""

from __future__ import annotations

import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex40_solver as ex40
from probecommit.studies.paper_values import value

from .recompute_contract import assert_stored_summary_round_trip

PAPER_RATIO = value("T18-engine-scans.sapien_ratio")
PAPER_DELTA = value("T18-engine-scans.sapien_offset")


def _point(index: int, offsets: list[float], ratios: list[float], cpu: float = 2.0) -> pd.DataFrame:
    """One grid point's stored rows as ``point_rows`` writes them (boundary, capture, capture_side)."""
    boundary = pd.DataFrame({"instance_id": [f"t{i // 2}" for i in range(len(offsets))], "offset": offsets,
                             "kind": "boundary"})
    capture = pd.DataFrame({"instance_id": [f"t{i}" for i in range(len(ratios))], "ratio": ratios, "kind": "capture"})
    sides = pd.DataFrame({"instance_id": [f"t{i // 2}" for i in range(2 * len(ratios))],
                          "enters_beyond": [0.0, 1.0] * len(ratios), "kind": "capture_side"})
    p, v = ex40.GRID[index]
    return pd.concat([boundary, capture, sides], ignore_index=True).assign(
        engine="sapien", arm=ex40.ARM, value=float(index), position_iterations=p, velocity_iterations=v, cpu_s=cpu)


def test_the_summary_by_hand():
    rows = pd.concat([_point(0, [0.9, 0.9, 0.9, 0.9], [0.99, 0.99], cpu=40.0),
                      _point(5, [0.8, 1.0, 0.9, 0.9], [0.5, 0.7], cpu=30.0)], ignore_index=True)
    keys = ex40.summary(rows)
    assert keys["points"] == 2 and keys["cpu_s"] == 70.0
    assert (keys["p0.position_iterations"], keys["p0.velocity_iterations"]) == (32, 4)
    assert (keys["p1.position_iterations"], keys["p1.velocity_iterations"]) == (1, 0)
    assert keys["p0.ratio"] == pytest.approx(0.99) and keys["p0.delta"] == pytest.approx(0.9)
    assert keys["p1.ratio"] == pytest.approx(0.6) and keys["p1.ratio_sd"] == pytest.approx(0.02 ** 0.5)
    assert keys["p1.delta_sd"] == pytest.approx((0.02 / 3) ** 0.5) and keys["p1.sides_entering_beyond"] == 2
    assert keys["chosen.value"] == 5 and (keys["chosen.position_iterations"], keys["chosen.velocity_iterations"]) == (1, 0)
    assert keys["chosen.ratio_passes"] == 1 and keys["chosen.offset_passes"] == 0 and keys["holds"] == 0


def test_a_tie_goes_to_the_first_point_in_the_declared_order_and_the_rule_needs_both_labels():
    tie = ex40.summary(pd.concat([_point(4, [PAPER_DELTA] * 2, [PAPER_RATIO + 0.05]),
                                  _point(1, [0.9] * 2, [PAPER_RATIO - 0.05])], ignore_index=True))
    assert tie["chosen.value"] == 1 and tie["chosen.position_iterations"] == 10 and tie["holds"] == 0
    held = ex40.summary(pd.concat([_point(0, [0.9] * 2, [0.99]), _point(3, [PAPER_DELTA + 0.04] * 2, [PAPER_RATIO])]))
    assert held["chosen.value"] == 3 and held["holds"] == 1
    off = ex40.summary(pd.concat([_point(0, [0.9] * 2, [0.99]), _point(3, [PAPER_DELTA + 0.06] * 2, [PAPER_RATIO])]))
    assert off["chosen.offset_passes"] == 0 and off["holds"] == 0  # the boundary 0.06 mm off


def test_e226_speaks_to_t18s_physx_labels_with_its_keys():
    t18 = next(c for c in claims.CLAIMS if c.id == "T18-engine-scans")
    assert dict(claims.explanations(t18))["E226"] == (f"{claims.EXACT}PhysX offset", f"{claims.EXACT}PhysX capture ratio")
    keys = {f"{claims.X}{ex40.GROUP}.{k}" for k in ex40.summary(_point(5, [0.9, 0.9], [0.5]))}
    experiment = claims.EXPERIMENTS["E226"]
    assert {k for k in experiment.keys.values() if not k.startswith("paper:")} <= keys
    assert experiment.supports({"h": 1}) and not experiment.supports({"h": 0})
    assert len(ex40.GRID) <= 6 and ex40.GRID[1] == (10, 1)  # SAPIEN's default second, after ours:
    from probecommit.engines.sapien import MM_BODY

    assert ex40.body_setting(0) == {k: MM_BODY[k] for k in ("solver_position_iterations", "solver_velocity_iterations")}


def test_verify_recomputes_the_group_from_its_stored_rows(tmp_path):
    rows = pd.concat([_point(0, [0.9, 0.9], [0.99]), _point(5, [0.9, 0.9], [0.6])], ignore_index=True)
    assert_stored_summary_round_trip(tmp_path, ex40, rows)


def test_our_count_is_the_engines_studys_scene():
    pytest.importorskip("sapien")
    from probecommit.studies.engines import make_simulator, scan_boundary, scan_capture_window, scan_rows

    truths = pd.DataFrame({"instance_id": ["t0"], "true_x_hole": [1.5], "true_c": [0.9]})
    scan = {"step": 0.25, "half_range": 7.0, "tolerance": 1e-3}
    ours = ex40.point_rows(0, truths, 0.5, scan)
    sim = make_simulator("sapien", noise_sigma=0.5)
    plain = scan_rows("sapien", scan_boundary(sim, truths, **scan), scan_capture_window(sim, truths))
    extra = ["arm", "value", "position_iterations", "velocity_iterations", "cpu_s"]
    pd.testing.assert_frame_equal(ours.drop(columns=extra), plain)
