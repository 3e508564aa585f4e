"""The robot study in quick mode: a complete simulated-rig session, audited and replayed."""

from __future__ import annotations

from probecommit.studies.robot import run_robot_study


def test_quick_robot_study(tmp_path):
    study = run_robot_study(tmp_path, quick=True, resamples=200)
    assert study.reproduced == 1.0
    assert list(study.table["taps"]) == [1, 2, 3, 4, 5] and study.table["episodes"].sum() == 4 * 5
    assert study.boundary["size"].tolist() == [0.0, 7.0, 14.0]
    assert study.boundary["delta_optimism"].iloc[0] == 0.0
    payload = study.payload()["results"]
    assert payload["episodes"] == 20 and payload["n_covered"] <= 20
