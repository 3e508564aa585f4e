"""The hinge family: closed-form hand cases, MuJoCo against the closed form, determinism, config errors."""

from __future__ import annotations

import numpy as np
import pytest

from probecommit.runner.config import ConfigError, parse_config
from probecommit.tasks.hinge.model import HingeModel, inertia, stop_angle
from probecommit.tasks.hinge.sim_analytic import AnalyticHingeSimulator


def test_closed_form_limits():
    # Coulomb only (b -> 0): I w0^2 / (2 f); damping only (f -> 0): I w0 / b.
    i = float(inertia(3.0))
    assert float(stop_angle(1.0, 0.5, 1e-7, 3.0)) == pytest.approx(i / (2 * 0.5), rel=1e-5)
    assert float(stop_angle(1.0, 1e-9, 0.2, 3.0)) == pytest.approx(i / 0.2, rel=1e-5)
    assert float(stop_angle(0.0, 0.5, 0.2, 3.0)) == 0.0


def test_more_friction_or_damping_stops_sooner_and_heavier_doors_go_further():
    base = float(stop_angle(1.0, 0.5, 0.3, 4.0))
    assert float(stop_angle(1.0, 0.7, 0.3, 4.0)) < base
    assert float(stop_angle(1.0, 0.5, 0.4, 4.0)) < base
    assert float(stop_angle(1.0, 0.5, 0.3, 5.0)) > base


def test_model_shapes_and_loss_against_a_hand_value():
    model = HingeModel()
    theta = np.array([[[0.5, 0.3, 4.0], [0.3, 0.2, 3.0]]])
    pred = model.predict(np.array([[1.0]]), theta)
    assert pred.shape == (1, 2, 1)
    loss = model.loss(model.action_grid, theta, np.array([[1.0]]))
    assert loss.shape == (1, model.action_grid.shape[0], 2)
    j = 100
    expected = abs(float(stop_angle(model.action_grid[j, 0], 0.5, 0.3, 4.0)) - 1.0)
    assert loss[0, j, 0] == pytest.approx(expected)


def test_mujoco_coast_matches_the_closed_form():
    pytest.importorskip("mujoco")
    from probecommit.tasks.hinge.sim_mujoco import MujocoHingeSimulator

    sim = MujocoHingeSimulator()
    for theta in ((0.2, 0.1, 2.0), (0.8, 0.5, 6.0), (0.45, 0.4, 2.3333)):
        for w in (0.5, 1.5, 4.0):
            assert sim.coast(*theta, w) == pytest.approx(float(stop_angle(w, *theta)), abs=3e-3)
    assert sim.coast(0.5, 0.3, 4.0, 1.0) == sim.coast(0.5, 0.3, 4.0, 1.0)  # bit-identical on repeat


def test_readings_are_deterministic_given_the_generator():
    sim = AnalyticHingeSimulator()
    theta, u = np.array([0.5, 0.3, 4.0]), np.array([1.0])
    assert sim.probe(theta, u, np.random.default_rng(3))[0] == sim.probe(theta, u, np.random.default_rng(3))[0]
    out = sim.execute(theta, np.array([2.0]), np.array([1.0]))
    assert out["realized"] == pytest.approx(abs(float(stop_angle(2.0, 0.5, 0.3, 4.0)) - 1.0))


def test_config_errors_name_the_field():
    with pytest.raises(ConfigError, match="sigma"):
        parse_config({"task": "hinge", "model": {"sigma": -0.02}})
    with pytest.raises(ConfigError, match="truth_low"):
        parse_config({"task": "hinge", "instances": {"truth_low": [0.0, 0.1, 2.0], "truth_high": [0.8, 0.5, 6.0]}})
