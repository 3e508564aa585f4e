"""The rig family: scaled geometry, touch-switch hand cases, MuJoCo against the closed form."""

from __future__ import annotations

import numpy as np
import pytest

from probecommit.runner.config import ConfigError, parse_config
from probecommit.tasks.insertion.model import InsertionModel
from probecommit.tasks.rig.model import ALLOWANCE_MM, RIG_SCALE, TOOL_RADIUS_MM, RigModel, rig_half_gap, rig_window
from probecommit.tasks.rig.sim_base import AnalyticRigSimulator

mujoco = pytest.importorskip("mujoco")
from probecommit.tasks.rig.sim_mujoco import MujocoRigSimulator  # noqa: E402


def test_geometry_is_the_simulation_at_rig_scale():
    rig, sim = RigModel(), InsertionModel()
    np.testing.assert_allclose(rig.probe_grid, RIG_SCALE * sim.probe_grid)
    np.testing.assert_allclose(rig.action_grid, RIG_SCALE * sim.action_grid)
    assert rig.decision_domain_width == pytest.approx(20 * RIG_SCALE)
    # The paper's 6.57 mm window at c = 1 and the prior-to-window ratio of 5.9.
    assert float(rig_window(1.0)) == pytest.approx(6.562, abs=1e-3)
    assert (rig.prior_high[0]) / float(rig_window(1.0)) == pytest.approx(10 / 1.7)


@pytest.mark.parametrize("sim_class", [AnalyticRigSimulator, MujocoRigSimulator])
def test_touch_switch_hand_cases(sim_class):
    sim = sim_class(misread_rate=0.0)
    x, c = 3.0, 1.0
    fits = float(rig_half_gap(c)) - TOOL_RADIUS_MM  # 14.81 mm
    assert sim.tap_reading(x, c, x) == -ALLOWANCE_MM  # centred: through the opening
    assert sim.tap_reading(x, c, x + fits - 0.05) == -ALLOWANCE_MM
    assert sim.tap_reading(x, c, x + fits + 0.05) == 0.0  # the tool's edge lands on the block
    assert sim.tap_reading(x, c, x - 30.0) == 0.0  # over the block
    assert sim.tool_depth(x, c, x) > 0.6 * 15 * RIG_SCALE  # a centred tool enters
    assert sim.tool_depth(x, c, x + 20.0) == 0.0


def test_mujoco_rig_matches_the_closed_form_on_a_grid():
    mj, an = MujocoRigSimulator(misread_rate=0.0), AnalyticRigSimulator(misread_rate=0.0)
    for x, c in ((0.0, 0.7), (-21.3, 1.0), (30.2, 1.3)):
        for u in RigModel.probe_grid[:, 0]:
            assert mj.tap_reading(x, c, u) == an.tap_reading(x, c, u)
        for a in RigModel.action_grid[::4, 0]:
            assert (mj.tool_depth(x, c, a) > 0) == (an.tool_depth(x, c, a) > 0)


def test_instances_sharing_one_data_buffer_answer_as_alone():
    """A simulator's instances share one MjData (their compiled models are process-wide);
    interleaving instances changes no answer."""
    rng = np.random.default_rng(5)
    model = RigModel()
    truths = rng.uniform(model.prior_low, model.prior_high, (5, 2))
    queries = [(x, c, kind, q) for x, c in truths for kind in ("tap_reading", "tool_depth")
               for q in (x + rng.uniform(-20, 20), rng.uniform(model.prior_low[0], model.prior_high[0]))]
    alone = [getattr(MujocoRigSimulator(misread_rate=0.0), kind)(x, c, q) for x, c, kind, q in queries]  # fresh buffers
    shared = MujocoRigSimulator(misread_rate=0.0)
    interleaved = {int(i): getattr(shared, queries[i][2])(queries[i][0], queries[i][1], queries[i][3])
                   for i in rng.permutation(len(queries))}
    assert [interleaved[i] for i in range(len(queries))] == alone
    for kind in ("tap_reading", "tool_depth"):  # not a trivial check: each query kind gets both outcomes
        assert len({a < 0 if kind == "tap_reading" else a > 0
                    for (_, _, k, _), a in zip(queries, alone) if k == kind}) == 2
    assert len(shared._data) == 1  # one layout, one buffer


def test_model_agrees_with_the_simulated_rig_as_deployed():
    model, sim = RigModel(), AnalyticRigSimulator(misread_rate=0.0)
    theta = np.array([[[4.0, 0.9]]])
    for u in model.probe_grid[:, 0]:
        assert model.predict(np.array([[u]]), theta)[0, 0, 0] == sim.tap_reading(4.0, 0.9, u)


def test_realized_failure_is_the_window_and_entry_is_kept_beside_it():
    sim = AnalyticRigSimulator(misread_rate=0.0)
    theta = np.array([0.0, 1.0])
    inside = sim.execute(theta, np.array([6.0]))
    outside = sim.execute(theta, np.array([10.0]))
    assert inside["realized"] == 0.0 and inside["entered"]
    assert outside["realized"] == 1.0 and outside["entered"]  # enters, but outside the model's window
    assert sim.execute(theta, np.array([20.0]))["entered"] is False


def test_misreads_flip_at_the_configured_rate_and_are_deterministic():
    sim = AnalyticRigSimulator(misread_rate=0.2)
    theta, u = np.array([0.0, 1.0]), np.array([0.0])
    draws = [sim.probe(theta, u, np.random.default_rng([5, i]))[0] for i in range(2000)]
    again = [sim.probe(theta, u, np.random.default_rng([5, i]))[0] for i in range(2000)]
    assert draws == again
    assert np.mean(np.array(draws) == 0.0) == pytest.approx(0.2, abs=0.03)


def test_config_errors_name_the_field():
    base = {"task": "rig", "simulator": {"engine": "analytic"}}
    with pytest.raises(ConfigError, match="sigma"):
        parse_config({**base, "model": {"sigma": -0.5}})
    with pytest.raises(ConfigError, match="misread_rate"):
        parse_config({**base, "simulator": {"engine": "analytic", "misread_rate": 1.5}})
    with pytest.raises(ConfigError, match="prior_low"):
        parse_config({**base, "model": {"prior_low": [-900.0, 0.7], "prior_high": [38.6, 1.3]}})
