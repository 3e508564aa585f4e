"""ex19's explain experiment (E138): the implied width's interpolation, the model premise on hand-built rows, the
rule's teeth (one failing condition at a width fails it), the claim's wiring and the stored rows' round trip."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex19_darts as ed

from .recompute_contract import assert_round_trip

#: Two of our darts truths (k_d, m, g), our targets, and two stored launches (speed m/s, elevation deg).
TRUTHS = ((0.0053, 0.0375, 9.3), (0.0187, 0.0325, 9.97))
TARGETS = (2.0, 3.0)
ACTIONS = {2.0: (4.6, 10.0), 3.0: (5.8, 10.0)}


def _rows(scale: float, realized_from_model: bool = True) -> pd.DataFrame:
    """Blind episodes at ``scale`` (truths mapped as E38's ``scaled_config`` maps them), two seeds, the misses
    the model gives (or off by 10 %)."""
    model = ed.model_at(scale)
    centre = (np.asarray(ed.model_at(1.0).prior_low) + np.asarray(ed.model_at(1.0).prior_high)) / 2
    rows = []
    for i, truth in enumerate(TRUTHS):
        theta = centre + scale * (np.asarray(truth) - centre)
        for target in TARGETS:
            action = np.asarray([ACTIONS[target]])
            miss = float(np.asarray(model.loss(action, theta[None, :], np.asarray([target])))[0, 0])
            for method in ed.ARMS:
                for repeat in range(2):
                    rows.append({"instance_id": f"i{i}-{target}", "repeat": repeat, "method": method,
                                 "realized": miss if realized_from_model else 1.1 * miss,
                                 "action_0": action[0, 0], "action_1": action[0, 1], "true_k_d": theta[0],
                                 "true_m": theta[1], "true_g": theta[2], "ctx_target": target, "scale": scale})
    return pd.DataFrame(rows)


def _e38(scale: float, lo: float = 0.008, hi: float = 0.016, paired_lo: float = 0.01) -> dict[str, float]:
    return {f"darts.s{scale:g}.probe_robust_lo": lo, f"darts.s{scale:g}.probe_robust_hi": hi,
            f"darts.s{scale:g}.paired_lo": paired_lo}


def test_implied_width_is_log_log_interpolation_and_none_outside_the_grid():
    assert ed.implied_width([0.5, 1.0, 2.0], [1.0, 2.0, 4.0], 3.0) == pytest.approx(1.5)
    assert ed.implied_width([0.25, 1.0], [1.0, 4.0], 2.0) == pytest.approx(0.5)  # v ~ s: the geometric mean
    assert math.isnan(ed.implied_width([0.5, 1.0], [1.0, 2.0], 5.0))


def test_the_model_premise_holds_on_rows_it_made_and_fails_off_by_ten_percent():
    good = ed.width_keys(_rows(0.25), 0.25, draws=20)
    assert good["blind_bayes.premise_rel_diff"] < 1e-12 and good["premise_holds"] == 1
    for arm in ed.ARMS:
        assert good[f"{arm}.p025"] <= good[f"{arm}.mean"] <= good[f"{arm}.p975"]
    bad = ed.width_keys(_rows(0.25, realized_from_model=False), 0.25, draws=20)
    assert bad["blind_bayes.premise_rel_diff"] == pytest.approx(0.1 / 1.1) and bad["premise_holds"] == 0
    assert bad["blind_inside"] == 0


def test_probed_checks_read_e38_at_that_width():
    inside = ed.probed_checks(_e38(0.25), 0.25)
    assert inside == {"probe_robust_lo": 0.008, "probe_robust_hi": 0.016, "probe_robust.paper_inside": 1.0,
                      "paired_lo": 0.01, "paired_excludes_zero": 1.0}
    assert ed.probed_checks(_e38(0.25, lo=0.011), 0.25)["probe_robust.paper_inside"] == 0  # the paper's 0.010
    assert ed.probed_checks(_e38(0.25, paired_lo=-0.001), 0.25)["paired_excludes_zero"] == 0
    assert ed.probed_checks({}, 0.25)["probe_robust.paper_inside"] == 0  # no E38 row there: nothing holds


def test_a_width_holds_only_when_every_condition_does(monkeypatch):
    blind = {"blind_inside": 1.0, "premise_holds": 1.0, "blind_bayes.paper_inside": 1.0,
             "blind_robust.paper_inside": 1.0, "ratio.paper_inside": 1.0, "blind_bayes.mean": 0.02,
             "blind_robust.mean": 0.03, "blind_bayes.stored": 0.04, "blind_robust.stored": 0.04}
    per = {0.25: blind, 1.0: blind | {"blind_inside": 0.0, "blind_bayes.paper_inside": 0.0, "blind_bayes.mean": 0.08,
                                      "blind_robust.mean": 0.13, "blind_bayes.stored": 0.16,
                                      "blind_robust.stored": 0.17}}
    monkeypatch.setattr(ed, "width_keys", lambda rows, s, draws, family: dict(per[s]))
    stored = pd.DataFrame({"scale": [0.25, 1.0]})
    k = ed.keys(stored, 10, _e38(0.25) | _e38(1.0))
    assert (k["s0.25.holds"], k["s1.holds"], k["widths_holding"], k["first_width"]) == (1, 0, 1, 0.25)
    assert k["best_width"] == 0.25 and k["best.holds"] == 1
    assert k["ratio.paper"] == pytest.approx(0.035 / 0.026)
    assert k["implied.prior.blind_bayes"] == pytest.approx(0.25 * 0.026 / 0.02)  # the mean ~ s: proportional
    slope = math.log(4) / math.log(0.13 / 0.03)
    assert k["implied.prior.blind_robust"] == pytest.approx(0.25 * (0.035 / 0.03) ** slope)
    assert math.isnan(k["implied.ours.blind_bayes"])  # 0.026 lies below the stored cells at every width
    k = ed.keys(stored, 10, _e38(0.25, lo=0.011) | _e38(1.0))  # the probed cell outside at the one blind-holding width
    assert (k["widths_holding"], k["first_width"], k["best.holds"]) == (0, 0.0, 0)


def test_e138_supports_only_when_a_width_holds_with_its_premise():
    e = claims.EXPERIMENTS["E138"]
    assert e.supports({"h": 1, "holds": 1, "ok": 1})
    assert not e.supports({"h": 0, "holds": 0, "ok": 1}) and not e.supports({"h": 1, "holds": 1, "ok": 0})
    breadth = next(c for c in claims.CLAIMS if c.id == "tab:breadth")
    spoken = {e[0]: e[1] for e in breadth.explain if isinstance(e, tuple)}
    assert spoken["E138"] == ("darts blind_bayes", "darts blind_robust", "darts probe_robust")


def test_stored_rows_round_trip(tmp_path):
    from probecommit.studies.explain import ex19

    e38 = _e38(0.25) | _e38(1.0)
    stored = pd.concat([_rows(0.25), _rows(1.0)], ignore_index=True)
    keys = ed.keys(stored, 20, e38)
    (tmp_path / "results.json").write_text(json.dumps({"results": {"breadth_prior": e38}}))
    assert_round_trip(tmp_path, ex19.recompute, "ex19_darts", ed.STORED, stored, keys)


def test_the_other_rows_print_only_blind_bayes_and_keep_their_truth_set_sizes():
    assert ed.printed("darts") == ("blind_bayes", "blind_robust")
    assert ed.printed("hinge") == ("blind_bayes",) and ed.printed("push1d") == ("blind_bayes",)
    assert (ed.N_TRUTHS["hinge"], ed.N_TRUTHS["push1d"]) == (6, 27)


def test_widths_keys_prefix_each_row_and_use_its_own_printed_cells(monkeypatch):
    seen = []

    def fake(rows, draws, e38, family):
        seen.append((family, len(rows), "family" in rows))
        return {"holds_somewhere": 1.0}

    monkeypatch.setattr(ed, "keys", fake)
    stored = pd.DataFrame({"family": ["hinge", "hinge", "push1d"], "scale": [1.0, 1.0, 1.0]})
    assert ed.widths_keys(stored, 5, {}) == {"hinge.holds_somewhere": 1.0, "push1d.holds_somewhere": 1.0}
    assert seen == [("hinge", 2, False), ("push1d", 1, False)]


def test_e140_e141_speak_to_the_rows_uncovered_cells():
    breadth = next(c for c in claims.CLAIMS if c.id == "tab:breadth")
    spoken = {e[0]: e[1] for e in breadth.explain if isinstance(e, tuple)}
    assert spoken["E140"] == ("hinge probe_robust",)
    assert spoken["E141"] == ("push1d blind_bayes", "push1d probe_robust")
    for n in ("E140", "E141"):
        assert claims.EXPERIMENTS[n].supports({"h": 1, "holds": 1, "ok": 1})
        assert not claims.EXPERIMENTS[n].supports({"h": 0, "holds": 0, "ok": 1})


def test_widths_rows_round_trip(tmp_path, monkeypatch):
    from probecommit.studies.explain import ex19

    monkeypatch.setattr(ed, "keys", lambda rows, draws, e38, family: {"draws": float(draws),
                                                                     "cell": float(rows["realized"].mean())})
    stored = pd.DataFrame({"family": ["hinge", "push1d"], "scale": [1.0, 1.0], "realized": [0.25, 0.5]})
    keys = ed.widths_keys(stored, 7, {})
    assert keys == {"hinge.draws": 7.0, "hinge.cell": 0.25, "push1d.draws": 7.0, "push1d.cell": 0.5}
    assert_round_trip(tmp_path, ex19.recompute, "ex19_widths", ed.STORED_WIDTHS, stored, keys)
