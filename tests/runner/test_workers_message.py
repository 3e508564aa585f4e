"""``--workers 2`` on a MuJoCo study (thread-safe simulator) runs threads and says why, as the
command prints it (issue 42, target 5: worker processes measured 0.72x one worker on 2 cores)."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from probecommit.cli.app import app
from probecommit.runner import study
from probecommit.runner.config import dump_config
from tests.conftest import small_config


def test_a_mujoco_study_with_two_workers_runs_two_threads_and_says_why():
    pytest.importorskip("mujoco")
    workers, threads, why = study.choose_backend(small_config(simulator={"engine": "mujoco"}), 2)
    assert (workers, threads) == (1, 2)
    assert why.startswith("--workers 2: running the units in 2 threads") and "the mujoco simulator is thread-safe" in why


def test_the_command_prints_the_reason_and_runs_in_threads(tmp_path):
    config = small_config(instances={"count": 4}, belief={"particles": 32}, probes={"budget": 2})
    path = tmp_path / "study.yaml"
    path.write_text(dump_config(config))
    result = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "run"), "--workers", "2"])
    assert result.exit_code == 0, result.output
    assert "--workers 2: running the units in 2 threads of this process" in " ".join(result.output.split())
    assert json.loads((tmp_path / "run" / "manifest.json").read_text())["backend"] == "threads:2"
