"""Hand cases for ex10's experiment E87 (PyBullet's tap boundary drawn per tap): the re-read rule, the per-tap
draws, the escape summary, the stored-run check, and the registry rule wiring it (each can fail)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex10_boundary as eb

BOOT = dict(resamples=200, seed=0)


def _instances() -> pd.DataFrame:
    # c = 1: hg = 4.6 mm, so with the mean offset 0.9 the boundary sits 5.5 mm from the hole
    return pd.DataFrame({"instance_id": ["a", "b"], "instance_index": [0, 1], "true_x_hole": [0.0, -3.0],
                         "true_c": [1.0, 1.0]})


def test_reread_decides_each_level_against_the_drawn_boundary_and_keeps_the_noise():
    probes = pd.DataFrame({"instance_id": ["a", "a", "a", "b"], "repeat": 0, "j": [1, 2, 3, 1],
                           "u": [5.0, 5.0, 6.0, -9.0], "y": [-15.2, 0.3, -14.9, 0.1]})
    z = np.array([-1.0, 0.0, 1.0, 0.6])
    out = eb.reread(probes, _instances(), z, mean_offset=0.9, s=1.0)
    # boundaries 4.5, 5.5, 6.5 from hole a (taps at 5, 5, 6 mm) and 6.1 from hole b (tap 6 mm away)
    assert out["y"].tolist() == pytest.approx([-0.2, -14.7, -14.9, -14.9])
    same = eb.reread(probes, _instances(), z, mean_offset=0.9, s=0.0)  # s = 0: a fixed line at 5.5 mm
    assert same["y"].tolist() == pytest.approx([-15.2, -14.7, 0.1, 0.1])
    assert out[["instance_id", "repeat", "j", "u"]].equals(probes[["instance_id", "repeat", "j", "u"]])


def test_tap_draws_follow_the_tap_not_the_row_order():
    probes = pd.DataFrame({"instance_id": ["a", "a", "b", "a"], "repeat": [0, 0, 0, 1], "j": [1, 2, 1, 1],
                           "u": 0.0, "y": 0.0})
    z = eb.tap_draws(probes, _instances(), seed=5)
    shuffled = probes.iloc[[3, 1, 2, 0]].reset_index(drop=True)
    z2 = eb.tap_draws(shuffled, _instances(), seed=5)
    assert z2.tolist() == [z[3], z[1], z[2], z[0]]
    assert len(set(np.round(z, 12))) == 4  # other tap, other repeat, other instance: other draws
    assert not np.allclose(eb.tap_draws(probes, _instances(), seed=6), z)


def test_summary_is_the_escape_share_per_variant_s_and_budget():
    rows = []
    for s, esc in ((np.nan, [0, 0, 0, 1]), (0.3, [1, 0, 1, 1])):
        for i, e in enumerate(esc):
            for k in (1, 8):
                rows.append({"variant": "deployed", "s": s, "instance_id": f"i{i}", "repeat": 0, "k": k,
                             "escaped": bool(e) if k == 8 else False})
    out = eb.summary(pd.DataFrame(rows), BOOT)
    assert out["deployed.as_run.escape_k8"][0] == pytest.approx(0.25)
    assert out["deployed.s03.escape_k8"][0] == pytest.approx(0.75)
    assert out["deployed.s03.escape_k1"] == [0.0, 0.0, 0.0]
    assert eb.s_label(1.2) == "s12" and eb.s_label(0.0) == "s00"


def test_matches_stored_needs_every_trajectory_and_budget():
    rows = pd.DataFrame({"variant": "deployed", "s": np.nan, "instance_id": ["a", "a"], "repeat": 0, "k": [1, 8],
                         "escaped": [False, True]})
    stored = rows.assign(method="probe_robust", status="ok").drop(columns=["s", "variant"])
    assert eb.matches_stored(rows, stored) == 1
    assert eb.matches_stored(rows, stored.assign(escaped=[False, False])) == 0
    assert eb.matches_stored(rows, stored.iloc[:1]) == 0  # a budget the stored run lacks


def test_e87_needs_all_four_paper_numbers_inside_at_one_sd():
    e = claims.EXPERIMENTS["E87"]
    by_id = {c.id: c for c in claims.CLAIMS}
    for claim_id in ("tab:engines", "T19-pybullet-escape"):
        assert "E87" in [x if isinstance(x, str) else x[0] for x in by_id[claim_id].explain]
    paper = {"d1": claims._pv("T19-pybullet-escape.k1"), "d8": claims._pv("T19-pybullet-escape.k8"),
             "m8": claims._pv("tab:engines.pybullet/mj_offset.support_escape"),
             "o8": claims._pv("tab:engines.pybullet/own_scan.support_escape")}
    far = {f"{c}.{eb.s_label(s)}{e}": (0.5 if e == "1" else 0.6) for s in claims.EX10_BOUNDARY_SD_MM
           for c in paper for e in ("1", "2")}
    assert not e.supports(far)
    one = {**far, **{f"{c}.s09{e}": p + (-0.01 if e == "1" else 0.01) for c, p in paper.items() for e in ("1", "2")}}
    assert e.supports(one)
    # three of four inside at s = 0.9 and the fourth inside only at s = 1.2 is no fit
    split = {**one, "o8.s091": paper["o8"] + 0.001, "o8.s121": paper["o8"] - 0.01, "o8.s122": paper["o8"] + 0.01}
    assert not e.supports(split)
    assert tuple(claims.EX10_BOUNDARY_SD_MM) == (0.0, 0.3, 0.6, 0.9, 1.2)


def _surprise_rows() -> pd.DataFrame:
    """Four trajectories of two instances under two filters; budgets 1 and 5."""
    rows = []
    for name, esc, s1 in (("as_run", [False, False, True, False], [1.0, 2.0, 0.5, 0.7]),
                          ("mh", [True, False, True, False], [3.0, 2.0, 4.0, 0.7])):
        for t, (e, s) in enumerate(zip(esc, s1)):
            for k in (1, 5):
                rows.append({"filter": name, "instance_id": f"i{t // 2}", "repeat": t % 2, "k": k,
                             "density": s + (k - 1), "escaped_final": e, "first_tap_pocket": t == 0})
    return pd.DataFrame(rows)


def test_surprise_summary_counts_escapes_and_ranks_the_surprise():
    from probecommit.studies.explain import ex10_surprise as es

    out = es.summary(_surprise_rows(), BOOT)
    assert out["as_run.n_escaped"] == 1 and out["mh.n_escaped"] == 2
    assert out["as_run.auc_k1"][0] == pytest.approx(0.0)  # the one escape is the least surprised
    assert out["mh.auc_k1"][0] == pytest.approx(1.0) and out["mh.auc_k5"][0] == pytest.approx(1.0)
    assert out["mh.first_tap_pocket.escaped"] == pytest.approx(0.5)
    assert out["as_run.first_tap_pocket.escaped"] == pytest.approx(0.0)


def test_surprise_matches_stored_needs_surprise_and_final_label():
    from probecommit.studies.explain import ex10_surprise as es

    rows = _surprise_rows()
    mine = rows[rows["filter"] == "as_run"]
    stored = mine.rename(columns={"density": "max_surprise"}).assign(escaped=mine["escaped_final"])
    assert es.matches_stored(rows, stored) == 1
    assert es.matches_stored(rows, stored.assign(max_surprise=stored["max_surprise"] + 1e-6)) == 0
    flipped = stored.copy()
    flipped.loc[(flipped["k"] == 5) & (flipped["instance_id"] == "i0") & (flipped["repeat"] == 0), "escaped"] = True
    assert es.matches_stored(rows, flipped) == 0


def test_the_filters_change_only_the_belief_move():
    from probecommit.runner.config import config_data
    from probecommit.studies.explain import ex10_surprise as es
    from probecommit.studies.protocol import load_protocol

    assert es.FILTERS == {"as_run": {}, "mh": {"move": "mh"}, "no_jitter": {"jitter": False}}
    base = load_protocol().run_config("x", "B", "B_test_cover", "cover")
    moved = es.filter_config(base, es.FILTERS["mh"])
    a, b = config_data(base), config_data(moved)
    assert b["belief"]["move"] == "mh" and {**b, "belief": a["belief"]} == a


def test_e88_needs_both_paper_aucs_inside_the_tail_free_intervals():
    e = claims.EXPERIMENTS["E88"]
    assert "E88" in [x if isinstance(x, str) else x[0] for x in {c.id: c for c in claims.CLAIMS}["T36-surprise"].explain]
    k1, k5 = claims._pv("T36-surprise.auc_k1"), claims._pv("T36-surprise.auc_k5")
    ok = {"mh11": k1 - 0.05, "mh12": k1 + 0.05, "mh51": k5 - 0.05, "mh52": k5 + 0.05}
    assert e.supports(ok)
    assert not e.supports({**ok, "mh12": k1 - 0.01})
    assert not e.supports({**ok, "mh51": k5 + 0.01})
