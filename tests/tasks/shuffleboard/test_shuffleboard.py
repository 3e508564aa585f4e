"""The shuffleboard family: SAPIEN hand cases, SAPIEN against the closed form, determinism, config errors."""

from __future__ import annotations

import numpy as np
import pytest

from probecommit.runner.config import ConfigError, parse_config
from probecommit.tasks.push1d.model import stop_distance
from probecommit.tasks.shuffleboard.model import ShuffleboardModel

sapien = pytest.importorskip("sapien")
from probecommit.tasks.shuffleboard.sim_sapien import SapienShuffleboardSimulator  # noqa: E402


@pytest.fixture(scope="module")
def sim():
    return SapienShuffleboardSimulator()


def test_hand_cases(sim):
    theta = (0.2, 0.4, 0.15)
    assert abs(sim.slide(*theta, 0.0)) < 1e-3  # no strike: no slide
    assert sim.slide(*theta, 1.0) > sim.slide(*theta, 0.5)  # harder strike: farther
    assert sim.slide(0.3, 0.4, 0.15, 1.0) < sim.slide(0.1, 0.4, 0.15, 1.0)  # more friction: shorter


@pytest.mark.parametrize("theta", [(0.1, 0.2, 0.05), (0.3, 0.6, 0.3), (0.1, 0.6, 0.3), (0.3, 0.2, 0.05)])
def test_sapien_matches_the_closed_form_within_one_percent(sim, theta):
    for strike in (0.5, 1.5, 3.0):
        assert sim.slide(*theta, strike) == pytest.approx(float(stop_distance(strike, *theta)), rel=0.01)


def test_a_fresh_scene_gives_identical_slides(sim):
    again = SapienShuffleboardSimulator()
    assert sim.slide(0.2167, 0.2667, 0.2833, 0.5) == again.slide(0.2167, 0.2667, 0.2833, 0.5)


def test_model_is_the_push_model_at_shuffleboard_scale():
    model = ShuffleboardModel()
    theta = np.array([[[0.2, 0.4, 0.15]]])
    assert model.predict(np.array([[1.0]]), theta)[0, 0, 0] == pytest.approx(float(stop_distance(1.0, 0.2, 0.4, 0.15)))
    assert model.action_grid[-1, 0] <= 4.0 and model.name == "shuffleboard"


def test_config_errors_name_the_field():
    with pytest.raises(ConfigError, match="sigma"):
        parse_config({"task": "shuffleboard", "model": {"sigma": -0.05}})
    with pytest.raises(ConfigError, match="engine"):
        parse_config({"task": "shuffleboard", "simulator": {"engine": "mujoco"}})
