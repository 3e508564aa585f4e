"""The insertion study's parts: instance sets, scan, faults, robust filters, reproduce --quick."""

import json

import numpy as np
import pandas as pd
import pytest

from probecommit.runner.instances import draw_instances
from probecommit.tasks.insertion.model import InsertionModel
from probecommit.runner.replay import load_run, replay_episodes
from probecommit.runner.study import run_study
from probecommit.studies.cover_search import candidate_schedules
from probecommit.studies.faults import Arm, fault_arms, run_fault_harness
from probecommit.studies.protocol import load_protocol
from probecommit.studies.scan import boundary_scan
from probecommit.tasks.insertion.model import InsertionModel
from probecommit.tasks.insertion.sim_base import AnalyticInsertionSimulator

SETS = [("development", "development"), ("A", "A"), ("B", "B_cal_cover"), ("B", "B_test_cover"),
        ("B", "B_cal_random"), ("B", "B_test_random"), ("C", "C_cover"), ("C", "C_random")]


def all_sets(protocol):
    return {split: draw_instances(protocol.run_config(split, name, split, "random"), InsertionModel()) for name, split in SETS}


def test_instance_sets_are_disjoint_reproducible_and_in_the_prior_box():
    p = load_protocol()
    a, b = all_sets(p), all_sets(p)
    truths = []
    for split, table in a.items():
        pd.testing.assert_frame_equal(table, b[split])
        assert table["true_x_hole"].between(-10, 10).all() and table["true_c"].between(0.7, 1.3).all()
        truths.append(table[["true_x_hole", "true_c"]].to_numpy())
    stacked = np.concatenate(truths)
    assert len(np.unique(stacked, axis=0)) == len(stacked)
    assert len(a["development"]) == 24 and len(a["A"]) == 96 and len(a["C_cover"]) == 96


def test_split_a_is_a_latin_hypercube():
    p = load_protocol()
    table = all_sets(p)["A"]
    for col, lo, hi in (("true_x_hole", -10, 10), ("true_c", 0.7, 1.3)):
        strata = np.floor((table[col] - lo) / (hi - lo) * 96).astype(int)
        assert sorted(strata) == list(range(96))


def test_test_c_uses_its_own_seed_stream():
    p = load_protocol()
    c = p.instances["C"].seed
    assert c not in {p.instances[n].seed for n in ("development", "A", "B")}


@pytest.mark.parametrize("planted", [0.6, -0.3, 0.905])
def test_scan_recovers_a_planted_boundary(planted):
    p = load_protocol()
    inst = draw_instances(p.run_config("d", "development", "development", "random"), InsertionModel()).head(5)
    sim = AnalyticInsertionSimulator(boundary_offset=planted)
    result = boundary_scan(sim, inst, step=0.25, half_range=7.0, tolerance=1e-3)
    assert len(result.scans) == 10
    assert np.all(np.abs(result.scans["offset"] - planted) <= 1e-3)
    assert abs(result.delta - planted) <= 1e-3


def test_scan_reports_a_pocket_that_never_closes():
    sim = AnalyticInsertionSimulator(boundary_offset=5.0)  # hg + 5 > 7 mm
    inst = pd.DataFrame({"instance_id": ["x"], "true_x_hole": [0.0], "true_c": [1.0]})
    with pytest.raises(RuntimeError, match="edge"):
        boundary_scan(sim, inst, step=0.25, half_range=7.0)


@pytest.mark.mujoco
def test_scan_with_engine_threads_equals_one_by_one(monkeypatch):
    """A MuJoCo scan runs its grid taps in engine threads first: same scans, same engine calls."""
    from probecommit.tasks.insertion.sim_mujoco import MujocoInsertionSimulator

    p = load_protocol()
    inst = draw_instances(p.run_config("d", "development", "development", "random"), InsertionModel()).head(2)
    results = {}
    for threads in ("1", "2"):
        monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", threads)
        sim = MujocoInsertionSimulator()
        results[threads] = boundary_scan(sim, inst, step=0.5, half_range=7.0, tolerance=1e-2), dict(sim.engine_calls)
    (one, calls_one), (two, calls_two) = results["1"], results["2"]
    pd.testing.assert_frame_equal(one.scans, two.scans, check_exact=True)
    pd.testing.assert_frame_equal(one.grid, two.grid, check_exact=True)
    assert calls_one == calls_two


def test_there_are_126_increasing_cover_candidates():
    cands = candidate_schedules(InsertionModel.deployed().probe_grid)
    assert len(cands) == 126 and all(list(c) == sorted(c) for c in cands)


@pytest.fixture
def base_run(tmp_path, make_config):
    cfg = make_config(model={"boundary": "corrected", "delta": 0.905}, probes={"budget": 4})
    return load_run(run_study(cfg, tmp_path / "base").run_dir)


def test_frame_fault_moves_the_simulator_aim_and_nothing_in_the_belief(base_run):
    clean, _ = replay_episodes(base_run, {})
    shifted, sim = replay_episodes(base_run, {"simulator": {"aim_offset": 1.0}})
    belief_cols = ["action", "predicted", "retained_lo", "retained_hi", "hull_lo", "hull_hi", "score_s", "post_var", "max_surprise", "covered", "escaped"]
    pd.testing.assert_frame_equal(clean[belief_cols], shifted[belief_cols])
    assert sim.aim_offset == 1.0
    # The realized outcome is that of the shifted aim under the analytic truth.
    truth = base_run.instances.set_index("instance_id")
    row = shifted[shifted.method == "probe_robust"].iloc[0]
    x, c = truth.loc[row.instance_id, ["true_x_hole", "true_c"]]
    assert row.realized == float(abs(row.action + 1.0 - x) >= 0.6 * c + 1.1)


def test_boundary_fault_changes_only_the_model(base_run):
    faulted, _ = replay_episodes(base_run, {"model": {"boundary": "deployed"}})
    assert set(faulted.variant) == {"deployed"}
    clean, _ = replay_episodes(base_run, {})
    pd.testing.assert_series_equal(faulted.z_true, clean.z_true)


def test_particles_fault_uses_fewer_particles_without_jitter(base_run):
    faulted, _ = replay_episodes(base_run, {"belief": {"particles": 32, "jitter": False}})
    assert faulted[faulted.method == "probe_robust"].n_retained.max() <= 32


def test_fault_arms_cover_five_classes_with_fix_and_tempering():
    arms = fault_arms(4, 12, 128, 1.0, 4.0, 0.5)
    faults = {a.fault for a in arms}
    assert faults == {"none", "noise", "boundary", "prior", "particles", "frame"}
    for fault in faults - {"none"}:
        assert {a.arm for a in arms if a.fault == fault} == {"fault", "fix", "tempered"}
    noise_fix = next(a for a in arms if a.fault == "noise" and a.arm == "fix")
    assert noise_fix.overrides == {"model": {"sigma": 2.0}}


def test_fault_harness_arms_sharing_a_replay_equal_their_own_replays(base_run):
    """Arms with the same rollout and overrides share one replay; every arm's rows equal its own replay."""
    arms = [Arm("none", "fault", "base", {}), Arm("boundary", "fault", "base", {"model": {"boundary": "deployed"}}),
            Arm("boundary", "fix", "base", {}), Arm("frame", "fix", "base", {})]
    episodes = run_fault_harness({"base": base_run}, arms)
    for arm in arms:
        rows = episodes[(episodes.fault == arm.fault) & (episodes.arm == arm.arm)].drop(columns=["fault", "arm"])
        alone, _ = replay_episodes(base_run, arm.overrides)
        pd.testing.assert_frame_equal(rows.reset_index(drop=True), alone, check_exact=True)
    assert len(episodes) == 4 * len(alone)


def test_replay_refuses_to_change_readings(base_run):
    with pytest.raises(ValueError, match="readings"):
        replay_episodes(base_run, {"simulator": {"noise_sigma": 2.0}})


@pytest.mark.slow
@pytest.mark.mujoco
def test_reproduce_insertion_quick_end_to_end(tmp_path):
    pytest.importorskip("mujoco")
    from probecommit.report.insertion_study import reproduce_insertion
    from probecommit.report.ledger import Ledger
    from probecommit.report.reproduction_md import Doc, insertion_section

    rep = reproduce_insertion(tmp_path / "q", quick=True)
    payload = json.loads((tmp_path / "q" / "results" / "results.json").read_text())
    r = payload["results"]
    assert abs(r["scan"]["delta"] - 0.905) < 0.01
    assert set(r["table_faults"]) == {"none", "noise", "boundary", "prior", "particles", "frame"}
    assert {"table_insertion", "table_audit", "table_testc", "robust", "resplits"} <= set(r)
    assert rep.engine_calls["tap_reading"] > 0
    assert set(r["fault_signatures"]["boundary"]) >= {"1", "8"}  # the figure's data, by fault and budget
    publication = tmp_path / "pub"
    (publication / "insertion").mkdir(parents=True)
    (publication / "insertion" / "results.json").write_text(json.dumps(payload))
    doc = Doc(publication, Ledger())
    insertion_section(doc)
    text = doc.text()
    assert "Test C" in text and "| quantity | paper |" in text and "Table VIII" in text
