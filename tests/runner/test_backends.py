"""Local processes and Ray give exactly the serial run's tables."""

import os

import pandas as pd
import pytest

from probecommit.runner.study import run_study
from tests.runner.test_resume import assert_same_tables


def test_two_worker_processes_match_a_serial_run(tmp_path, make_config):
    cfg = make_config(unit_instances=1)  # 6 units over 2 workers, finishing out of order
    serial = run_study(cfg, tmp_path / "serial")
    parallel = run_study(cfg, tmp_path / "parallel", workers=2)
    assert parallel.manifest["backend"] == "processes:2"
    assert len({s for s in _unit_pids(parallel.run_dir)}) == 2
    pd.testing.assert_frame_equal(parallel.episodes, serial.episodes, check_exact=True)
    assert_same_tables(serial.run_dir, parallel.run_dir)
    assert parallel.manifest["engine_calls"] == serial.manifest["engine_calls"]


def _unit_pids(run_dir):
    import json

    return [json.loads(p.read_text())["pid"] for p in (run_dir / "shards").glob("*.stats.json")]


@pytest.mark.ray
@pytest.mark.slow
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
