"""A small simulated-rig config (analytic rig: no engine needed) for the robot tests."""

from __future__ import annotations

import pytest

from probecommit.runner.config import parse_config

RIG_SMALL = {
    "name": "rig-small", "task": "rig", "seed": 3, "repeats": 1,
    "instances": {"split": "rig", "count": 4, "seed": 1},
    "probes": {"schedule": "random", "budget": 3, "budgets": [1, 2, 3]},
    "belief": {"particles": 512, "nu": 0.8, "likelihood": "mixture", "epsilon": 0.03,
               "mixture_low": -12.0, "mixture_high": 2.0},
    "simulator": {"engine": "analytic", "misread_rate": 0.01},
    "methods": ["probe_robust"],
}


@pytest.fixture
def rig_config():
    return parse_config(RIG_SMALL)
