"""A run directory is read only when complete and unchanged since its manifest."""

from __future__ import annotations

import pytest

from probecommit.audit.io import EpisodeTableError, read_episodes
from probecommit.runner.replay import load_run
from probecommit.runner.study import run_study
from probecommit.store.rundir import RunDirError
from tests.conftest import small_config


@pytest.fixture
def run(tmp_path):
    return run_study(small_config(name="intact", instances={"count": 4}), tmp_path / "run").run_dir


def test_a_hand_edited_config_is_caught_by_replay(run):
    (run / "config.yaml").write_text((run / "config.yaml").read_text().replace("sigma: 0.5", "sigma: 0.4", 1))
    with pytest.raises(RunDirError, match="config.yaml changed"):
        load_run(run)


def test_an_edited_table_or_a_missing_manifest_is_refused_by_the_audit(run):
    read_episodes(run)  # intact: reads
    (run / "manifest.json").rename(run / "manifest.bak")
    with pytest.raises(EpisodeTableError, match="incomplete"):
        read_episodes(run)
    (run / "manifest.bak").rename(run / "manifest.json")
    with open(run / "episodes.parquet", "ab") as handle:
        handle.write(b"\0")
    with pytest.raises(EpisodeTableError, match="episodes.parquet changed"):
        read_episodes(run)
