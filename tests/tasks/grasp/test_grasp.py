"""The grasp family: force balance by hand, MuJoCo's lift and squeeze against it, the success window."""

from __future__ import annotations

import numpy as np
import pytest

from probecommit.runner.config import ConfigError, parse_config
from probecommit.tasks.grasp.model import (CRUSH_RATIO, G, LIFT_ACCEL, SQUEEZE_S, GraspModel, hold_force,
                                           squeeze_slip_mm)
from probecommit.tasks.grasp.sim_base import AnalyticGraspSimulator


def test_force_balance_by_hand():
    assert float(hold_force(0.5, 0.2)) == pytest.approx(0.2 * 9.81 / 1.0)
    assert float(hold_force(0.5, 0.2, LIFT_ACCEL)) == pytest.approx(0.2 * (9.81 + 2.0) / 1.0)
    # A squeeze at the hold force or above does not slip; at zero force the object falls freely.
    assert float(squeeze_slip_mm(hold_force(0.5, 0.2), 0.5, 0.2)) == 0.0
    assert float(squeeze_slip_mm(0.0, 0.5, 0.2)) == pytest.approx(1000 * 0.5 * SQUEEZE_S ** 2 * G)


def test_success_window_and_margin():
    model = GraspModel()
    theta = np.array([[[0.5, 0.2]]])
    f_lift = float(hold_force(0.5, 0.2, LIFT_ACCEL))
    lo, hi = model.success_interval(theta)
    assert (lo[0, 0], hi[0, 0]) == pytest.approx((f_lift, CRUSH_RATIO * f_lift))
    forces = np.array([0.9 * f_lift, 1.2 * f_lift, 1.6 * f_lift])
    assert model.loss(forces, theta)[0, :, 0].tolist() == [True, False, True]
    tight = model.with_margin(0.5).success_interval(theta)
    assert tight[0][0, 0] > f_lift and tight[1][0, 0] < CRUSH_RATIO * f_lift


def test_analytic_truth_and_feasibility():
    sim = AnalyticGraspSimulator(noise_sigma=0.0)
    theta = np.array([0.5, 0.2])
    f_lift = float(hold_force(0.5, 0.2, LIFT_ACCEL))
    assert sim.execute(theta, np.array([1.2 * f_lift]))["realized"] == 0.0
    assert sim.execute(theta, np.array([0.9 * f_lift]))["realized"] == 1.0
    crushed = sim.execute(theta, np.array([1.6 * f_lift]))
    assert crushed["realized"] == 1.0 and crushed["crushed"]
    forces = GraspModel.action_grid[:, 0]
    assert sim.feasible(theta, forces)
    assert not sim.feasible(np.array([0.2, 0.5]), forces)  # needs 14.8 N: beyond the 5 N gripper


def test_mujoco_lift_and_squeeze_follow_the_force_balance():
    pytest.importorskip("mujoco")
    from probecommit.tasks.grasp.sim_mujoco import MujocoGraspSimulator

    sim = MujocoGraspSimulator()
    for mu, m in ((0.5, 0.2), (0.3, 0.4), (0.9, 0.1)):
        f_lift = float(hold_force(mu, m, LIFT_ACCEL))
        assert sim.lift(mu, m, 1.05 * f_lift) < 2.0  # holds
        assert sim.lift(mu, m, 0.95 * f_lift) > 2.0  # slips
        f_hold = float(hold_force(mu, m))
        for ratio in (0.5, 0.8, 1.2):
            assert sim.squeeze(mu, m, ratio * f_hold) == pytest.approx(float(squeeze_slip_mm(ratio * f_hold, mu, m)), abs=1.0)
    assert sim.lift(0.5, 0.2, 2.5) == sim.lift(0.5, 0.2, 2.5)  # bit-identical on repeat


def test_config_errors_name_the_field():
    with pytest.raises(ConfigError, match="sigma"):
        parse_config({"task": "grasp", "model": {"sigma": -2.0}})
    with pytest.raises(ConfigError, match="prior_high"):
        parse_config({"task": "grasp", "model": {"prior_low": [0.2, 0.05], "prior_high": [0.1, 0.5]}})
