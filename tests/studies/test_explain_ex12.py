"""ex12's explain experiment (E100): first-distinct re-indexing, the cells and the summary on hand cases, and the
claims' joint ``supports`` rule deciding on hand values (it can fail)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from probecommit.studies import claims
from probecommit.studies.explain import ex12_distinct as ex12
from probecommit.studies.paper_values import value


def _episode(instance: str, repeat: int, taps: list[float], covered: list[bool], predicted: list[float],
             realized: list[float]) -> tuple[list[dict], list[dict]]:
    eps = [{"instance_id": instance, "repeat": repeat, "k": j + 1, "covered": c, "predicted": p, "realized": r}
           for j, (c, p, r) in enumerate(zip(covered, predicted, realized))]
    probes = [{"instance_id": instance, "repeat": repeat, "j": j + 1, "u": u} for j, u in enumerate(taps)]
    return eps, probes


def test_distinct_rows_read_the_tap_where_each_new_position_first_appears():
    # taps 0, 0, 3, 0, 6: distinct positions appear at taps 1, 3, 5
    eps, probes = _episode("a", 0, [0.0, 0.0, 3.0, 0.0, 6.0], [True] * 5, [0.1, 0.2, 0.3, 0.4, 0.5], [0, 0, 1, 1, 0])
    rows = ex12.distinct_rows(pd.DataFrame(eps), pd.DataFrame(probes), budgets=(1, 2, 3, 5))
    assert rows["k"].tolist() == [1, 2, 3]  # never reaches 5 distinct: no row at 5
    assert rows["tap"].tolist() == [1, 3, 5]
    assert rows["predicted"].tolist() == [0.1, 0.3, 0.5]


def test_cells_count_only_clusters_with_every_repeat_and_take_optimism_over_them():
    eps, probes = [], []
    # instance a: both repeats reach 2 distinct; b: repeat 1 repeats one position (no k = 2 row)
    for inst, rep, taps, cov, pred, real in (("a", 0, [0, 3], [True, True], [0.2, 0.1], [0, 1]),
                                             ("a", 1, [3, 0], [True, False], [0.2, 0.3], [0, 0]),
                                             ("b", 0, [0, 6], [True, True], [0.5, 0.5], [1, 1]),
                                             ("b", 1, [6, 6], [True, True], [0.5, 0.5], [1, 1])):
        e, p = _episode(inst, rep, [float(u) for u in taps], cov, pred, real)
        eps += e
        probes += p
    rows = ex12.distinct_rows(pd.DataFrame(eps), pd.DataFrame(probes), budgets=(1, 2))
    got = ex12.cells(rows, repeats=2).set_index("k")
    assert got.loc[1, "clusters"] == 2 and got.loc[1, "cluster_coverage"] == 1.0
    assert math.isclose(got.loc[1, "optimism"], 0.5 - 0.35)  # realized 0,0,1,1; predicted .2,.2,.5,.5
    assert got.loc[2, "clusters"] == 1  # only a
    assert got.loc[2, "cluster_coverage"] == 0.0  # a's repeat 1 misses at k = 2
    assert math.isclose(got.loc[2, "optimism"], 0.5 - 0.2)


def test_summary_ranges_over_fresh_draws_keeps_the_frozen_draw_apart_and_nulls_thin_draws():
    def draw(name: str, covered: bool, n: int) -> pd.DataFrame:
        return pd.DataFrame({"draw": name, "instance_id": [f"i{j}" for j in range(n)], "repeat": 0, "k": 1, "tap": 1,
                             "covered": covered, "predicted": 0.1, "realized": 0.0})
    stored = pd.concat([draw("d0", True, 3), draw("d1", False, 3), draw(ex12.FROZEN, True, 3)], ignore_index=True)
    got = ex12.summary(stored, budgets=(1,), min_clusters=3)
    assert got["draws"] == 2 and got["clusters.k1.min"] == 3
    assert (got["cluster_coverage.k1.min"], got["cluster_coverage.k1.max"], got["cluster_coverage.k1.mean"]) == (0, 1, 0.5)
    assert got["cluster_coverage.k1.frozen"] == 1.0
    assert math.isclose(got["optimism.k1.min"], -0.1)
    thin = ex12.summary(stored, budgets=(1,), min_clusters=4)
    assert np.isnan(thin["cluster_coverage.k1.min"]) and thin["cluster_coverage.k1.frozen"] == 1.0


def test_the_joint_rule_needs_every_original_cell_in_range():
    exp = claims.EXPERIMENTS["E100[optimism original k=3]"]
    v = {"c": 49, "lo": 0.0, "hi": 1.0, "m": 0.5, "f": 0.5, "n": 12}
    for k in claims.EX12_BUDGETS:
        for m in ("cluster_coverage", "optimism"):
            p = value(f"tab:audit.{m}_original.{k}")
            v[f"{m}{k}lo"], v[f"{m}{k}hi"] = p - 0.01, p + 0.01
    assert exp.supports(v)
    assert not exp.supports({**v, "optimism1hi": value("tab:audit.optimism_original.1") - 0.001})  # k = 1 out
    assert not exp.supports({**v, "c": claims.EX12_MIN_CLUSTERS - 1})
    assert not exp.supports({**v, "hi": value("tab:audit.optimism_original.3") - 0.001})
    assert claims.EX12_MIN_CLUSTERS == ex12.MIN_CLUSTERS and tuple(claims.EX12_BUDGETS) == ex12.BUDGETS


# ----------------------------------------------------------------------------- E101
from probecommit.studies.explain import ex12_simultaneous as ex12s  # noqa: E402


def test_split_row_takes_the_simultaneous_level_over_budgets_and_covers_at_the_last():
    # 5 calibration clusters, alpha = 0.2: q = ceil(0.8 * 6) = 5, the largest score
    ids = [f"c{j}" for j in range(5)] + ["t0", "t1"]
    table = pd.DataFrame({1: [0.1, 0.2, 0.3, 0.4, 1.2, 0.1, 0.1], 2: [0.3, 0.1, 0.2, 0.5, 0.6, 0.9, 0.55]},
                         index=ids)
    got = ex12s.split_row(table, np.array(ids[:5]), np.array(["t0", "t1"]), 0.2, 2)
    assert got == {"level": 1.2, "coverage": 1.0, "level_fixed": 0.6, "coverage_fixed": 0.5}


def test_summary_per_pool_means_and_sd():
    rows = pd.DataFrame({"pool": ["a", "a", "b"], "index": [0, 1, 0], "level": [1.0, 0.5, 0.9],
                         "coverage": [0.8, 0.9, 0.7], "level_fixed": [0.4, 0.6, 0.3], "coverage_fixed": [0.8, 0.8, 0.6]})
    got = ex12s.summary(rows)
    assert got["a.splits"] == 2 and got["a.level.mean"] == 0.75 and math.isclose(got["a.level.sd"], 0.5 ** 0.5 / 2)
    assert math.isclose(got["a.coverage.mean"], 0.85) and got["a.level_fixed.mean"] == 0.5
    assert got["b.splits"] == 1 and np.isnan(got["b.level.sd"])


def test_e101_needs_both_the_coverage_and_the_level_of_the_same_reading():
    exp = claims.EXPERIMENTS["E101"]
    v = {"lv": value("T14-resplits.level_mean"), "lsd": 0.2, "cv": value("T14-resplits.heldout_cluster_coverage"),
         "n": 50, "lf": 0.6, "cf": 0.8}
    assert exp.supports(v)
    assert not exp.supports({**v, "lv": 1.011})  # a level that does not vary as the paper's does
    assert not exp.supports({**v, "cv": 0.918})
