"""Replay of recorded probes: exact as deployed, unchanged at fault size zero, and a planted fault seen."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from probecommit.robot.replay import fault_overrides, fault_sweep, parse_sweep, replay_session
from probecommit.robot.simulated import simulate_session
from probecommit.robot.table import session_episodes
from probecommit.runner.config import parse_config
from tests.robot.conftest import RIG_SMALL


@pytest.fixture(scope="module")
def paper_size_log(tmp_path_factory):
    """The frozen rig protocol (12 positions x 2 x 5 budgets) on the analytic rig."""
    from probecommit import paper_config
    from probecommit.runner.config import config_data, load_config

    data = config_data(load_config(paper_config("rig")))
    data["simulator"]["engine"] = "analytic"
    return simulate_session(tmp_path_factory.mktemp("rig") / "s", parse_config(data))


def test_replay_as_deployed_reproduces_every_decision(tmp_path):
    log = simulate_session(tmp_path / "s", parse_config(RIG_SMALL))
    recorded = session_episodes(log).rows
    replayed, reproduced = replay_session(log)
    assert reproduced == 1.0
    pd.testing.assert_frame_equal(recorded, replayed.rows)


def test_a_fault_of_size_zero_changes_nothing(paper_size_log):
    sweep, _ = fault_sweep(paper_size_log, "boundary", [0.0], resamples=200)
    row = sweep.iloc[0]
    assert row["delta_optimism"] == 0.0 and row["delta_coverage"] == 0.0
    assert not row["optimism_resolved"] and not row["coverage_resolved"]


def test_a_planted_boundary_fault_is_seen_by_optimism_as_it_grows(paper_size_log):
    sweep, reproduced = fault_sweep(paper_size_log, "boundary", [0.0, 4.0, 8.0, 12.0], resamples=1000)
    assert reproduced == 1.0
    d = sweep["delta_optimism"].to_numpy()
    assert d[0] == 0.0 and d[-1] > 0.1
    assert sweep["optimism_resolved"].iloc[-1]
    assert d[-1] > d[1]


def test_a_narrowed_prior_breaks_coverage(paper_size_log):
    sweep, _ = fault_sweep(paper_size_log, "prior", [12.0], resamples=500)
    row = sweep.iloc[0]
    assert row["coverage"] < 0.9 and row["escape"] > 0.1 and row["coverage_resolved"]


def test_fault_arguments_are_checked(rig_config):
    assert parse_sweep("0:14:1") == list(map(float, range(15)))
    assert parse_sweep("0, 4,8") == [0.0, 4.0, 8.0]
    for bad in ("0:14", "5:1:1", "0:1:0", "a,b", ""):
        with pytest.raises(ValueError, match="--sweep"):
            parse_sweep(bad)
    with pytest.raises(ValueError, match="unknown fault"):
        fault_overrides(rig_config, "gravity", 1.0)
    with pytest.raises(ValueError, match="half-width must be > 0"):
        fault_overrides(rig_config, "prior", 0.0)
    assert fault_overrides(rig_config, "prior", 12.0)["model"]["prior_low"][0] == -12.0
