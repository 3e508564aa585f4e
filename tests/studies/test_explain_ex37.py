"""ex37's E211 (T33's adjusted gate under the paper's schedule), E212 and E213 (the robust filters' optimism off the
harness draw): hand cases with exact answers, same-seed equality, the rules at their edges, registration, the
replay on a small analytic run and verify's round trips."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex37_adjusted, ex37_filters
from probecommit.studies.paper_values import value

from .recompute_contract import assert_bootstrapped_round_trip

BOOT = {"resamples": 50, "seed": 3}
FLOOR = value("T43-robust-filters.optimism_floor")


def _gate_rows(escaped: set[int] = frozenset({0, 1, 6})) -> pd.DataFrame:
    """Ten trajectories (five instances x two repeats), budgets 1 and 2. Trajectory t's adjusted score is t / 10 at
    k = 1 and 1 at k = 2, so a threshold t / 10 commits t + 1 of them: the 60 % point is 0.5, trajectories 0..5.
    The raw executor's final escape is ``escaped``; its score and posterior variance are t's reverse."""
    rows = []
    for t in range(10):
        for k in (1, 2):
            base = {"instance_id": f"i{t // 2}", "repeat": t % 2, "k": k, "status": "ok", "threshold": 0.9, "gamma": 0.6}
            rows.append({**base, "request": "adjusted", "predicted": t / 10 if k == 1 else 1.0, "realized": float(t % 3 == 0)})
            rows.append({**base, "request": "raw", "predicted": (9 - t) / 10 if k == 1 else 1.0, "realized": 0.0,
                         "escaped": k == 2 and t in escaped, "post_var": float(9 - t), "max_surprise": 0.0})
    out = pd.DataFrame(rows)
    out["escaped"] = out["escaped"].astype("boolean")
    return out


def test_adjusted_pool_by_hand():
    v = ex37_adjusted.keys(_gate_rows(), BOOT)
    assert v["adjusted.tau"] == 0.5 and v["adjusted.n_committed"] == 6 and v["adjusted.n_rejected"] == 4
    assert v["adjusted.escaped_committed"] == 2 and v["adjusted.escaped_rejected"] == 1
    assert v["adjusted.final_hull.committed_rate"][0] == pytest.approx(2 / 6)
    assert v["adjusted.final_hull.rejected_rate"][0] == pytest.approx(1 / 4)
    assert v["adjusted.final_hull.ratio"][0] == pytest.approx((2 / 6) / (1 / 4))
    assert v["adjusted.realized"] == pytest.approx(np.mean([t % 3 == 0 for t in range(6)]))
    # the raw gate commits the reverse half: trajectories 4..9 (its escapes 6 only), rejecting 0..3 (0 and 1)
    assert (v["raw.n_committed"], v["raw.escaped_committed"], v["raw.escaped_rejected"]) == (6, 1, 2)
    assert v["threshold"] == 0.9 and v["gamma"] == 0.6 and v["trajectories"] == 10
    assert "posterior_variance.claimed" not in v
    again = ex37_adjusted.keys(_gate_rows(), BOOT)
    assert again == v  # same seed, same keys


def test_e211_is_t33s_fold_at_its_edge():
    e211 = claims.EXPERIMENTS["E211"].supports
    assert e211 is claims.several_times
    assert e211({"ec": 4, "nc": 8, "er": 1, "nr": 4})  # 0.5 against 0.25: exactly twice
    assert not e211({"ec": 4, "nc": 8, "er": 1, "nr": 3.99})
    assert not e211({"ec": 0, "nc": 8, "er": 0, "nr": 4})
    assert not e211(_pool(ex37_adjusted.keys(_gate_rows(), BOOT)))  # 1.33 x


def _pool(v: dict) -> dict:
    return {"ec": v["adjusted.escaped_committed"], "nc": v["adjusted.n_committed"], "er": v["adjusted.escaped_rejected"],
            "nr": v["adjusted.n_rejected"]}


def test_e211_credited_with_the_adjusted_gate_only_and_its_keys_exist():
    t33 = next(c for c in claims.CLAIMS if c.id == "T33-committed-pool")
    assert ("E211", (f"{claims.EXACT}adjusted",)) in claims.explanations(t33)
    keys = {f"{claims.X}{ex37_adjusted.GROUP}.{k}" for k in ex37_adjusted.keys(_gate_rows(), BOOT)}
    keys |= {f"{k}.{i}" for k in keys for i in (1, 2)}
    own = {v for v in claims.EXPERIMENTS["E211"].keys.values() if v.startswith(claims.X)}
    assert own <= keys  # beside them: our schedule's adjusted pools (insertion) and the paper's escape count


def test_verify_recomputes_e211_from_the_stored_rows(tmp_path):
    from probecommit.report import recompute

    rows = _gate_rows({0, 6, 7})
    assert_bootstrapped_round_trip(tmp_path, ex37_adjusted, rows, ex37_adjusted.keys(rows, BOOT), BOOT)
    assert "ex37_adjusted" in recompute.BOOTSTRAPPED


def _filter_rows() -> pd.DataFrame:
    """Test C (deployed and rejuvenation) and two draws with three arms; each (source, arm) has two episodes whose
    optimism (realized - predicted) is given by hand."""
    cells = {("testc", "deployed"): (0.4, 0.2), ("testc", "rejuvenation"): (0.5, 0.1),
             ("d0", "deployed"): (0.3, 0.3), ("d0", "mixture"): (0.2, 0.3), ("d0", "rejuvenation"): (0.3, 0.4),
             ("d1", "deployed"): (0.1, 0.1), ("d1", "mixture"): (0.2, 0.2), ("d1", "rejuvenation"): (0.0, 0.1)}
    rows = []
    for (source, arm), pair in cells.items():
        for i, o in enumerate(pair):
            rows.append({"source": source, "arm": arm, "instance_id": f"i{i}", "repeat": 0, "k": 8, "predicted": 0.5,
                         "realized": 0.5 + o, "escaped": i == 0 and arm == "rejuvenation"})
    return pd.DataFrame(rows)


def test_filter_keys_by_hand():
    v = ex37_filters.summary(_filter_rows())
    assert v["testc.deployed.optimism"] == pytest.approx(0.3) and v["testc.rejuvenation.optimism"] == pytest.approx(0.3)
    assert v["testc.rejuvenation.escape"] == 0.5 and v["testc.n"] == 2 and v["draws.count"] == 2
    assert v["draws.d0.mixture.optimism"] == pytest.approx(0.25)
    assert (v["draws.deployed.optimism.min"], v["draws.deployed.optimism.max"]) == pytest.approx((0.1, 0.3))
    assert (v["draws.mixture.optimism.min"], v["draws.mixture.optimism.max"]) == pytest.approx((0.2, 0.25))
    assert v["draws.rejuvenation.optimism.mean"] == pytest.approx((0.35 + 0.05) / 2)
    assert v["draws.mixture.max_gap"] == pytest.approx(0.1)  # d1: 0.2 against 0.1
    assert v["draws.rejuvenation.max_gap"] == pytest.approx(0.05)
    assert ex37_filters.summary(_filter_rows()) == v


def test_e212_and_e213_rules_at_their_edges():
    e212 = claims.EXPERIMENTS["E212"].supports
    assert e212({"to": FLOOR + 1e-9}) and not e212({"to": FLOOR})
    for f in ("mixture", "rejuvenation"):
        e213 = claims.EXPERIMENTS[f"E213[optimism {f}]"].supports
        ok = {"lo": FLOOR - 0.05, "hi": FLOOR, "gap": claims.EX37_SAME_OPTIMISM}
        assert e213(ok) and e213({**ok, "lo": FLOOR, "hi": FLOOR + 0.1})
        assert not e213({**ok, "gap": claims.EX37_SAME_OPTIMISM + 1e-9})
        assert not e213({**ok, "hi": FLOOR - 1e-9}) and not e213({**ok, "lo": FLOOR + 1e-9, "hi": FLOOR + 0.1})


def test_e212_e213_credited_with_their_optimism_labels_and_their_keys_exist():
    t43 = next(c for c in claims.CLAIMS if c.id == "T43-robust-filters")
    got = claims.explanations(t43)
    assert not [n for n, _ in got if n in ("E12", "E212")]  # Test C is an outlier draw: beside, uncredited (rev2)
    keys = {f"{claims.X}{ex37_filters.GROUP}.{k}" for k in ex37_filters.summary(_filter_rows())}
    keys.add(f"{claims.X}robust.harness.rejuvenation.optimism")
    assert set(claims.EXPERIMENTS["E212"].keys.values()) <= keys
    for f in ("mixture", "rejuvenation"):
        assert (f"E213[optimism {f}]", (f"{claims.EXACT}optimism {f}",)) in got
        assert set(claims.EXPERIMENTS[f"E213[optimism {f}]"].keys.values()) <= keys | {f"{claims.X}robust.harness.deployed.optimism"}


def test_arms_are_the_insertion_studys_chosen_filters_under_the_deployed_boundary():
    from probecommit.studies.protocol import load_protocol
    from probecommit.studies.robust import robust_candidates

    p = load_protocol()
    r = p.robust
    grid = robust_candidates(r.temperatures, r.epsilons, r.rejuvenation, r.mixture_range)
    chosen = {"mixture": grid["mixture"][1][0], "rejuvenation": grid["rejuvenation"][0][0]}
    arms = ex37_filters.arm_overrides(p, chosen)
    assert list(arms) == list(ex37_filters.ARMS)
    assert all(a["model"] == {"boundary": "deployed"} for a in arms.values()) and "belief" not in arms["deployed"]
    assert arms["mixture"]["belief"] == grid["mixture"][1][1]
    assert arms["rejuvenation"]["belief"] == grid["rejuvenation"][0][1]
    with pytest.raises(ValueError):
        ex37_filters.arm_overrides(p, {"mixture": 0.123, "rejuvenation": chosen["rejuvenation"]})


def test_a_replay_without_overrides_gives_the_stored_final_rows(tmp_path):
    from probecommit.runner.replay import load_run
    from probecommit.runner.study import run_study
    from tests.conftest import small_config

    cfg = small_config(name="C_random", instances={"split": "test", "count": 3, "seed": 5}, methods=["probe_robust"])
    loaded = load_run(run_study(cfg, tmp_path / "run").run_dir)
    rows = ex37_filters.draw_rows(loaded, {"deployed": {}, "rejuvenation": {"belief": {"rejuvenation": 0.5}}}, 5, "d")
    stored = ex37_filters.final_rows(loaded.episodes, 5, "d", "deployed")
    pd.testing.assert_frame_equal(rows[rows["arm"] == "deployed"].reset_index(drop=True), stored, check_dtype=False)
    assert len(rows[rows["arm"] == "rejuvenation"]) == len(stored) == 3 * 2


def test_verify_recomputes_the_filters_from_their_stored_rows(tmp_path):
    from probecommit.report import recompute

    assert (ex37_filters.GROUP, ex37_filters.STORED, "ex37_filters") in recompute.STORED_SUMMARIES
    rows = _filter_rows()
    rows.to_parquet(tmp_path / ex37_filters.STORED)
    out = recompute.Recomputed()
    recompute._stored_summaries(tmp_path, {ex37_filters.GROUP: ex37_filters.summary(rows)}, out)
    assert {k: v for k, v in out.values.items() if k.startswith(ex37_filters.GROUP + ".")} \
        == {f"{ex37_filters.GROUP}.{k}": v for k, v in ex37_filters.summary(rows).items()}
