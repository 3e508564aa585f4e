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
