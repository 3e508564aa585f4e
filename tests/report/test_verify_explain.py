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


def flip_rule(pub: Path) -> list[str]:
    """The margin rule's sums at gamma = 1 moved across each other (the first stored curve row): gamma moves."""
    f = paper_root(pub) / "explain" / "margin_per_gamma.parquet"
    table = pd.read_parquet(f)
    realized = float(table.loc[0, "sum_realized"])
    passes = float(table.loc[0, "sum_predicted"]) >= realized - 1e-9
    table.loc[0, "sum_predicted"] = realized - 1.0 if passes else realized + 1.0
    table.to_parquet(f, index=False)
    return ["margin_per_gamma.parquet", "margin_per_gamma.ours.gamma"]


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
    ("stored-ex5-resplit-cost", edit_stored("ex5_calibration_rows.parquet", lambda t: t.part == "resplit_cost",
                                            "difference", bump, "ex5_calibration.resplit_cost.estimate.mean")),
    ("stored-ex5-capture-pair", edit_stored("ex5_calibration_rows.parquet", lambda t: t.part == "capture",
                                            "optimism.original.k2", bump, "ex5_calibration.capture.")),
    ("stored-ex9-cost-split", edit_stored("ex9_calibration_rows.parquet", lambda t: t.part == "cost", "difference", bump,
                                          "ex9_calibration.cost.estimate.mean")),
    ("stored-ex9-coverage-split", edit_stored("ex9_calibration_rows.parquet", lambda t: t.part == "coverage", "le",
                                              bump, "ex9_calibration.coverage.le.")),
    ("stored-ex7-dev-draw", edit_stored("ex7_dev_draws.parquet", first, "failure", bump,
                                        "ex7_robust.dev_draws.mixture.eps_")),
    ("stored-ex7-harness-draw", edit_stored("ex7_harness_draws.parquet", first, "mixed", bump,
                                            "ex7_robust.harness_draws.mixture.paired_cost")),
    ("stored-ex7-surprise-row", edit_stored("ex7_fault_surprise.parquet", first, "escaped", lambda v: not v,
                                            "ex7_faults.surprise.")),
    ("stored-ex8-blind-episode", edit_stored("ex8_blind_episodes.parquet", lambda t: t.method == "blind_bayes",
                                             "realized", bump, "ex8_blind.")),
    ("stored-ex8-pybullet-reading", edit_stored("ex8_pybullet_readings.parquet", first, "y_0_pybullet",
                                                lambda v: v + 0.5, "ex8_pybullet.")),
    ("stored-ex8-grasp-row", edit_stored("ex8_grasp_rows.parquet",
                                         lambda t: (t.method == "probe_robust") & (t.k == 8) & t.feasible,
                                         "realized", lambda v: 1.0 - v, "ex8_grasp.")),
    ("stored-ex10-boundary-row", edit_stored("ex10_boundary_noise.parquet",
                                             lambda t: (t.variant == "deployed") & (t.s == t.s.max()) & (t.k == t.k.max()),
                                             "escaped", lambda v: not v, "ex10_boundary.deployed.s12.escape_k")),
    ("stored-ex11-pool-episode", edit_stored("ex11_probe_rows.parquet", lambda t: t.part == "pool", "realized", bump,
                                             "ex11_probe.")),
    ("stored-ex16-reach-episode", edit_stored("ex16_reach_rows.parquet", lambda t: t.part == "reach", "realized", bump,
                                              "ex16_reach.")),
    ("stored-ex19-darts-episode", edit_stored("ex19_darts_rows.parquet", lambda t: t.method == "blind_bayes", "realized",
                                              bump, "ex19_darts.")),
    ("stored-ex19-widths-episode", edit_stored("ex19_widths_rows.parquet", lambda t: t.method == "blind_bayes",
                                               "realized", bump, "ex19_widths.")),
    ("stored-ex19-cone-miss", edit_stored("ex19_cone_rows.parquet", lambda t: (t.kind == "miss") & (t.cone == "pyramidal"),
                                          "realized", bump, "ex19_cone.")),
    ("stored-ex22-exact-episode", edit_stored("ex22_exact_rows.parquet", lambda t: t.part == "exact", "realized", bump,
                                              "ex22_exact.")),
    ("stored-ex22-magnitude-episode", edit_stored("ex22_magnitude_rows.parquet", lambda t: t.part == "c150", "realized",
                                                  bump, "ex22_magnitude.")),
    ("stored-ex25-uniform-episode", edit_stored("ex25_uniform_rows.parquet", lambda t: t.part == "interval", "realized",
                                                bump, "ex25_uniform.")),
    ("stored-ex27-torque-episode", edit_stored("ex27_torque_rows.parquet", lambda t: t.part == "d025", "realized",
                                               bump, "ex27_torque.")),
    ("stored-ex32-floor-episode", edit_stored("ex32_floor_rows.parquet", lambda t: t.k == 5, "realized", bump,
                                              "ex32_floor.")),
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
    ("stored-margin-rule-sum", flip_rule),
    ("stored-calibration-score", edit_stored("margin_instances.parquet", lambda t: t.schedule == "ours", "score_k5",
                                             lambda v: 0.5 if v > 1.0 else 1.5,
                                             "thresholds.ours.share_scores_final_escaped")),
    ("stored-calibration-escape", edit_stored("margin_instances.parquet", lambda t: t.schedule == "paper_schedule",
                                              "escaped_final", lambda n: n + 1,
                                              "margin_per_gamma.paper_schedule.escaped_share_cal")),
    ("stored-margin-instance-sum", edit_stored("margin_instance_sums.parquet", lambda t: t.schedule == "ours",
                                               "sum_predicted", lambda v: v + 1e6, "margin_per_gamma.ours.gamma_")),
    ("stored-random-gate-commit", edit_stored("commits.parquet", lambda t: (t.calibration == "gates_random")
                                              & (t.request == "adjusted"), "predicted", lambda v: 1.0 - v,
                                              "random")),
    ("stored-paper-schedule-commit", edit_stored("commits.parquet", lambda t: (t.calibration == "paper_schedule")
                                                 & (t.request == "set_margin") & (t.k == 5), "realized",
                                                 lambda v: 1.0 - v,
                                                 "committed_pool.schedule.B_test.paper_schedule.cost_table."
                                                 "set_calibration_margin")),
    ("stored-paper-schedule-test-row", edit_stored("episodes.parquet", lambda t: (t.run == "paper_B_test") & (t.k == 5),
                                                   "realized", lambda v: 1.0 - v, "cost_table.no_calibration")),
    ("stored-corrected-calibration-score", edit_stored("episodes.parquet", lambda t: t.run == "B_cal_random_corrected",
                                                       "score_s", lambda v: 50.0,
                                                       "missing.simultaneous_threshold_random_corrected")),
    ("stored-emulated-physx-row", edit_stored("physx_emulated_episodes.parquet", first, "escaped", lambda v: not v,
                                              "physx_capture.emulated.deployed.escape")),
    ("stored-mixture-replay-row", edit_stored("robust_replays.parquet", lambda t: t.part == "right_base", "realized",
                                              lambda v: 1.0 - v, "robust.right_model.failure")),
    ("stored-resplit-row", edit_stored("resplits_paper_schedule.parquet", first, "level", bump,
                                       "committed_pool.resplits.paper_schedule.level_mean")),
    ("stored-surprise-reading", edit_stored("surprise_variants.parquet", lambda t: t.schedule == "paper_schedule",
                                            "density_k1", lambda v: 1e9,
                                            "missing.surprise_variants.paper_schedule.density.final_retained.k1")),
    ("stored-cover-search-row", edit_stored("cover_search_episodes.parquet", first, "aim_error", lambda v: v + 100.0,
                                            "aim_error")),  # the insertion study's candidate no longer follows
    ("stored-cover-search-instance", edit_stored("cover_search_episodes.parquet", first, "instance_id", "another",
                                                 "searches.cover.instances")),
    ("stored-generator-seed", edit_stored("generator_instances.parquet", first, "seed", lambda s: s + 1,
                                          "generator_instances.parquet")),
    ("stored-grasp-feasibility", edit_stored("grasp_analytic_episodes.parquet", lambda t: t.feasible, "feasible",
                                             False, "grasp_signs.analytic.n_feasible")),
    ("json-margin-gamma", edit_results("explain", ["margin_per_gamma", "ours.gamma_interval"],
                                       lambda v: [v[0], v[1] - 0.02, v[2]])),
    ("json-threshold-interval", edit_results("explain", ["thresholds", "ours.t_5_interval"],
                                             lambda v: [v[0] + 0.0123, *v[1:]])),
    ("json-random-gate-area", edit_results("explain", ["missing", "gate_area_random.raw"], bump)),
    ("json-paper-schedule-cost", edit_results("explain", ["missing", "cost_of_calibration_paper_schedule.full"],
                                              lambda v: [v[0] + 0.0123, *v[1:]])),
    ("json-generator-redraw", edit_results("explain", ["instance_generator", "B_test_random.redraw_sd"], bump)),
    ("json-gru-se-ratio", edit_results("explain", ["gru", "se_ratio"], bump)),
    ("json-engines-x-capture", edit_results("explain", ["engines_x", "pybullet_capture.ours"], bump)),
    ("json-robust-search", edit_results("explain", ["searches", "robust.mixture.share_paper"], bump)),
    ("stored-emulated-pybullet-reading", edit_stored("pybullet_emulated_episodes.parquet", lambda t: t.part == "unit_probe",
                                                     "y", lambda v: v + 1.0, "pybullet_escape.capture_moves_readings")),
    ("deleted-calibration-rows-rehashed", delete_stored("margin_instances.parquet")),
    ("deleted-explain-commits-rehashed", delete_stored("commits.parquet")),
    ("deleted-draw-cells-rehashed", delete_stored("draw_cells.parquet")),
    ("deleted-schedules-rehashed", delete_stored("schedule_episodes.parquet")),
    ("deleted-ex11-rows-rehashed", delete_stored("ex11_probe_rows.parquet")),
    ("deleted-ex16-rows-rehashed", delete_stored("ex16_reach_rows.parquet")),
    ("deleted-ex19-cone-rows-rehashed", delete_stored("ex19_cone_rows.parquet")),
    ("deleted-ex22-exact-rows-rehashed", delete_stored("ex22_exact_rows.parquet")),
    ("deleted-ex25-uniform-rows-rehashed", delete_stored("ex25_uniform_rows.parquet")),
    ("deleted-ex27-torque-rows-rehashed", delete_stored("ex27_torque_rows.parquet")),
]


#: The cases in two xdist groups, one per worker of ``make test``: both read the one build of the publication
#: (``conftest.built_once``), so the slowest stretch of the suite is halved instead of run on one worker.
HALVES = [pytest.mark.xdist_group(f"explain_publication_{half}") for half in (0, 1)]


@HALVES[0]
def test_the_explain_publication_verifies_and_recomputes_explain(explain_publication):
    report = verify(explain_publication, figures=False)
    assert report.ok, report.failures[:5]
    assert report.counts["recomputed"] > 1000, report.counts
    # Every explain key but the retrained seed's parameters (training), the paper's PyBullet values and two engine
    # measurements copied beside the rows (ex6's scene boundary, the cone premise) is recomputed; no traced number
    # anywhere in the publication is a summary of rows it does not store.
    explain = [n for n in report.notes if n.startswith("explain/results.json")]
    allowed = ("training: gru.", "paper value: pybullet_escape.", "measured: ex6_probe_rule.boundary_offset",
               "measured: ex4_cone.premise_max_probe_difference_m")
    assert all(any(a in n for a in allowed) for n in explain), explain
    assert report.traced_only_kinds["not stored"] == 0, [n for n in report.notes if "not stored" in n]


@pytest.mark.parametrize("name,edit", [pytest.param(name, edit, id=name, marks=HALVES[i % 2])
                                       for i, (name, edit) in enumerate(CASES)])
def test_an_edit_to_explain_fails_verify_naming_file_and_number(pub, name, edit):
    expected = edit(pub)
    rehash(pub)
    failures = verify(pub, figures=False).failures
    assert failures, f"{name}: verify passed"
    assert any(all(part in f for part in expected) for f in failures), (name, expected, failures[:6])
