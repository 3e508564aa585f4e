"""ex35's E205 (T14's re-split statistics over 12 fresh pools): the keys by hand, the step's join of E56's stored
rows with the pools it runs, the rule at its edges, registration, and verify's recomputation from the stored rows."""

from __future__ import annotations

import math
from collections import defaultdict
from pathlib import Path
from types import SimpleNamespace

import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex5_calibration as ex5
from probecommit.studies.explain import ex35_pools as ex35

LABELS = {"level mean": "level_mean", "held-out cluster coverage": "heldout_cluster_coverage",
          "margin optimistic": "margin_optimistic_fraction"}


def _rows(**stats: list[float]) -> pd.DataFrame:
    n = len(next(iter(stats.values())))
    full = {s: stats.get(s, [0.5] * n) for s in ex5.POOL_STATS}
    return pd.DataFrame({"part": "fresh_pool", "index": list(range(n)), **full, "splits": 50.0})


def test_summary_by_hand():
    paper = {s: ex35.paper_fraction(s) for s in ex35.TESTED}
    margin = paper["margin_optimistic_fraction"]
    rows = _rows(level_mean=[0.6, 0.7, 0.9, 0.8], heldout_cluster_coverage=[0.80, 0.81, 0.79, 0.80],
                 margin_optimistic_fraction=[margin - 0.1, margin, margin + 0.02, margin - 0.2])
    keys = ex35.summary(rows)
    assert keys["pools"] == 4 and keys["prediction_level"] == pytest.approx(3 / 5)
    assert keys["level_mean.min"] == 0.6 and keys["level_mean.max"] == 0.9 and keys["level_mean.mean"] == pytest.approx(0.75)
    assert keys["level_mean.sd"] == pytest.approx(math.sqrt(((0.15 ** 2) + 0.05 ** 2 * 2 + 0.15 ** 2) / 3))
    assert keys["margin_optimistic_fraction.at_least_paper"] == 2  # the paper's value itself counts
    assert keys["margin_optimistic_fraction.holds"] == 1
    assert keys["level_mean.holds"] == int(0.6 <= paper["level_mean"] <= 0.9)
    assert keys["heldout_cluster_coverage.holds"] == int(0.79 <= paper["heldout_cluster_coverage"] <= 0.81)
    assert {k: v for k, v in keys.items() if k.split(".")[-1] in ("min", "max", "mean") or k == "pools"} \
        == ex5.pool_keys(rows)  # E56's keys, computed by E56's function


def test_paper_fraction_reads_the_margin_as_a_fraction():
    from probecommit.studies.paper_values import value

    assert ex35.paper_fraction("margin_optimistic_fraction") == pytest.approx(
        value("T14-resplits.margin_optimistic_percent") / 100)
    assert ex35.paper_fraction("level_mean") == value("T14-resplits.level_mean")


def test_the_step_joins_e56s_stored_rows_before_the_pools_it_runs(monkeypatch, tmp_path):
    e56 = _rows(level_mean=[0.7, 0.8, 0.9])
    stored = pd.concat([pd.DataFrame({"part": ["resplit_cost"], "index": [0], "difference": [0.1]}), e56],
                       ignore_index=True)
    ran: list[tuple[int, int]] = []

    def fake(protocol, schedule, runs, count, workers, first=0):
        ran.append((first, count))
        return _rows(level_mean=[0.1 * i for i in range(first, count)]).assign(index=list(range(first, count)))

    monkeypatch.setattr("probecommit.runner.aside.in_own_process", lambda fn, *a: fn(*a))
    monkeypatch.setattr(ex5, "fresh_pool_rows", fake)
    job = SimpleNamespace(stored={ex5.STORED: stored}, p=None, runs=Path(tmp_path), workers=1, quick=False,
                          cfg={"ex35_pools": 5, "ex35_pools_quick": 0}, progress=lambda *a: None,
                          res=defaultdict(dict))
    ex35.run(job)
    rows = job.stored[ex35.STORED]
    assert ran == [(3, 4), (4, 5)]  # one pool a process, after E56's three
    assert rows["index"].tolist() == [0, 1, 2, 3, 4]
    assert rows["level_mean"].tolist() == pytest.approx([0.7, 0.8, 0.9, 0.3, 0.4])
    assert job.res[ex35.GROUP] == ex35.summary(rows)
    alone = SimpleNamespace(**{**vars(job), "res": defaultdict(dict), "stored": {}})  # no E56 rows: all run here
    ran.clear()
    ex35.run(alone)
    assert ran == [(0, 1), (1, 2), (2, 3), (3, 4), (4, 5)]
    assert alone.stored[ex35.STORED]["index"].tolist() == [0, 1, 2, 3, 4]
    quick = SimpleNamespace(**{**vars(job), "quick": True, "res": defaultdict(dict), "stored": {}})
    ex35.run(quick)
    assert not quick.res and not quick.stored  # none in a quick run


def test_e205_rule_is_e56s_at_its_edges():
    for label, stat in LABELS.items():
        paper = ex35.paper_fraction(stat)
        e205, e56 = claims.EXPERIMENTS[f"E205[{label}]"].supports, claims.EXPERIMENTS[f"E56[{label}]"].supports
        for lo, hi in ((paper, paper + 0.1), (paper - 0.1, paper), (paper + 1e-9, paper + 0.1), (paper - 0.1, paper - 1e-9)):
            assert e205({"lo": lo, "hi": hi}) == e56({"lo": lo, "hi": hi}) == (lo <= paper <= hi)


def test_e205_is_registered_for_each_t14_label_and_its_keys_exist():
    t14 = next(c for c in claims.CLAIMS if c.id == "T14-resplits")
    rows = _rows(level_mean=[0.7, 0.8], margin_optimistic_fraction=[0.4, 0.7])
    keys = {f"{claims.X}{ex35.GROUP}.{k}" for k in ex35.summary(rows)}
    for label in LABELS:
        assert (f"E205[{label}]", (label,)) in claims.explanations(t14)
        assert set(claims.EXPERIMENTS[f"E205[{label}]"].keys.values()) <= keys


def test_verify_recomputes_the_group_from_its_stored_rows(tmp_path):
    from probecommit.report import recompute

    assert (ex35.GROUP, ex35.STORED, "ex35_pools") in recompute.STORED_SUMMARIES
    rows = _rows(level_mean=[0.7, 0.8, 0.75], margin_optimistic_fraction=[0.4, 0.7, 0.5])
    rows.to_parquet(tmp_path / ex35.STORED)
    out = recompute.Recomputed()
    recompute._stored_summaries(tmp_path, {ex35.GROUP: ex35.summary(rows)}, out)
    assert {k: v for k, v in out.values.items() if k.startswith(ex35.GROUP + ".")} \
        == {f"{ex35.GROUP}.{k}": v for k, v in ex35.summary(rows).items()}
