"""The hinge's torque commit (ex27, docs/decisions.md): the closed form against hand cases and a fine Euler
integration, the declared grid's ends, the model's commit (probes stay coasts) and both scenes' push query."""

from __future__ import annotations

import numpy as np
import pytest

from probecommit.tasks.hinge.model import ACTION_SPEEDS, PRIOR_HIGH, PRIOR_LOW, HingeModel, inertia, stop_angle
from probecommit.tasks.hinge.sim_torque import AnalyticHingeTorqueSimulator
from probecommit.tasks.hinge.torque import torque_angle, torque_for_speed, torque_grid, torque_model


def _euler(torque: float, f: float, b: float, m: float, push_s: float, dt: float = 1e-5) -> float:
    """``I dw/dt = T - f - b w`` for ``push_s`` from rest, then the coast to a stop, by explicit Euler."""
    i, w, angle, t = float(inertia(m)), 0.0, 0.0, 0.0
    while t < push_s:
        w = max(w + dt * (torque - f - b * w) / i, 0.0)
        angle, t = angle + dt * w, t + dt
    while w > 0:
        w = max(w - dt * (f + b * w) / i, 0.0)
        angle += dt * w
    return angle


def test_impulse_is_a_coast_from_j_over_i():
    assert float(torque_angle(0.6, 0.5, 0.3, 4.0, 0.0)) == pytest.approx(float(stop_angle(0.6 / inertia(4.0), 0.5, 0.3, 4.0)))


def test_a_torque_at_or_below_the_friction_does_not_move_the_door():
    assert float(torque_angle(0.5, 0.5, 0.3, 4.0, 1.0)) == 0.0
    assert float(torque_angle(0.2, 0.5, 0.3, 4.0, 0.25)) == 0.0


@pytest.mark.parametrize("torque, theta, push_s", [(1.0, (0.5, 0.3, 4.0), 0.25), (2.0, (0.2, 0.1, 2.0), 1.0),
                                                   (3.0, (0.8, 0.5, 6.0), 1.0)])
def test_closed_form_matches_a_fine_integration(torque, theta, push_s):
    assert float(torque_angle(torque, *theta, push_s)) == pytest.approx(_euler(torque, *theta, push_s), rel=2e-3)


@pytest.mark.parametrize("push_s", [0.0, 0.25, 1.0])
def test_grid_spans_the_frozen_release_speeds_for_every_door_of_the_prior(push_s):
    grid = torque_grid(push_s)
    assert grid[0] == pytest.approx(torque_for_speed(float(ACTION_SPEEDS[0]), *PRIOR_LOW, push_s))
    assert grid[-1] >= torque_for_speed(float(ACTION_SPEEDS[-1]), *PRIOR_HIGH, push_s) > grid[-2]
    assert np.allclose(grid[1:] / grid[:-1], 1.01, rtol=1e-8)
    theta = (0.45, 0.4, 2.3333)  # the speed a grid torque reaches is the speed torque_for_speed inverts
    assert torque_for_speed(1.5, *theta, push_s) > torque_for_speed(0.5, *theta, push_s)


def test_the_model_commits_a_torque_and_probes_a_coast():
    model = torque_model(HingeModel(), 0.25)
    theta = np.array([[[0.5, 0.3, 4.0], [0.3, 0.2, 3.0]]])
    assert model.predict(np.array([[1.0]]), theta)[0, 0, 0] == pytest.approx(float(stop_angle(1.0, 0.5, 0.3, 4.0)))
    loss = model.loss(model.action_grid, theta, np.array([[1.0]]))
    j = 150
    assert loss[0, j, 0] == pytest.approx(abs(float(torque_angle(model.action_grid[j, 0], 0.5, 0.3, 4.0, 0.25)) - 1.0))
    assert model.action_grid.shape == (len(torque_grid(0.25)), 1) and model.push_s == 0.25
    assert HingeModel.action_grid.shape[0] == len(ACTION_SPEEDS)  # the frozen family untouched


def test_analytic_scene_commits_the_push_and_probes_the_coast():
    sim = AnalyticHingeTorqueSimulator(1.0)
    theta = np.array([0.5, 0.3, 4.0])
    out = sim.execute(theta, np.array([2.0]), np.array([1.0]))
    assert out["realized"] == pytest.approx(abs(float(torque_angle(2.0, 0.5, 0.3, 4.0, 1.0)) - 1.0))
    clean = sim.probe(theta, np.array([1.0]), np.random.default_rng(0)) - 0.02 * np.random.default_rng(0).standard_normal(1)
    assert clean[0] == pytest.approx(float(stop_angle(1.0, 0.5, 0.3, 4.0)))


@pytest.mark.parametrize("push_s", [0.0, 1.0])
def test_mujoco_push_matches_the_closed_form(push_s):
    pytest.importorskip("mujoco")
    from probecommit.tasks.hinge.sim_torque import MujocoHingeTorqueSimulator

    sim = MujocoHingeTorqueSimulator(push_s)
    for theta in ((0.2, 0.1, 2.0), (0.8, 0.5, 6.0)):
        torque = torque_for_speed(1.5, *theta, push_s)
        assert sim.push(*theta, torque) == pytest.approx(float(torque_angle(torque, *theta, push_s)), abs=3e-3)
