"""Verify recomputes the explain target's summaries from its stored rows: single edits to a scratch
publication that includes explain (each re-hashed like an attacker would) fail, naming file and number."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Callable

import pandas as pd
import pytest

from probecommit.report.verify import verify

from .test_verify_tamper import Edit, bump, edit_results, paper_root, rehash

pytestmark = pytest.mark.slow


@pytest.fixture
def pub(explain_publication, tmp_path) -> Path:
    shutil.copytree(explain_publication, tmp_path / "pub")
    return tmp_path / "pub"


def edit_stored(name: str, where: Callable[[pd.DataFrame], pd.Series], column: str, value, key: str) -> Edit:
    """One stored explain row changed (the first ``where`` selects); verify must name the file and ``key``."""
    def edit(pub: Path) -> list[str]:
        f = paper_root(pub) / "explain" / name
        table = pd.read_parquet(f)
        row = table.index[where(table)][0]
        table.loc[row, column] = value(table.loc[row, column]) if callable(value) else value
        table.to_parquet(f, index=False)
        return [name, key]
    return edit


def first(t: pd.DataFrame) -> pd.Series:
    return pd.Series(t.index == t.index[0], index=t.index)


def delete_stored(name: str) -> Edit:
    def edit(pub: Path) -> list[str]:
        (paper_root(pub) / "explain" / name).unlink()
        return [f"explain/{name}", "missing"]
    return edit


CASES: list[tuple[str, Edit]] = [
    ("stored-margin-curve-cell", edit_stored("margin_per_gamma.parquet", first, "mean_realized", bump,
                                             "margin_per_gamma.ours.g1.00.realized")),
    ("stored-fresh-draw", edit_stored("fresh_draws.parquet", lambda t: t.index == 1, "failure_k8", bump,
                                      "instance_generator.draws.failure_k8.mean")),
    ("stored-draw-cell-check", edit_stored("draw_cells.parquet", lambda t: (t.part == "audit") & (t.draw == 0), "value",
                                           bump, "instance_generator.draws.audit_check.")),
    ("stored-draw-cell-fresh", edit_stored("draw_cells.parquet", lambda t: (t.part == "faults") & (t.draw == 1), "value",
                                           bump, "instance_generator.draws.faults.")),
    ("stored-schedule-row", edit_stored("schedule_episodes.parquet", lambda t: t.run == "paper_A", "realized",
                                        lambda v: 1.0 - v, "committed_pool.schedule.A.paper_schedule.failure_k5")),
    ("stored-schedule-trajectory", edit_stored("schedule_episodes.parquet", lambda t: (t.run == "ours_B_test") & (t.k == 5),
                                               "z_true", lambda v: 9.9 if abs(v) <= 7 else 0.0,
                                               "instance_generator.stratified.B_test_cover.k5.share_beyond")),
    ("stored-prior-sweep-row", edit_stored("breadth_prior_episodes.parquet", lambda t: t.method == "blind_bayes",
                                           "realized", bump, "breadth_prior.push1d.s0.5.blind_bayes")),
    ("stored-mixture-seed", edit_stored("mixture_noise_seeds.parquet", first, "mixed", bump,
                                        "mixture_noise.mixture.failure.mean")),
    ("stored-rig-session-row", edit_stored("rig_redraws_sessions.parquet", lambda t: t.k == t.k.max(), "realized",
                                           lambda v: 1.0 - v, "rig_redraws.optimism.pooled_optimism.k")),
    ("stored-rig-boundary-row", edit_stored("rig_redraws_boundary.parquet", first, "holds_to_mm", lambda v: v + 1.0,
                                            "rig_redraws.boundary.coverage_holds_to_mm")),
    ("stored-pybullet-draw", edit_stored("pybullet_draws.parquet", first, "escape_k8", bump,
                                         "pybullet_escape.draws.escape_k8.")),
    ("stored-ex7-dev-draw", edit_stored("ex7_dev_draws.parquet", first, "failure", bump,
                                        "ex7_robust.dev_draws.mixture.eps_")),
    ("stored-ex7-harness-draw", edit_stored("ex7_harness_draws.parquet", first, "mixed", bump,
                                            "ex7_robust.harness_draws.mixture.paired_cost")),
    ("stored-ex7-surprise-row", edit_stored("ex7_fault_surprise.parquet", first, "escaped", lambda v: not v,
                                            "ex7_faults.surprise.")),
    ("json-ex7-signature", edit_results("explain", ["ex7_faults", "signature.particles.optimism_change"],
                                        lambda v: [v[0] + 0.0123, *v[1:]])),
    ("json-pybullet-stored-escape", edit_results("explain", ["pybullet_escape", "stored.escape_k8"],
                                                 lambda v: [v[0] + 0.0123, *v[1:]])),
    ("json-margin-cell", edit_results("explain", ["margin_per_gamma", "ours.g0.98.predicted"], bump)),
    ("json-draws-sd", edit_results("explain", ["instance_generator", "draws.escape_k8.max"], bump)),
    ("json-boundary-fix", edit_results("explain", ["boundary_fault", "harness.paired_fix"],
                                       lambda v: [v[0] + 0.0123, *v[1:]])),
    ("json-whole-cluster-escape", edit_results("explain", ["missing", "all_repeats_escape.boundary.k8.clusters_all"], bump)),
    ("json-pool-count", edit_results("explain", ["committed_pool", "ours.final_hull.escaped_committed"], lambda n: n + 1)),
    ("json-prior-span", edit_results("explain", ["breadth_prior", "push1d.span.blind_bayes.lo"], bump)),
    ("json-physx-coverage", edit_results("explain", ["missing", "physx_episode_coverage.deployed"], lambda v: v - 0.01)),
    ("json-cost-of-calibration", edit_results("explain", ["missing", "cost_of_calibration.set"],
                                              lambda v: [v[0] + 0.0123, *v[1:]])),
    ("deleted-draw-cells-rehashed", delete_stored("draw_cells.parquet")),
    ("deleted-schedules-rehashed", delete_stored("schedule_episodes.parquet")),
]


def test_the_explain_publication_verifies_and_recomputes_explain(explain_publication):
    report = verify(explain_publication, figures=False)
    assert report.ok, report.failures[:5]
    assert report.counts["recomputed"] > 1000, report.counts


@pytest.mark.parametrize("name,edit", CASES, ids=[c[0] for c in CASES])
def test_an_edit_to_explain_fails_verify_naming_file_and_number(pub, name, edit):
    expected = edit(pub)
    rehash(pub)
    failures = verify(pub, figures=False).failures
    assert failures, f"{name}: verify passed"
    assert any(all(part in f for part in expected) for f in failures), (name, expected, failures[:6])
