"""ex5's explain experiments (E55..E58): the summaries of the stored rows on hand cases, and the
claims' ``supports`` rules deciding on hand values (each one can fail)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex5_calibration as ex5
from probecommit.studies.paper_values import value


def test_split_halves_are_the_insertion_studys_draws():
    ids = np.array(list("abcdef"))
    rng = np.random.default_rng(9)
    expected = [rng.permutation(6) for _ in range(3)]
    halves = ex5.split_halves(ids, 3, 9)
    for (cal, test), perm in zip(halves, expected):
        assert list(cal) == list(ids[perm[:3]]) and list(test) == list(ids[perm[3:]])
        assert sorted([*cal, *test]) == list(ids)


def test_cost_keys_by_hand():
    rows = pd.DataFrame({"part": "resplit_cost", "index": range(5), "difference": [0.0, 0.1, 0.2, 0.3, 0.4],
                         "lo": [-0.1, 0.01, 0.0, -0.2, 0.1], "hi": [0.1, 0.2, 0.3, -0.01, 0.5],
                         "gamma": [0.5, 0.6, 0.7, 0.6, 0.6]})
    keys = ex5.cost_keys(rows)
    assert keys["splits"] == 5
    assert keys["estimate.mean"] == pytest.approx(0.2)
    assert keys["estimate.p025"] == pytest.approx(0.01)  # 0.025 * 4 = 0.1 of the way from 0.0 to 0.1
    assert keys["estimate.p975"] == pytest.approx(0.39)
    assert keys["share_above_zero"] == pytest.approx(0.4)  # lo > 0 strictly: 0.01 and 0.1, not 0.0
    assert keys["share_below_zero"] == pytest.approx(0.2)
    assert keys["gamma.mean"] == pytest.approx(0.6)


def test_pool_keys_by_hand():
    stats = {s: [0.1, 0.3] for s in ex5.POOL_STATS}
    keys = ex5.pool_keys(pd.DataFrame({"part": "fresh_pool", "index": [0, 1], **stats}))
    assert keys["pools"] == 2
    for s in ex5.POOL_STATS:
        assert (keys[f"{s}.min"], keys[f"{s}.max"], keys[f"{s}.mean"]) == pytest.approx((0.1, 0.3, 0.2))


def _capture(scale: float, lo: float, hi: float, gamma: tuple[float, float], pairs: int = 2) -> pd.DataFrame:
    """Pairs at one scale whose optimism cells span ``[lo, hi]`` and whose margins span ``gamma``."""
    cells = {c: np.linspace(lo, hi, pairs) for c in ex5.CELLS}
    return pd.DataFrame({"part": "capture", "index": range(pairs), "scale": scale, **cells,
                         "gamma": np.linspace(*gamma, pairs), "mean_abs_optimism.original": np.linspace(0.1, 0.3, pairs),
                         "mean_abs_optimism.calibrated": 0.05})


def test_capture_keys_pick_the_largest_scale_meeting_the_joint_rule():
    rows = pd.concat([_capture(0.80, -1.0, 1.0, (0.5, 0.7)), _capture(0.90, -1.0, 1.0, (0.5, 0.7)),
                      _capture(0.95, -1.0, 1.0, (0.3, 0.4))], ignore_index=True)
    keys = ex5.capture_keys(rows)
    assert keys["tests"] == 11 and keys["pairs"] == 2
    assert keys["s0.95.inside"] == 10  # every cell, not the margin
    assert (keys["best_scale"], keys["best_meets_rule"], keys["best_inside"]) == (0.90, 1, 11)
    assert keys["best.gamma.min"] == 0.5 and keys["best.mean_abs_optimism.original.max"] == pytest.approx(0.3)


def test_capture_keys_without_a_qualifying_scale_say_so():
    # Cells in [0.2, 0.3]: of the paper's optimism cells only +0.218 and +0.263 lie in range (+0.306 does not),
    # and its margin 0.62 in [0.5, 0.7]: three of eleven.
    rows = pd.concat([_capture(0.85, 0.2, 0.3, (0.5, 0.7)), _capture(0.90, 0.2, 0.3, (0.5, 0.7))], ignore_index=True)
    keys = ex5.capture_keys(rows)
    assert keys["best_meets_rule"] == 0 and keys["best_inside"] == 3 and keys["best_scale"] == 0.90  # tie: larger s


def test_summary_survives_the_stored_parquet(tmp_path):
    rows = pd.concat([
        pd.DataFrame({"part": "resplit_cost", "index": [0, 1], "difference": [0.0, 0.1], "lo": [-0.1, 0.01],
                      "hi": [0.1, 0.2], "gamma": [0.6, 0.6]}),
        pd.DataFrame({"part": "fresh_pool", "index": [0], **{s: [0.5] for s in ex5.POOL_STATS}}),
        _capture(0.9, -1.0, 1.0, (0.5, 0.7))], ignore_index=True)
    rows.to_parquet(tmp_path / ex5.STORED)
    assert ex5.summary(pd.read_parquet(tmp_path / ex5.STORED)) == ex5.summary(rows)
    assert {k.split(".")[0] for k in ex5.summary(rows)} == {"resplit_cost", "fresh_pool", "capture"}
    no_pools = pd.concat([rows[rows.part == "resplit_cost"], ex5.fresh_pool_rows(None, [], tmp_path, 0, 1)],
                         ignore_index=True)  # a quick run draws no fresh pool: its keys are absent, not NaN
    assert {k.split(".")[0] for k in ex5.summary(no_pools)} == {"resplit_cost"}


def test_e55_needs_the_paper_inside_and_the_paper_verdict_often_enough():
    support = claims.EXPERIMENTS["E55"].supports
    p = value("T13-cost-of-calibration.full")
    base = {"n": 50, "m": 0.02, "lo": p - 0.05, "hi": p + 0.01, "below": 0.0}
    assert support({**base, "share": claims.EX5_VERDICT_SHARE})
    assert not support({**base, "share": claims.EX5_VERDICT_SHARE - 0.02})
    assert not support({**base, "hi": p - 0.001, "share": 0.5})


def test_e56_and_e57_and_e58_read_the_paper_value_in_range():
    e56 = claims.EXPERIMENTS["E56[margin optimistic]"].supports
    share = value("T14-resplits.margin_optimistic_percent") / 100
    assert e56({"lo": share - 0.01, "hi": share + 0.01}) and not e56({"lo": share + 0.01, "hi": share + 0.2})
    e57 = claims.EXPERIMENTS["E57[optimism original k=2]"].supports
    cell = value("tab:audit.optimism_original.2")
    assert e57({"ok": 1, "lo": cell - 0.01, "hi": cell + 0.01})
    assert not e57({"ok": 0, "lo": cell - 0.01, "hi": cell + 0.01})  # the joint rule failed at that window
    assert not e57({"ok": 1, "lo": cell + 0.01, "hi": cell + 0.1})
    e58 = claims.EXPERIMENTS["E58"].supports
    t12 = value("T12-calibrated-audit.optimism_original")
    assert e58({"ok": 1, "lo": t12 - 0.01, "hi": t12 + 0.01}) and not e58({"ok": 0, "lo": 0.0, "hi": 1.0})


def test_ex5_experiments_speak_only_to_their_claims():
    by_claim = {c.id: [e for e, _ in claims.explanations(c)] for c in claims.CLAIMS}
    owners = {e: cid for cid, es in by_claim.items() for e in es if e.startswith(("E55", "E56", "E57", "E58"))}
    assert set(owners.values()) == {"tab:audit", "T12-calibrated-audit", "T13-cost-of-calibration", "T14-resplits"}
    assert all(e in claims.EXPERIMENTS for e in owners)
