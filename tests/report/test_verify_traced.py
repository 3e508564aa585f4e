"""Traced-only numbers are counted by why they are not recomputed (``recompute.traced_kind``): exact answers."""

from __future__ import annotations

import pytest

from probecommit.report.recompute import TRACED_KINDS, TRACED_PATTERNS, traced_kind


@pytest.mark.parametrize("study,key,kind", [
    ("gru", "training_loss_last_mean", "training"),
    ("explain", "gru.retrain_vs_study_max_abs_param_diff", "training"),
    ("explain", "gru.se_ratio", "not stored"),  # recomputed since the GRU study's rows are stored: never "training"
    ("engines", "scans.pybullet.engine_calls.tap_reading", "measured"),
    ("robot", "replay_reproduced_fraction", "measured"),
    ("insertion", "scan.frozen_delta", "measured"),
    ("insertion", "scan.delta", "not stored"),
    ("insertion", "cover.frozen_rank", "engine rows"),
    ("insertion", "setup.bootstrap.seed", "setting"),
    ("robot", "config.belief.nu", "setting"),
    ("figures", "scenes.renders.3", "scene render"),
    ("explain", "pybullet_escape.paper_ratio_sd", "paper value"),
    ("explain", "thresholds.paper_schedule.t_5", "not stored"),  # "paper_schedule" is ours, not a paper value
])
def test_a_traced_number_is_named_by_the_first_pattern_that_matches(study, key, kind):
    assert traced_kind(study, key) == kind


def test_every_pattern_names_a_declared_kind():
    assert {kind for _, _, kind in TRACED_PATTERNS} | {"not stored"} <= set(TRACED_KINDS)
