"""ex38's E214 / E216 (a PhysX shape setting chosen by the paper's capture window, judged on its boundary): one
scan point's keys by hand from stored rows, the declared refinement, the rule at its edges, registration, verify's
recomputation, and (with SAPIEN) that the sweep's first contact-offset point is the engines study's own scene."""

from __future__ import annotations

import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex38_physx as ex38
from probecommit.studies.paper_values import value

from .recompute_contract import assert_stored_summary_round_trip

PAPER_RATIO = value("T18-engine-scans.sapien_ratio")
PAPER_DELTA = value("T18-engine-scans.sapien_offset")


def _point(arm: str, v: float, offsets: list[float], ratios: list[float], cpu: float = 2.0) -> pd.DataFrame:
    """One point's stored rows as ``engines.scan_rows`` writes them (boundary, capture, capture_side)."""
    boundary = pd.DataFrame({"instance_id": [f"t{i // 2}" for i in range(len(offsets))], "offset": offsets,
                             "kind": "boundary"})
    capture = pd.DataFrame({"instance_id": [f"t{i}" for i in range(len(ratios))], "ratio": ratios, "kind": "capture"})
    sides = pd.DataFrame({"instance_id": [f"t{i // 2}" for i in range(2 * len(ratios))],
                          "enters_beyond": [0.0, 1.0] * len(ratios), "kind": "capture_side"})
    return pd.concat([boundary, capture, sides], ignore_index=True).assign(engine="sapien", arm=arm, value=v, cpu_s=cpu)


def test_one_points_keys_by_hand():
    rows = _point("contact_offset", 1e-4, [0.8, 1.0, 0.9, 0.9], [0.5, 0.7], cpu=3.5)
    keys = ex38.summary(rows)
    assert keys["contact_offset.points"] == 1 and keys["contact_offset.p0.value"] == 1e-4
    assert keys["contact_offset.p0.delta"] == pytest.approx(0.9)
    assert keys["contact_offset.p0.delta_sd"] == pytest.approx((0.02 / 3) ** 0.5)
    assert keys["contact_offset.p0.ratio"] == pytest.approx(0.6)
    assert keys["contact_offset.p0.ratio_sd"] == pytest.approx(0.02 ** 0.5)
    assert keys["contact_offset.p0.sides_entering_beyond"] == 2 and keys["contact_offset.p0.failed"] == 0
    assert keys["contact_offset.chosen.value"] == 1e-4 and keys["contact_offset.cpu_s"] == 3.5
    assert keys["contact_offset.chosen.ratio_passes"] == 1  # 0.6 is within 0.1 of 0.55
    assert keys["contact_offset.chosen.offset_passes"] == 0 and keys["contact_offset.holds"] == 0


def test_the_point_is_chosen_by_the_window_and_held_only_with_the_boundary():
    near = _point("rest_offset", 3e-4, [PAPER_DELTA + 0.04] * 2, [PAPER_RATIO + 0.01])
    far = _point("rest_offset", 0.0, [PAPER_DELTA] * 2, [PAPER_RATIO + 0.3])  # the paper's boundary, wrong window
    failed = pd.DataFrame({"kind": ["failed"], "error": ["x"], "engine": ["sapien"], "arm": ["rest_offset"],
                           "value": [1e-3], "cpu_s": [1.0]})
    keys = ex38.summary(pd.concat([far, near, failed], ignore_index=True))
    assert keys["rest_offset.points"] == 3 and keys["rest_offset.p2.failed"] == 1
    assert keys["rest_offset.chosen.value"] == 3e-4 and keys["rest_offset.holds"] == 1
    off = ex38.summary(pd.concat([far, _point("rest_offset", 3e-4, [PAPER_DELTA + 0.06] * 2, [PAPER_RATIO])]))
    assert off["rest_offset.chosen.value"] == 3e-4 and off["rest_offset.holds"] == 0  # the boundary 0.06 mm off


def test_the_declared_refinement_bisects_the_first_bracket_in_log10():
    calls: list[float] = []

    def evaluate(arm: str, v: float) -> pd.DataFrame:
        calls.append(v)
        ratio = 1.0 if v < 1e-3 else 0.3  # a step at 1e-3, never within NEAR: all bisections spent
        return _point(arm, v, [0.0, 0.0], [ratio])

    rows = ex38.sweep("contact_offset", (1e-4, 1e-3, 1e-2), evaluate)
    assert calls[:3] == [1e-4, 1e-3, 1e-2] and len(calls) == 3 + ex38.BISECTIONS
    assert calls[3] == pytest.approx(10 ** -3.5) and calls[4] == pytest.approx(10 ** -3.25)  # 1.0 there: go up
    assert sorted(rows["value"].unique()) == sorted(calls)
    stop: list[float] = []

    def close(arm: str, v: float) -> pd.DataFrame:
        stop.append(v)
        return _point(arm, v, [0.0, 0.0], [PAPER_RATIO if v not in (1e-4, 1e-2) else (0.9 if v == 1e-4 else 0.2)])

    ex38.sweep("contact_offset", (1e-4, 1e-2), close)
    assert stop == [1e-4, 1e-2, pytest.approx(1e-3)]  # the first midpoint is within NEAR: stop
    none: list[float] = []
    ex38.sweep("rest_offset", (0.0, 1e-4), lambda a, v: none.append(v) or _point(a, v, [0.0, 0.0], [0.9]))
    assert none == [0.0, 1e-4]  # no bracket, no refinement


def test_tolerances_are_t18s_and_e214_e216_speak_to_t18s_physx_labels_only():
    t18 = next(c for c in claims.CLAIMS if c.id == "T18-engine-scans")
    tol = {c.label: c.tol for c in t18.comparisons}
    assert (tol["PhysX capture ratio"], tol["PhysX offset"]) == (ex38.RATIO_TOLERANCE, ex38.OFFSET_TOLERANCE_MM)
    covers = dict(claims.explanations(t18))
    keys = {f"{claims.X}{ex38.GROUP}.{k}" for k in ex38.summary(
        pd.concat([_point(arm, 0.0, [0.0, 0.0], [0.5]) for arm in ex38.GRIDS], ignore_index=True))}
    for number in ("E214", "E216"):
        assert covers[number] == (f"{claims.EXACT}PhysX offset", f"{claims.EXACT}PhysX capture ratio")
        assert {k for k in claims.EXPERIMENTS[number].keys.values() if not k.startswith("paper:")} <= keys
        assert claims.EXPERIMENTS[number].supports({"h": 1}) and not claims.EXPERIMENTS[number].supports({"h": 0})


def test_verify_recomputes_the_group_from_its_stored_rows(tmp_path):
    rows = pd.concat([_point("contact_offset", 1e-4, [0.9, 0.9], [0.99]), _point("contact_offset", 1e-2, [-0.2, -0.2], [0.5])],
                     ignore_index=True)
    assert_stored_summary_round_trip(tmp_path, ex38, rows)


def test_our_setting_is_the_engines_studys_scene():
    pytest.importorskip("sapien")
    from probecommit.studies.engines import make_simulator, scan_boundary, scan_capture_window, scan_rows

    truths = pd.DataFrame({"instance_id": ["t0"], "true_x_hole": [1.5], "true_c": [0.9]})
    scan = {"step": 0.25, "half_range": 7.0, "tolerance": 1e-3}
    ours = ex38.point_rows("contact_offset", ex38.GRIDS["contact_offset"][0], truths, 0.5, scan)
    sim = make_simulator("sapien", noise_sigma=0.5)
    plain = scan_rows("sapien", scan_boundary(sim, truths, **scan), scan_capture_window(sim, truths))
    pd.testing.assert_frame_equal(ours.drop(columns=["arm", "value", "cpu_s"]), plain)
    assert ex38.shape_setting("rest_offset", 0.0) == ex38.shape_setting("contact_offset", ex38.OUR_CONTACT_M)
