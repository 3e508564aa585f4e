"""ex29's E187 (T36's k = 1 AUC at the paper's own first-tap band loss): hand cases with exact answers."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.studies import claims
from probecommit.studies.explain import ex29_band as ex29
from probecommit.studies.paper_values import value

INPUTS = {"x_low": -10.0, "x_high": 10.0, "c_low": 0.7, "c_high": 1.3, "tip_radius": 1.2, "sim_offset": 0.905}


def _part(name: str = "b_test", first_tap: float = -12.0) -> pd.DataFrame:
    """Six trajectories: A band escaped, B-D band covered (all surprise 3), E off-band escaped, F off-band covered
    (surprise 1)."""
    return pd.DataFrame({"part": name, "instance_id": list("ABCDEF"), "repeat": 0,
                         "surprise_k1": [3.0, 3.0, 3.0, 3.0, 1.0, 1.0],
                         "escaped_final": [True, False, False, False, True, False],
                         "first_tap_pocket": [True, True, True, True, False, False],
                         "first_tap": first_tap, "in_band": [True, True, True, True, False, False], **INPUTS})


def test_band_weights_set_the_band_share_to_q():
    part = _part()
    w = ex29.band_weights(part, 0.5)
    assert np.allclose(w, [2.0, 2 / 3, 2 / 3, 2 / 3, 1.0, 1.0])
    band, esc = part["in_band"].to_numpy(bool), part["escaped_final"].to_numpy(bool)
    assert math.isclose(w[band & esc].sum() / w[band].sum(), 0.5)
    assert ex29.band_weights(part.assign(in_band=False), 0.5) is None
    assert ex29.band_weights(part.assign(escaped_final=part["in_band"]), 0.5) is None  # band share 1


def test_band_weighted_auc_hand_case():
    part = _part()
    # As run: A ties B-D (1.5) and beats F (1); E loses to B-D and ties F (0.5): 3 / (2 x 4).
    assert math.isclose(ex29.band_weighted_auc(part, None), 0.375)
    # Whole band lost: A weight 4, B-D 0; (4 x 1 + 0.5) / (5 x 1).
    assert math.isclose(ex29.band_weighted_auc(part, 1.0), 0.9)
    # Half lost: A 2, B-D 2/3 each; (2 x 2 x 0.5 + 2 x 1 + 0.5) / (3 x 3).
    assert math.isclose(ex29.band_weighted_auc(part, 0.5), 0.5)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.booleans(), st.booleans()), min_size=2, max_size=40))
def test_a_binary_first_reading_gives_the_tpr_fpr_identity(pairs):
    """A score that is the first reading's class: AUC = 0.5 + (TPR - FPR) / 2 (ours_keys' ``binary``)."""
    pocket, esc = (np.array(x, bool) for x in zip(*pairs))
    if esc.all() or not esc.any():
        return
    part = pd.DataFrame({"surprise_k1": pocket.astype(float), "escaped_final": esc, "first_tap_pocket": pocket,
                         "in_band": False, "first_tap": -9.0})
    keys = ex29.ours_keys(part)
    assert math.isclose(keys["auc"], keys["binary"], abs_tol=1e-12)


def test_random_keys_split_the_band_at_the_first_tap():
    part = pd.DataFrame({"first_tap": [-12.0, -12.0, 0.0, 0.0, 3.0], "in_band": [True, True, True, True, False],
                         "escaped_final": [True, False, False, False, False]})
    got = ex29.random_keys(part, -12.0)
    assert got == {"n_band.at_first": 2, "n_band.all": 4, "band_escaped_k1.at_first": 0.5,
                   "band_escaped_k1.all": 0.25, "escaped_k1_off_band": 0}


def _rows() -> pd.DataFrame:
    return pd.concat([_part("b_test"), _part("a"), _part(ex29.OURS, -9.0),
                      _part(ex29.RANDOM).assign(first_tap=[-12.0, 0.0, 3.0, -12.0, 6.0, 9.0])], ignore_index=True)


def test_summary_rates_rule_and_stored_round_trip(tmp_path):
    rows = _rows()
    keys = ex29.summary(rows)
    assert math.isclose(keys["q1"], value("T11-audit-trend.escape_k1") / 100.0 / keys["p_band_nine"])
    assert math.isclose(keys["top_first_room"], 2 * (1 - value("T36-surprise.auc_k1")) * value("T36-surprise.escaped"))
    assert keys["draws"] == 2 and keys["first_tap"] == -12.0
    assert math.isclose(keys["b_test.auc_all"], 0.9) and keys["b_test.top_first_escapes"] == 1.0
    assert math.isclose(keys["auc_q1.min"], ex29.band_weighted_auc(_part(), keys["q1"]))
    paper = value("T36-surprise.auc_k1")
    assert keys["holds"] == float(keys["auc_q1.min"] <= paper <= keys["auc_q1.max"])
    assert keys["ours.first_tap"] == -9.0 and keys["ours.band_escapes"] == 1
    assert keys["random.n_band.at_first"] == 2
    rows.to_parquet(tmp_path / ex29.STORED)
    assert ex29.summary(pd.read_parquet(tmp_path / ex29.STORED)) == keys


def test_part_rows_join_the_first_tap_and_its_band():
    ids = ["i0", "i1"]
    episodes = pd.DataFrame([{"instance_id": i, "repeat": 0, "k": k, "method": "probe_robust", "status": "ok",
                              "max_surprise": 1.0 + k + n, "escaped": k == 5 and n == 0}
                             for n, i in enumerate(ids) for k in (1, 5)])
    probes = pd.DataFrame({"instance_id": ids, "repeat": [0, 0], "j": [1, 1], "u": [-12.0, -12.0],
                           "y": [-15.0, 0.0]})
    # hg(1) = 4.6: the band beside -12 mm is [-8.6, -6.495); -7 is in it, 5 is not.
    instances = pd.DataFrame({"instance_id": ids, "true_x_hole": [-7.0, 5.0], "true_c": [1.0, 1.0]})
    rows = ex29.part_rows("b_test", episodes, probes, instances, 5, INPUTS)
    assert list(rows["in_band"]) == [True, False] and list(rows["escaped_final"]) == [True, False]
    assert list(rows["first_tap_pocket"]) == [True, False] and list(rows["surprise_k1"]) == [2.0, 3.0]
    assert set(ex29.BAND_COLUMNS) <= set(rows.columns) and list(rows["first_tap"]) == [-12.0, -12.0]


def test_e187_is_registered_for_t36_k1_and_verify_recomputes_it():
    from probecommit.report import recompute

    e = claims.EXPERIMENTS["E187"]
    assert e.supports({"h": 1.0}) and not e.supports({"h": 0.0})
    t36 = next(c for c in claims.CLAIMS if c.id == "T36-surprise")
    assert ("E187", ("k=1",)) in claims.explanations(t36)
    assert ("ex29_band", ex29.STORED, "ex29_band") in recompute.STORED_SUMMARIES


def test_position_keys_scale_q1_by_the_draws_band_loss_against_the_random_runs():
    rows = _rows()
    got = ex29.position_keys(rows, 0.3, 0.125)
    assert math.isclose(got["band_share.pooled"], 0.25) and math.isclose(got["position_ratio"], 2.0)
    assert math.isclose(got["q_first"], 0.6)
    assert math.isclose(got["auc_q_first.min"], ex29.band_weighted_auc(_part(), 0.6))
    keys = ex29.summary(rows)
    assert math.isclose(keys["position_ratio"], 0.25 / keys["random.band_escaped_k1.all"])
