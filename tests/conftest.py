"""Shared fixtures: small analytic studies (no engine needed)."""

import pytest

from probecommit.runner.config import parse_config


def small_config(**overrides) -> "StudyConfig":  # noqa: F821
    data = {
        "name": "small",
        "seed": 11,
        "repeats": 2,
        "instances": {"split": "test", "count": 6, "seed": 3},
        "probes": {"schedule": "random", "budget": 5},
        "belief": {"particles": 256},
        "simulator": {"engine": "analytic", "boundary_offset": 0.905},
        "unit_instances": 2,
        "blind_prior_samples": 2000,
    }
    for key, value in overrides.items():
        data[key] = {**data[key], **value} if isinstance(value, dict) and key in data else value
    return parse_config(data)


def cal_test_runs(root, seeds: tuple[int, int], count: int, repeats: int, **overrides) -> dict:
    """A calibration and a test run of the small config ("cal" and "test" splits, one instance seed each): the
    pair that calibration, gate, chunking, margin-search and report tests read. Returns their run directories."""
    from probecommit.runner.study import run_study

    out = {}
    for split, seed in zip(("cal", "test"), seeds):
        cfg = small_config(name=split, instances={"split": split, "count": count, "seed": seed}, repeats=repeats,
                           **overrides)
        out[split] = run_study(cfg, root / split).run_dir
    return out


@pytest.fixture
def make_config():
    return small_config
