"""Conformance suite: every registered (family, engine) honours the contract.

For each family: the model satisfies the ``TaskModel`` Protocol and its shapes agree;
a one-particle belief commits to the model's optimum for that particle. For each
(family, engine) with the engine installed: the same seed gives identical episodes,
and a rollout replayed under the same model reproduces its episodes exactly.
"""

from __future__ import annotations

import importlib.util

import numpy as np
import pandas as pd
import pytest

from probecommit.core.belief import ParticleFilter
from probecommit.core.executors import ProbeRobust, grown_set, retained_scores, scenario_scores, select_action
from probecommit.runner.config import parse_config
from probecommit.runner.replay import load_run, replay_episodes
from probecommit.runner.study import run_study
from probecommit.tasks.base import Simulator, TaskModel
from probecommit.tasks.registry import build_simulator, families

FAMILIES = sorted(families())
PAIRS = [(name, engine) for name in FAMILIES for engine in families()[name].engines]


def _deep_merge(base: dict, extra: dict) -> dict:
    out = dict(base)
    for key, value in extra.items():
        out[key] = _deep_merge(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) else value
    return out


def small_config(family: str, engine: str, name: str = "conf"):
    spec = families()[family]
    data = {
        "name": name, "task": family, "seed": 11, "repeats": 2,
        "instances": {"split": "conf", "count": 2, "seed": 5},
        "probes": {"schedule": "random", "budget": 2},
        "belief": {"particles": 64},
        "simulator": {"engine": engine},
        "blind_prior_samples": 500,
    }
    return parse_config(_deep_merge(_deep_merge(data, spec.example), {"simulator": {"engine": engine}}))


def _needs(engine: str) -> None:
    if engine != "analytic" and importlib.util.find_spec(engine) is None:
        pytest.skip(f"{engine} not installed")


@pytest.mark.parametrize("family", FAMILIES)
def test_model_satisfies_the_protocol_and_shapes_agree(family):
    spec = families()[family]
    model = spec.build_model(spec.config())
    assert isinstance(model, TaskModel)
    d, p, a = len(model.latent_names), model.probe_dim, model.action_dim
    P, A = np.asarray(model.probe_grid).shape, np.asarray(model.action_grid).shape
    assert P[1] == p and A[1] == a and P[0] >= 1 and A[0] >= 1
    assert np.asarray(model.prior_low).shape == (d,) == np.asarray(model.jitter_scale).shape
    rng = np.random.default_rng(0)
    theta = np.stack([model.sample_prior(rng, 7) for _ in range(3)])  # [E=3, N=7, d]
    assert np.all((theta >= model.prior_low) & (theta <= model.prior_high))
    u = np.asarray(model.probe_grid)[:3]
    y = model.predict(u, theta)
    assert y.shape == (3, 7, model.observation_dim) and np.all(np.isfinite(y))
    context = np.zeros((3, len(model.context_names))) + 0.5 if model.context_names else None
    loss = model.loss(model.action_grid, theta, context)
    assert loss.shape == (3, A[0], 7)
    assert loss.dtype == bool if model.binary_loss else np.all(loss >= 0)
    assert model.decision(theta).shape == (3, 7)
    ref = theta.mean(axis=1)
    assert model.tie_break_cost(model.action_grid, ref, context).shape == (3, A[0])
    # Grown-set points across the belief's own decision range map back to those coordinates.
    z = model.decision(theta)
    points = z.min(axis=1, keepdims=True) + (z.max(axis=1, keepdims=True) - z.min(axis=1, keepdims=True)) * np.linspace(0, 1, 9)
    grown = model.grown_scenarios(theta, points)
    assert grown.shape == (3, 9, d)
    np.testing.assert_allclose(model.decision(grown), points, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("family", FAMILIES)
def test_one_particle_belief_commits_to_that_particles_optimum(family):
    spec = families()[family]
    model = spec.build_model(spec.config())
    rng = np.random.default_rng(1)
    theta = model.sample_prior(rng, 5)[:, None, :]  # five episodes, one particle each
    context = model.sample_prior(rng, 5)[:, :len(model.context_names)] * 0 + 0.7 if model.context_names else None
    chosen = ProbeRobust(model).act(theta, np.ones((5, 1)), 0.8, context)
    loss = model.loss(model.action_grid, theta, context)[:, :, 0].astype(float)
    np.testing.assert_array_equal(chosen.score, loss.min(axis=1))
    np.testing.assert_array_equal(loss[np.arange(5), chosen.index], loss.min(axis=1))


@pytest.mark.parametrize("family", FAMILIES)
@pytest.mark.parametrize("margin", [1.0, 0.8])
def test_grown_set_scored_in_blocks_equals_its_scenarios_scored_at_once(family, margin):
    """A grown set (t > 1) scores its particles and its added points as two blocks, copying neither:
    the scores, the action and its score are those of scoring the concatenated scenarios."""
    spec = families()[family]
    model = spec.build_model(spec.config()).with_margin(margin)
    rng = np.random.default_rng(2)
    theta = np.stack([model.sample_prior(rng, 40) for _ in range(4)])  # [E=4, N=40, d]
    weights = rng.random((4, 40))
    weights /= weights.sum(axis=1, keepdims=True)
    context = np.zeros((4, len(model.context_names))) + 0.6 if model.context_names else None
    executor = ProbeRobust(model)
    retained = executor.retain(theta, weights, 1.3)
    assert retained.grown is not None and retained.particles is theta  # no copy of the particles
    scenarios, lo, hi = grown_set(model, theta, 1.3)
    at_once = scenario_scores(model, scenarios, np.ones(scenarios.shape[:2], dtype=bool), context)
    np.testing.assert_array_equal(retained_scores(model, retained, context), at_once)
    np.testing.assert_array_equal(retained.scenarios, scenarios)
    chosen = executor.choose(retained, context)
    expected = select_action(at_once, model.tie_break_cost(model.action_grid, retained.reference, context))
    np.testing.assert_array_equal(chosen.index, expected)
    np.testing.assert_array_equal(chosen.score, at_once[np.arange(4), expected])
    np.testing.assert_array_equal(chosen.lo, lo)
    np.testing.assert_array_equal(chosen.hi, hi)


@pytest.mark.parametrize("family,engine", PAIRS)
def test_simulator_satisfies_the_protocol(family, engine):
    _needs(engine)
    config = small_config(family, engine)
    sim = build_simulator(family, config.task)
    assert isinstance(sim, Simulator) and sim.engine == engine


@pytest.mark.parametrize("family,engine", PAIRS)
def test_same_seed_identical_episodes_and_exact_replay(family, engine, tmp_path):
    _needs(engine)
    config = small_config(family, engine)
    a = run_study(config, tmp_path / "a").episodes
    b = run_study(config, tmp_path / "b").episodes
    pd.testing.assert_frame_equal(a, b)
    assert (a["status"] == "ok").all() and len(a) > 0
    replayed, _ = replay_episodes(load_run(tmp_path / "a"))
    pd.testing.assert_frame_equal(replayed.reset_index(drop=True), a.reset_index(drop=True), check_dtype=False)


@pytest.mark.parametrize("family", FAMILIES)
def test_filter_runs_on_the_model_shapes(family):
    spec = families()[family]
    model = spec.build_model(spec.config())
    pf = ParticleFilter.gaussian(model, model.sigma, n_particles=32)
    rngs = [np.random.default_rng(i) for i in range(2)]
    state = pf.initial(rngs)
    u = np.asarray(model.probe_grid)[[0, -1]]
    y = model.predict(u, state.particles[:, :1])[:, 0]
    new = pf.update(state, u, y, rngs)
    assert new.particles.shape == state.particles.shape and np.all(np.isfinite(new.log_weights).any(axis=1))
