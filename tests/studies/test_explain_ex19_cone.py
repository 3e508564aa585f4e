"""ex19's E139 (2-D push under the pyramidal cone over E95's pool): the keys on hand-built rows with exact answers,
each premise's and the contrast's teeth, the claim's wiring and the stored rows' round trip."""

from __future__ import annotations

import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex19_cone as ec

from .recompute_contract import assert_round_trip

PAPER = {"blind_bayes": 0.252, "blind_robust": 0.307, "probe_robust": 0.221}


def _rows(pyramidal: dict[str, float], elliptic: dict[str, float], replay_off: float = 0.0,
          probe_off: float = 0.0) -> pd.DataFrame:
    """Two pool truths with the same cells (exact bands), two episodes each arm; probe rests per cone."""
    rows = []
    for cone, cells in (("pyramidal", pyramidal), ("elliptic", elliptic)):
        for truth in ("a", "b"):
            for method, miss in cells.items():
                stored = miss + (replay_off if truth == "b" else 0.0) if method == "probe_robust" else float("nan")
                rows += [{"kind": "miss", "cone": cone, "truth": truth, "method": method, "realized": miss,
                          "stored": stored if cone == "elliptic" else float("nan")} for _ in range(2)]
            rows += [{"kind": "probe", "cone": cone, "truth": truth, "pulse": u,
                      "x": u / 10 + (probe_off if cone == "pyramidal" else 0.0), "y": 0.0} for u in (1.0, 2.0, 3.0)]
    return pd.DataFrame(rows)


def test_keys_hold_when_the_pyramidal_bands_hold_the_paper_and_the_elliptic_one_does_not():
    k = ec.keys(_rows(PAPER, {**PAPER, "probe_robust": 0.09}), 20)
    assert k["premise.probe_max_m"] == 0 and k["premise.replay_max_m"] == 0 and k["premise_holds"] == 1
    assert k["pyramidal.probe_robust.p025"] == pytest.approx(0.221) and k["pyramidal.probe_robust.paper_inside"] == 1
    assert k["pyramidal.probe_over_robust.mean"] == pytest.approx(0.221 / 0.307)
    assert k["paper.probe_over_robust"] == pytest.approx(0.221 / 0.307)
    assert k["elliptic.probe_robust.paper_inside"] == 0 and k["pyramidal.all_inside"] == 1 and k["holds"] == 1
    assert (k["pool_truths"], k["n_truths"], k["draws"]) == (2, 3, 20)


@pytest.mark.parametrize("change", ["replay", "probe", "contrast", "ratio"])
def test_each_condition_has_teeth(change):
    elliptic = {**PAPER, "probe_robust": 0.221 if change == "contrast" else 0.09}
    pyramidal = {**PAPER, "blind_robust": 0.5} if change == "ratio" else PAPER
    k = ec.keys(_rows(pyramidal, elliptic, replay_off=1e-5 if change == "replay" else 0.0,
                      probe_off=0.001 if change == "probe" else 0.0), 20)
    assert k["holds"] == 0
    if change == "probe":
        assert k["premise.probe_max_m"] == pytest.approx(0.001) and k["premise_holds"] == 0
    if change == "ratio":  # Blind-Robust 0.5 also moves the ratio out: probing's small gain is the row's point
        assert k["pyramidal.probe_over_robust.paper_inside"] == 0


def test_e139_supports_only_when_everything_holds_and_speaks_to_push2d_probe():
    e = claims.EXPERIMENTS["E139"]
    assert e.supports({"holds": 1, "ok": 1}) and not e.supports({"holds": 0, "ok": 1})
    breadth = next(c for c in claims.CLAIMS if c.id == "tab:breadth")
    spoken = {e[0]: e[1] for e in breadth.explain if isinstance(e, tuple)}
    assert spoken["E139"] == ("push2d probe_robust",)


def test_stored_rows_round_trip(tmp_path):
    from probecommit.studies.explain import ex19

    rows = _rows(PAPER, {**PAPER, "probe_robust": 0.09})
    keys = ec.keys(rows, 20)
    values, sources, problems = ex19.recompute(tmp_path, {"ex19_cone": keys})
    assert problems  # published without its rows
    assert_round_trip(tmp_path, lambda f, r: ex19.recompute(f, r), "ex19_cone", ec.STORED, rows, keys)


class _Scene:
    """A scene whose rest is (J_x * mu, J_y): exact misses by hand."""

    def rest_of(self, theta, action):
        return (action[0] * theta[0], action[1])


def test_miss_rows_run_every_pool_episode_and_every_stored_blind_action_at_every_pool_truth():
    pool = pd.DataFrame({"method": ["probe_robust", "probe_robust", "probe_robust"], "k": [5, 5, 2],
                         "true_mu": [0.5, 0.25, 0.5], "true_m": [1.0, 1.0, 1.0], "true_k_d": [2.0, 2.0, 2.0],
                         "ctx_target_x": [1.0, 1.0, 1.0], "ctx_target_y": [0.0, 0.0, 0.0],
                         "action_0": [2.0, 4.0, 9.0], "action_1": [0.0, 0.0, 0.0], "realized": [0.0, 0.0, 0.0]})
    blind = pd.DataFrame({"method": ["blind_bayes", "blind_robust", "blind_robust", "probe_robust"], "k": [0, 0, 0, 5],
                          "ctx_target_x": [1.0] * 4, "ctx_target_y": [0.0] * 4, "action_0": [3.0, 1.0, 2.0, 7.0],
                          "action_1": [0.0, 0.0, 0.0, 0.0]})
    rows = ec.miss_rows(pool, blind, _Scene(), "pyramidal")
    probe = rows[rows["method"] == "probe_robust"]
    assert list(probe["realized"]) == [0.0, 0.0] and list(probe["stored"]) == [0.0, 0.0]  # k = 2 row not read
    by = rows[rows["method"] != "probe_robust"].groupby(["truth", "method"])["realized"].apply(sorted).to_dict()
    a, b = "0.500000|1.000000|2.000000", "0.250000|1.000000|2.000000"
    assert by[(a, "blind_bayes")] == [0.5] and by[(a, "blind_robust")] == [0.0, 0.5]
    assert by[(b, "blind_bayes")] == [0.25] and by[(b, "blind_robust")] == [0.5, 0.75]
