"""Local processes and Ray give exactly the serial run's tables."""

import os

import pandas as pd
import pytest

from probecommit.runner import study
from probecommit.runner.study import run_study, unit_threads
from probecommit.store.rundir import RunDir
from tests.runner.test_resume import assert_same_tables


def test_two_worker_processes_match_a_serial_run(tmp_path, make_config):
    cfg = make_config(unit_instances=1)  # 6 units over 2 workers, finishing out of order
    serial = run_study(cfg, tmp_path / "serial", threads=1)
    assert serial.manifest["backend"] == "serial"
    parallel = run_study(cfg, tmp_path / "parallel", workers=2)
    assert parallel.manifest["backend"] == "processes:2"
    pids = set(_unit_pids(parallel.run_dir))
    # The units ran in worker processes. Which worker takes which unit is the pool's choice: a
    # worker that starts first may take all six quick units before the second has imported.
    assert os.getpid() not in pids and 1 <= len(pids) <= 2
    pd.testing.assert_frame_equal(parallel.episodes, serial.episodes, check_exact=True)
    assert_same_tables(serial.run_dir, parallel.run_dir)
    assert parallel.manifest["engine_calls"] == serial.manifest["engine_calls"]


def test_unit_threads_match_a_serial_run(tmp_path, make_config):
    cfg = make_config(unit_instances=1)  # 6 units over 3 threads, finishing out of order
    serial = run_study(cfg, tmp_path / "serial", threads=1)
    threaded = run_study(cfg, tmp_path / "threads", threads=3)
    assert threaded.manifest["backend"] == "threads:3"
    pd.testing.assert_frame_equal(threaded.episodes, serial.episodes, check_exact=True)
    assert_same_tables(serial.run_dir, threaded.run_dir)
    assert threaded.manifest["engine_calls"] == serial.manifest["engine_calls"]


def test_unit_threads_follow_the_engine_threads_and_the_simulator(monkeypatch, make_config):
    cfg = make_config()
    monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", "3")
    assert unit_threads(cfg) == 3 and unit_threads(cfg, 2) == 2 and unit_threads(cfg, 1) == 1
    with pytest.raises(ValueError, match="threads must be >= 1"):
        unit_threads(cfg, 0)

    from probecommit.tasks.base import CachedSimulator

    class Unsafe(CachedSimulator):  # a simulator keeping the base's thread_safe = False runs its units one by one
        pass

    monkeypatch.setattr(study.build, "simulator_class", lambda config: Unsafe)
    assert unit_threads(cfg, 4) == 1


def test_a_failing_unit_thread_stops_the_run_and_leaves_it_resumable(tmp_path, monkeypatch, make_config):
    cfg = make_config(unit_instances=1)
    real = study.compute_units

    def flaky(config_data, instances, units):
        if "unit-00003" in [name for name, _ in units]:
            raise RuntimeError("engine crashed in unit 3")
        return real(config_data, instances, units)

    monkeypatch.setattr(study, "compute_units", flaky)
    with pytest.raises(RuntimeError, match="unit 3"):
        run_study(cfg, tmp_path / "run", threads=2)
    monkeypatch.setattr(study, "compute_units", real)
    finished = len(RunDir(tmp_path / "run").done_units())  # whole units committed before the error
    assert finished < 6
    resumed = run_study(cfg, tmp_path / "run", threads=2)
    assert resumed.manifest["resumed_units"] == finished
    serial = run_study(cfg, tmp_path / "serial", threads=1)
    pd.testing.assert_frame_equal(resumed.episodes, serial.episodes, check_exact=True)


def _unit_pids(run_dir):
    run = RunDir(run_dir)
    return [run.unit_stats(unit)["pid"] for unit in run.done_units()]


@pytest.mark.parametrize("units", [1, 2], ids=["units of one instance", "units of two"])
def test_units_computed_in_groups_equal_units_computed_alone(tmp_path, make_config, monkeypatch, units):
    """Several small units computed as one batch and split give each unit's tables exactly."""
    cfg = make_config(unit_instances=units)
    monkeypatch.setattr(study, "GROUP_EPISODES", 1)
    alone = run_study(cfg, tmp_path / "alone", threads=1)
    monkeypatch.setattr(study, "GROUP_EPISODES", 10_000)
    grouped = run_study(cfg, tmp_path / "grouped", threads=1)
    run = RunDir(grouped.run_dir)
    first = sorted(run.done_units())[0]
    assert len(run.unit_stats(first)["group"]) == 6 // units  # really computed together
    assert_same_tables(alone.run_dir, grouped.run_dir)
    assert grouped.manifest["engine_calls"] == alone.manifest["engine_calls"]
    assert grouped.manifest["episodes"] == alone.manifest["episodes"]
    # Rebuilt from the stored batches (slices of the group's tables, read back): the same tables.
    (grouped.run_dir / "manifest.json").unlink()
    (grouped.run_dir / "episodes.parquet").unlink()
    rebuilt = run_study(cfg, tmp_path / "grouped", threads=1)
    assert rebuilt.manifest["resumed_units"] == 6 // units
    assert_same_tables(alone.run_dir, rebuilt.run_dir)


@pytest.mark.ray
@pytest.mark.slow
@pytest.mark.xdist_group("ray")  # one Ray cluster at a time (tests/runner/test_ray_planted.py)
def test_local_ray_matches_a_serial_run(tmp_path, make_config):
    ray = pytest.importorskip("ray")
    cfg = make_config(unit_instances=2)
    serial = run_study(cfg, tmp_path / "serial")
    # What `probecommit run CONFIG --ray local --workers 2` does: start, run, shut down.
    on_ray = run_study(cfg, tmp_path / "ray", workers=2, ray_address="local")
    assert not ray.is_initialized()
    assert on_ray.manifest["backend"] == "ray:local"
    assert on_ray.manifest["timing"]["backend_start_s"] > 0
    assert os.getpid() not in _unit_pids(on_ray.run_dir)  # the units really ran in Ray workers
    pd.testing.assert_frame_equal(on_ray.episodes, serial.episodes, check_exact=True)
    assert_same_tables(serial.run_dir, on_ray.run_dir)


@pytest.mark.mujoco
def test_mujoco_units_in_threads_match_one_by_one(tmp_path, monkeypatch, make_config):
    """MuJoCo insertion is thread-safe: units in threads, each prefetching in engine threads, give the serial tables."""
    pytest.importorskip("mujoco")
    cfg = make_config(unit_instances=1, instances={"count": 4}, probes={"budget": 3}, belief={"particles": 128},
                      simulator={"engine": "mujoco"}, methods=["blind_robust", "probe_robust"])
    monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", "1")
    serial = run_study(cfg, tmp_path / "serial")
    monkeypatch.setenv("PROBECOMMIT_ENGINE_THREADS", "2")
    threaded = run_study(cfg, tmp_path / "threads")
    assert (serial.manifest["backend"], threaded.manifest["backend"]) == ("serial", "threads:2")
    assert_same_tables(serial.run_dir, threaded.run_dir)
    assert threaded.manifest["engine_calls"] == serial.manifest["engine_calls"]
