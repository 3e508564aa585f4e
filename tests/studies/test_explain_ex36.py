"""ex36's E208 (Table V's cover cells under the paper's schedule on Test C) and E209 (Table V's random k = 8 coverage
over E17's fresh draws): the keys by hand, Table V's own rules on them, the rerun's config, registration and verify's
recomputation from the stored rows."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path
from types import SimpleNamespace

import pandas as pd
import pytest

from probecommit.studies import claims
from probecommit.studies.explain import ex36_coverage as cov
from probecommit.studies.explain import ex36_testc as testc

from .recompute_contract import assert_bootstrapped_round_trip

BOOT = {"resamples": 50, "seed": 3}


def _rows(realized: dict[tuple[str, int], list[float]]) -> pd.DataFrame:
    """Stored rows of two instances x two repeats: ``realized[(model, k)]`` in (instance, repeat) order."""
    out = []
    for (model, k), values in realized.items():
        for i, value in enumerate(values):
            out.append({"instance_id": f"C-{i // 2}", "repeat": i % 2, "k": k, "method": "probe_robust",
                        "status": "ok", "predicted": 0.5, "realized": value, "covered": True, "escaped": False,
                        "model": model})
    return pd.DataFrame(out)


HAND = {("old", 1): [1.0, 1.0, 1.0, 0.0], ("corrected", 1): [1.0, 0.0, 1.0, 0.0],
        ("old", 5): [0.0, 1.0, 0.0, 0.0], ("corrected", 5): [0.0, 0.0, 0.0, 0.0]}


def test_cells_by_hand():
    keys = testc.keys(_rows(HAND), BOOT)
    assert keys["failure_cover_k1.old"][0] == 0.75 and keys["failure_cover_k1.corrected"][0] == 0.5
    assert keys["failure_cover_k1.old_minus_corrected"][0] == pytest.approx(0.25)
    assert keys["failure_cover_k5.old"][0] == 0.25 and keys["failure_cover_k5.corrected"] == [0.0, 0.0, 0.0]
    assert keys["failure_cover_k5.old_minus_corrected"][0] == pytest.approx(0.25)
    assert keys["trajectories"] == 4
    for name, v in keys.items():
        if isinstance(v, list):
            assert v[1] <= v[0] <= v[2], name
    assert keys == testc.keys(_rows(HAND), BOOT)  # same seed, same keys


def _values(k1_old, k1_corrected, k1_diff, k5_corrected) -> dict[str, list[float]]:
    return {"failure_cover_k1.old": k1_old, "failure_cover_k1.corrected": k1_corrected,
            "failure_cover_k1.old_minus_corrected": k1_diff, "failure_cover_k5.old": [0.3, 0.25, 0.35],
            "failure_cover_k5.corrected": k5_corrected, "failure_cover_k5.old_minus_corrected": [0.15, 0.1, 0.2]}


def test_outcomes_are_table_vs_own_rules_and_the_rule_needs_all_three_failing_labels():
    # paper: k = 1 old 0.721, corrected 0.703, paired +0.018 [-0.016, +0.052]; k = 5 old 0.326, corrected 0.159,
    # paired +0.167 [+0.091, +0.247]
    inside = _values([0.7, 0.65, 0.75], [0.7, 0.65, 0.75], [0.01, -0.02, 0.04], [0.15, 0.1, 0.2])
    out = testc.outcomes(inside)
    assert out["holds"] == 1 and out["passes.failing_count"] == 3 and out["passes.count"] == 6
    k1_low = testc.outcomes(_values([0.62, 0.55, 0.70], [0.7, 0.65, 0.75], [0.01, -0.02, 0.04], [0.15, 0.1, 0.2]))
    assert k1_low["passes.failure_cover_k1.old"] == 0 and k1_low["holds"] == 0 and k1_low["passes.failing_count"] == 2
    excludes = testc.outcomes(_values([0.7, 0.65, 0.75], [0.7, 0.65, 0.75], [0.04, 0.005, 0.07], [0.15, 0.1, 0.2]))
    assert excludes["passes.failure_cover_k1.old_minus_corrected"] == 0  # ours excludes zero, the paper's does not
    assert excludes["holds"] == 1  # the paired label is not one our schedule fails
    assert testc.outcomes(_values([0.7, 0.65, 0.75], [0.7, 0.65, 0.75], [0.01, -0.02, 0.04],
                                  [0.1, 0.05, 0.15]))["holds"] == 0


def test_the_rerun_is_test_cs_cover_run_with_only_the_schedule_changed(monkeypatch, tmp_path):
    from probecommit.studies.explain import runs
    from probecommit.studies.explain.study import COVER_SCHEDULE
    from probecommit.studies.protocol import load_protocol

    seen = {}
    monkeypatch.setattr(runs, "_run", lambda config, path, workers: seen.update(config=config, path=path)
                        or SimpleNamespace(path=path))
    monkeypatch.setattr(runs, "corrected_replay", lambda source, where, delta: seen.update(replay=(source, delta)))
    p = load_protocol()
    runs.testc_schedule_runs(p, COVER_SCHEDULE, Path(tmp_path), 1)
    ours = p.run_config("C_cover", "C", "C_cover", "cover")
    cfg = seen["config"]
    assert cfg.instances == ours.instances and cfg.seed == ours.seed and cfg.repeats == ours.repeats
    assert [float(u[0]) for u in cfg.probes.schedule] == COVER_SCHEDULE != [float(u[0]) for u in ours.probes.schedule]
    assert cfg.model_copy(update={"name": ours.name, "probes": ours.probes}) == ours
    assert seen["path"] == Path(tmp_path) / "C_cover_paper_schedule"
    assert seen["replay"] == (seen["path"], p.delta)


def test_the_step_stores_both_arms_and_publishes_their_keys(monkeypatch, tmp_path):
    old = _rows({k: v for k, v in HAND.items() if k[0] == "old"}).drop(columns="model")
    new = _rows({k: v for k, v in HAND.items() if k[0] == "corrected"}).drop(columns="model")
    monkeypatch.setattr("probecommit.studies.explain.runs.testc_schedule_runs",
                        lambda *a: (SimpleNamespace(episodes=old), SimpleNamespace(episodes=new)))
    monkeypatch.setattr("probecommit.runner.aside.in_own_process", lambda fn, *a: fn(*a))
    job = SimpleNamespace(p=None, runs=Path(tmp_path), workers=1, boot=BOOT, progress=lambda *a: None,
                          stored={}, res=defaultdict(dict))
    testc.run(job)
    rows = job.stored[testc.STORED]
    assert sorted(rows["model"].unique()) == ["corrected", "old"] and len(rows) == 16
    assert job.res[testc.GROUP] == testc.keys(_rows(HAND), BOOT)


def test_coverage_summary_by_hand():
    paper = cov.summary(pd.DataFrame({"draw": ["x"], "coverage_k1": [0.5], "coverage_k8": [0.5]}))
    p8, p1 = paper["k8.paper"], paper["k1.paper"]
    rows = pd.DataFrame({"draw": [cov.CHECK, "analytic_draw_00", "analytic_draw_01", "analytic_draw_02"],
                         "coverage_k1": [0.99, p1 - 0.01, p1, p1 + 0.02],
                         "coverage_k8": [0.9, p8 + 0.01, p8 + 0.03, p8 + 0.02]})
    keys = cov.summary(rows)
    assert keys["draws"] == 3 and keys["check.k8"] == 0.9 and keys["check.k1"] == 0.99
    assert keys["k8.min"] == pytest.approx(p8 + 0.01) and keys["k8.max"] == pytest.approx(p8 + 0.03)
    assert keys["k8.mean"] == pytest.approx(p8 + 0.02) and keys["k8.sd"] == pytest.approx(0.01)
    assert keys["k8.inside"] == 0 and keys["holds"] == 0  # the check row is not a fresh draw
    assert keys["k1.inside"] == 1  # its edge counts
    assert cov.summary(rows.assign(coverage_k8=[0.9, p8, p8 + 0.1, p8 - 0.1]))["holds"] == 1


def test_a_draws_row_counts_probe_robust_episodes_covered_at_each_budget():
    episodes = pd.DataFrame({"k": [1, 1, 1, 8, 8, 8], "method": ["probe_robust"] * 5 + ["blind_robust"],
                             "status": ["ok"] * 6, "covered": [True, False, True, False, False, True]})
    row = cov.draw_row("d", episodes)
    assert row == {"draw": "d", "episodes_k1": 3, "coverage_k1": pytest.approx(2 / 3), "episodes_k8": 2,
                   "coverage_k8": 0.0}


def test_registered_with_exact_covers_and_their_keys_exist():
    testc_claim = next(c for c in claims.CLAIMS if c.id == "tab:testc")
    explain = dict(claims.explanations(testc_claim))
    assert explain["E208"] == tuple(f"{claims.EXACT}{label}" for label in claims.TESTC_SCHEDULE_FAILING)
    assert explain["E209"] == (f"{claims.EXACT}episode_coverage_random_k8 old",)
    keys = {f"{claims.X}{testc.GROUP}.{k}" for k in testc.keys(_rows(HAND), BOOT)}
    e208 = {v.rsplit(".", 1)[0] if v.endswith((".1", ".2")) else v for v in claims.EXPERIMENTS["E208"].keys.values()}
    assert e208 <= keys
    rows = pd.DataFrame({"draw": [cov.CHECK, "analytic_draw_00", "analytic_draw_01"], "coverage_k1": [0.9, 0.9, 0.95],
                         "coverage_k8": [0.7, 0.7, 0.8]})
    beside = {f"{claims.I}table_testc.episode_coverage_random_k8.old", f"{claims.X}instance_generator.C_random.percentile"}
    assert set(claims.EXPERIMENTS["E209"].keys.values()) <= {f"{claims.X}{cov.GROUP}.{k}" for k in cov.summary(rows)} | beside
    e209, paper = claims.EXPERIMENTS["E209"].supports, cov.summary(rows)["k8.paper"]
    for lo, hi in ((paper, paper + 0.1), (paper - 0.1, paper), (paper + 1e-9, paper + 0.1)):
        assert e209({"lo": lo, "hi": hi}) == (lo <= paper <= hi)
    assert claims.EXPERIMENTS["E208"].supports({"h": 1.0}) and not claims.EXPERIMENTS["E208"].supports({"h": 0.0})


def test_verify_recomputes_both_groups_from_their_stored_rows(tmp_path):
    from probecommit.report import recompute

    rows = _rows(HAND)
    assert_bootstrapped_round_trip(tmp_path, testc, rows, testc.keys(rows, BOOT), BOOT)
    assert "ex36_testc" in recompute.BOOTSTRAPPED
    assert (cov.GROUP, cov.STORED, "ex36_coverage") in recompute.STORED_SUMMARIES
    draws = pd.DataFrame({"draw": [cov.CHECK, "analytic_draw_00", "analytic_draw_01"], "coverage_k1": [0.9, 0.9, 0.95],
                          "coverage_k8": [0.7, 0.7, 0.8], "episodes_k1": 4, "episodes_k8": 4})
    draws.to_parquet(tmp_path / cov.STORED)
    out = recompute.Recomputed()
    recompute._stored_summaries(tmp_path, {cov.GROUP: cov.summary(draws)}, out)
    assert {k: v for k, v in out.values.items() if k.startswith(cov.GROUP + ".")} \
        == {f"{cov.GROUP}.{k}": v for k, v in cov.summary(draws).items()}
