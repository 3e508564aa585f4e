"""End-to-end runs on the analytic engine: determinism, replay, run directories."""

import json

import pandas as pd
import pytest

from probecommit.runner.replay import load_run, replay_run
from probecommit.runner.study import run_study
from probecommit.store.rundir import RunDirError


def test_same_seed_runs_are_bit_identical(tmp_path, make_config):
    cfg = make_config()
    a = run_study(cfg, tmp_path / "a").episodes
    b = run_study(cfg, tmp_path / "b").episodes
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    assert len(a) == 6 * 2 * (5 + 2)


def test_unit_size_does_not_change_results(tmp_path, make_config):
    a = run_study(make_config(unit_instances=1), tmp_path / "a").episodes
    b = run_study(make_config(unit_instances=6), tmp_path / "b").episodes
    pd.testing.assert_frame_equal(a, b, check_exact=True)


def test_replay_under_same_model_reproduces_episodes(tmp_path, make_config):
    run = run_study(make_config(), tmp_path / "run")
    out = replay_run(run.run_dir, tmp_path / "same", {"model": {"boundary": "deployed"}})
    pd.testing.assert_frame_equal(load_run(out).episodes, run.episodes, check_exact=True)
    # No engine query beyond those the run cached.
    manifest = json.loads((out / "manifest.json").read_text())
    assert sum(manifest["engine_calls"].values()) == 0


def test_replay_under_corrected_model_sees_identical_probes(tmp_path, make_config):
    run = run_study(make_config(), tmp_path / "run")
    out = replay_run(run.run_dir, tmp_path / "corr", {"model": {"boundary": "corrected", "delta": 0.905}})
    corrected = load_run(out)
    pd.testing.assert_frame_equal(corrected.probes, load_run(run.run_dir).probes)
    assert set(corrected.episodes["variant"]) == {"corrected"}
    # The analytic truth uses the corrected boundary: the corrected belief never loses the truth.
    probe = corrected.episodes[corrected.episodes.method == "probe_robust"]
    assert not probe["escaped"].any()


def test_budget_prefix_trajectories_are_nested(tmp_path, make_config):
    long = run_study(make_config(), tmp_path / "long")
    short = run_study(make_config(probes={"budget": 3}), tmp_path / "short")
    pl, ps = load_run(long.run_dir).probes, load_run(short.run_dir).probes
    merged = ps.merge(pl, on=["instance_id", "repeat", "j"], suffixes=("_s", "_l"))
    assert len(merged) == len(ps)
    assert (merged.u_s == merged.u_l).all() and (merged.y_s == merged.y_l).all()


def test_run_directory_of_another_config_is_refused(tmp_path, make_config):
    run_study(make_config(), tmp_path / "run")
    with pytest.raises(RunDirError, match="different config"):
        run_study(make_config(seed=12), tmp_path / "run")


def test_manifest_is_last_and_lists_table_digests(tmp_path, make_config):
    run = run_study(make_config(), tmp_path / "run")
    manifest = run.manifest
    assert set(manifest["sha256"]) == {"instances.parquet", "probes.parquet", "episodes.parquet", "engine_cache.parquet", "config.yaml"}
    assert manifest["engine_calls"]["tap_reading"] <= 6 * 9
