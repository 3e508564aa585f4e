"""--ray ADDRESS ships the package to the workers (Ray's runtime environment).

On a two-node local cluster (``ray.cluster_utils.Cluster``) the units run on workers
that import the probecommit Ray uploaded, not an installed one, and every table equals a
run in threads, byte for byte.
"""

from __future__ import annotations

import os

import pandas as pd
import pytest

from probecommit.runner.study import package_runtime_env, run_study
from probecommit.store.rundir import RunDir
from tests.conftest import small_config
from tests.runner.test_resume import assert_same_tables

ray = pytest.importorskip("ray")
#: Two local Ray clusters at once (two pytest-xdist workers) share /tmp/ray: every Ray test runs in one worker.
pytestmark = pytest.mark.xdist_group("ray")


@pytest.mark.slow
def test_units_run_on_a_two_node_cluster_with_the_shipped_package(tmp_path):
    from ray.cluster_utils import Cluster

    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False})
    cluster.add_node(num_cpus=1)
    try:
        config = small_config(name="ray2", instances={"count": 8}, belief={"particles": 64}, unit_instances=2)
        result = run_study(config, tmp_path / "ray", ray_address=cluster.address)
        threads = run_study(config, tmp_path / "threads", threads=2)
        pd.testing.assert_frame_equal(result.episodes, threads.episodes, check_exact=True)
        assert_same_tables(threads.run_dir, result.run_dir)  # every table, byte for byte
        assert result.manifest["backend"].startswith("ray:")
        run = RunDir(result.run_dir)
        assert os.getpid() not in {run.unit_stats(u)["pid"] for u in run.done_units()}  # ran on the nodes

        ray.init(address=cluster.address, runtime_env=package_runtime_env(), log_to_driver=False)

        @ray.remote
        def where() -> str:
            import probecommit

            return probecommit.__file__

        paths = ray.get([where.remote() for _ in range(4)])
        assert all("runtime_resources" in p for p in paths), paths  # the uploaded copy, not the install
    finally:
        ray.shutdown()
        cluster.shutdown()
