"""ex15's E118 (T14's re-split sentence under every reading it admits): hand cases with exact answers."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from probecommit.studies import claims
from probecommit.studies.explain import ex15_readings as ex15
from probecommit.studies.paper_values import value


def _table() -> tuple[pd.DataFrame, pd.Series, np.ndarray, np.ndarray]:
    # 5 calibration clusters, alpha = 0.2: q = ceil(0.8 * 6) = 5, the largest calibration score of each budget
    ids = [f"c{j}" for j in range(5)] + ["t0", "t1"]
    table = pd.DataFrame({1: [0.1, 0.2, 0.3, 0.4, 0.5, 0.45, 0.6], 2: [0.3, 0.1, 0.2, 0.5, 0.7, 0.9, 0.55]},
                         index=ids)
    failed = pd.Series([0.0, 0.25, 0.5, 0.0, 1.0, 0.25, 0.75], index=ids)
    return table, failed, np.array(ids[:5]), np.array(["t0", "t1"])


def test_split_row_reads_each_budget_reading_exactly():
    table, failed, cal, test = _table()
    got = ex15.split_row(table, failed, cal, test, 0.2)
    # t_1 = 0.5, t_2 = 0.7 (the final budget's)
    assert got["level_a1"] == 0.7 and got["coverage_a1"] == 0.5  # t0 0.9 > 0.7, t1 0.55 <= 0.7
    assert math.isclose(got["level_a2"], 0.6)  # mean of t_1 and t_2
    assert math.isclose(got["coverage_a2"], 0.5 * (0.5 + 0.5))  # k = 1: t0 0.45 <= 0.5, t1 0.6 > 0.5
    assert math.isclose(got["coverage_a3"], 0.5 * (1.0 + 0.5))  # k = 1 against t_2 = 0.7: both covered
    assert got["coverage_a4"] == 0.5  # max over budgets: t0 0.9, t1 0.6
    assert got["base_failure"] == 0.5  # the held-out clusters' uncalibrated failure at the final budget


def test_pool_rows_use_the_study_splits_and_the_final_budgets_failure():
    rows = []
    for i in range(10):
        for k in (1, 2):
            for rep in range(2):
                rows.append({"instance_id": f"p-{i:02d}", "repeat": rep, "k": k, "method": "probe_robust",
                             "status": "ok", "score_s": 0.1 * i + 0.01 * k + 0.001 * rep,
                             "realized": float(k == 2 and rep == 0 and i % 2 == 0)})
    got = ex15.pool_rows("p", pd.DataFrame(rows), 0.2, 3, 7)
    assert list(got["index"]) == [0, 1, 2] and set(got["budgets"]) == {2}
    from probecommit.studies.explain.ex5_calibration import split_halves

    _, test = split_halves(np.array([f"p-{i:02d}" for i in range(10)]), 3, 7)[0]
    want = np.mean([0.5 if int(t[-2:]) % 2 == 0 else 0.0 for t in test])
    assert math.isclose(got["base_failure"].iloc[0], want)


def test_margin_columns_and_summary_shares():
    rows = pd.DataFrame({"pool": "a", "index": [0, 1], "budgets": 2, "level_a1": [0.4, 0.8],
                         "coverage_a1": [0.8, 0.9], "level_a2": [0.3, 0.5], "coverage_a2": [0.8, 0.8],
                         "coverage_a3": [0.9, 0.9], "coverage_a4": [0.7, 0.6], "base_failure": [0.2, 0.3]})
    study = pd.DataFrame({"split": [1, 0], "failure": [0.35, 0.25], "margin_optimistic": [True, False]})
    e55 = pd.DataFrame({"index": [0, 1], "difference": [0.1, 0.0], "optimism_k1": [-0.1, 0.2],
                        "optimism_k2": [0.05, -0.3]})
    got = ex15.summary(ex15.margin_columns(rows, study, e55))
    assert got["a.splits"] == 2 and math.isclose(got["a.a1.level"], 0.6) and math.isclose(got["a.a2.level"], 0.4)
    assert got["a.a3.level"] == got["a.a1.level"] and math.isclose(got["a.a4.coverage"], 0.65)
    assert math.isclose(got["a.c5.failure"], 0.3) and got["a.c5.b0"] == 0.5
    assert math.isclose(got["a.c15.failure"], 0.3)  # (0.2 + 0.1 + 0.3 + 0.0) / 2
    # split 0: optimism (-0.1, +0.05): last > 0, mean < 0, some > 0; split 1: (+0.2, -0.3): last < 0, mean < 0, some
    assert got["a.c15.b1"] == 0.5 and got["a.c15.b2"] == 0.0 and got["a.c15.b3"] == 1.0


def _at_paper() -> dict[str, float]:
    v = {"n": 50, "c5f": value("T14-resplits.failure_mean"), "c15f": 0.0,
         "c5b0": value("T14-resplits.margin_optimistic_percent") / 100, "c15b1": 0.0, "c15b2": 0.0, "c15b3": 0.0}
    for a in claims.EX15_READINGS:
        v[f"{a}l"], v[f"{a}c"] = 0.0, 0.0
    v["a3l"], v["a3c"] = value("T14-resplits.level_mean"), value("T14-resplits.heldout_cluster_coverage")
    return v


def test_e118_needs_all_four_numbers_of_one_reading():
    exp = claims.EXPERIMENTS["E118"]
    v = _at_paper()
    assert claims._ex15_inside(v) == ["a3/c5.b0"] and exp.supports(v)
    assert not exp.supports({**v, "c5f": v["c5f"] + 0.03})  # failure outside 0.02
    assert not exp.supports({**v, "a3l": v["a3l"] + 0.11})  # level outside 0.1
    assert not exp.supports({**v, "a3c": v["a3c"] - 0.06})  # coverage outside 0.05
    assert not exp.supports({**v, "c5b0": v["c5b0"] + 0.11})  # share outside 0.10
    # a level of one reading and a coverage of another do not make a pass
    assert not exp.supports({**v, "a3c": 0.0, "a1c": value("T14-resplits.heldout_cluster_coverage")})


def test_t14_names_e118_and_e119_for_its_three_failing_comparisons():
    t14 = next(c for c in claims.CLAIMS if c.id == "T14-resplits")
    spoken = {label for number, labels in (e if isinstance(e, tuple) else (e, ()) for e in t14.explain)
              if number in ("E118", "E119") for label in labels}
    assert spoken == {"level mean", "held-out cluster coverage", "margin optimistic"}


# ----------------------------------------------------------------------------- E119
def test_union_pools_two_runs_tables_with_instances_in_id_order():
    from probecommit.runner.replay import LoadedRun
    from probecommit.studies.explain import ex15_union

    def run(name: str, ids: list[str]) -> LoadedRun:
        table = pd.DataFrame({"instance_id": ids, "v": range(len(ids))})
        return LoadedRun(f"/nowhere/{name}", None, table[["instance_id"]], table, table, table, {"name": name})

    got = ex15_union.union([run("b", ["t-1", "t-0"]), run("a", ["c-0"])])
    assert list(got.instances["instance_id"]) == ["c-0", "t-0", "t-1"]
    assert list(got.episodes["instance_id"]) == ["t-1", "t-0", "c-0"] and len(got.engine_cache) == 3
    assert got.manifest == {"name": "b"} and str(got.path) == "/nowhere/b"


def test_e119_reads_the_union_pools_keys_under_e118s_rule():
    e118, e119 = claims.EXPERIMENTS["E118"], claims.EXPERIMENTS["E119"]
    assert set(e119.keys) == set(e118.keys)
    assert all(key.startswith("explain:results.ex15_union.B_union_cover.") for key in e119.keys.values())
    v = _at_paper()
    assert e119.supports(v) and not e119.supports({**v, "c5b0": 0.0})


def test_a_batch_pooling_two_splits_keeps_each_episodes_split_through_subsets():
    from probecommit.runner.inference import ProbeBatch

    n = 3
    batch = ProbeBatch(np.array(["a", "b", "b"], dtype=object), np.array(["a-0", "b-0", "b-1"], dtype=object),
                       np.array([0, 0, 1]), np.zeros(n, int), np.zeros((n, 2)), np.zeros((n, 1, 1)), np.zeros((n, 1, 1)))
    assert list(batch.subset(np.array([2, 0])).split) == ["b", "a"]
    one = ProbeBatch("a", batch.instance_id, batch.instance_index, batch.repeat, batch.truths, batch.u, batch.y)
    assert one.subset(np.array([1])).split == "a"  # a single run's batch is unchanged


def test_a_pooled_batchs_filter_streams_are_each_runs_own():
    from probecommit.runner.seeding import episode_rngs

    pooled = episode_rngs(7, ["B_cal_cover", "B_test_cover"], [3, 3], [1, 1], 0)
    alone = [episode_rngs(7, name, [3], [1], 0)[0] for name in ("B_cal_cover", "B_test_cover")]
    assert [g.random() for g in pooled] == [g.random() for g in alone]
