"""``probecommit run --ray local`` beside a cluster another process recorded: it starts its own.

The issue's failure ("When connecting to an existing cluster, num_cpus and num_gpus must not be
provided") came from ``ray.init`` attaching to a cluster named by ``RAY_ADDRESS`` or by Ray's
recorded-cluster file. Here a real Ray head runs and is planted both ways (in a Ray temp folder
of the test's own, so no other process's Ray is touched); the command, run as a user runs it
(a process), must start an instance of its own with the CPUs it asks for, and its tables must
equal a run in threads, byte for byte.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from probecommit.runner.study import run_study
from probecommit.runner.config import dump_config
from tests.conftest import small_config
from tests.runner.test_resume import assert_same_tables

ray = pytest.importorskip("ray")
#: Two local Ray clusters at once (two pytest-xdist workers) share /tmp/ray: every Ray test runs in one worker.
pytestmark = pytest.mark.xdist_group("ray")
ROOT = Path(__file__).resolve().parents[2]

CONFIG = dict(name="planted", instances={"count": 8}, belief={"particles": 64}, unit_instances=2)


@pytest.mark.ray
@pytest.mark.slow
def test_ray_local_starts_its_own_instance_beside_a_recorded_cluster(tmp_path, monkeypatch):
    from ray.cluster_utils import Cluster

    # Ray's sockets live under its temp folder, whose path must stay short (a Unix socket's limit).
    ray_tmp = Path(tempfile.mkdtemp(prefix="pcray", dir="/tmp"))
    monkeypatch.setenv("RAY_TMPDIR", str(ray_tmp))
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False})
    try:
        planted = cluster.address
        (ray_tmp / "ray").mkdir(exist_ok=True)
        (ray_tmp / "ray" / "ray_current_cluster").write_text(planted)  # what `ray start` records
        config = small_config(**CONFIG)
        config_path = tmp_path / "planted.yaml"
        config_path.write_text(dump_config(config))
        env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "RAY_ADDRESS": planted, "COLUMNS": "120"}
        done = subprocess.run([sys.executable, "-m", "probecommit", "run", str(config_path), "--out",
                               str(tmp_path / "ray"), "--ray", "local", "--workers", "2"],
                              env=env, capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
    finally:
        cluster.shutdown()
        shutil.rmtree(ray_tmp, ignore_errors=True)
    manifest = json.loads((tmp_path / "ray" / "manifest.json").read_text())
    assert manifest["backend"] == "ray:local"
    # Attaching to the planted head with num_cpus=2 fails outright (the error): the
    # run finished, so it started an instance of its own; how long that took is recorded.
    assert 0 < manifest["timing"]["backend_start_s"]
    print(f"--ray local started its instance in {manifest['timing']['backend_start_s']:.2f} s")
    threads = run_study(config, tmp_path / "threads", threads=2)
    assert_same_tables(threads.run_dir, tmp_path / "ray")
