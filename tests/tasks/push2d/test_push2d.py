"""push2d: fitted analytic model vs the MuJoCo scene, the fit, determinism, shrinkage, a small study."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")

from probecommit.core.belief import ParticleFilter  # noqa: E402
from probecommit.core.retained import weighted_variance  # noqa: E402
from probecommit.runner.config import parse_config  # noqa: E402
from probecommit.runner.study import run_study  # noqa: E402
from probecommit.tasks.push2d.model import FITTED_MU_SCALE, Push2DModel, rest_position  # noqa: E402
from probecommit.tasks.push2d.sim_mujoco import FIT_TRUTHS, MujocoPush2DSimulator, fit_friction_scale  # noqa: E402

pytestmark = pytest.mark.mujoco

EVAL_TRUTHS = [(0.25, 0.625, 0.8125), (0.4, 1.0, 1.75), (0.55, 1.375, 2.6875)]


@pytest.fixture(scope="module")
def sim() -> MujocoPush2DSimulator:
    return MujocoPush2DSimulator(noise_sigma=0.0)


def test_fit_reproduces_the_frozen_friction_factor(sim):
    fit = fit_friction_scale(sim)
    assert fit["n"] == 6
    assert fit["mu_scale"] == pytest.approx(FITTED_MU_SCALE, abs=1e-4)
    assert fit["rms_after"] < 0.2e-3 < fit["rms_before"]  # measured: 0.49 mm -> 0.07 mm
    assert not set(map(tuple, FIT_TRUTHS)) & set(EVAL_TRUTHS)


@pytest.mark.parametrize("theta", EVAL_TRUTHS)
def test_fitted_model_matches_the_engine_on_held_out_probes_and_pushes(sim, theta):
    # Held out from the fit: evaluation truths, bearings off +x, larger impulses.
    # Measured over these and the two prior corners: max 2.0 mm, mean 0.33 mm, max 0.14% of the distance.
    model = Push2DModel()
    for bearing in (0.0, -20.0, 30.0, 45.0):
        for j in (1.0, 2.0, 3.0, 5.0):
            a = j * np.array([np.cos(np.deg2rad(bearing)), np.sin(np.deg2rad(bearing))])
            engine = sim.rest(*theta, *a)
            analytic = rest_position(a, theta[0], theta[1], theta[2], model.mu_scale)
            assert np.linalg.norm(engine - analytic) < max(2.5e-3, 2e-3 * np.linalg.norm(analytic))


def test_each_query_starts_from_the_start_pose(sim):
    theta = EVAL_TRUTHS[1]
    first = sim.rest(*theta, 2.0, 0.0)
    sim.rest(*theta, 0.5, 1.5)  # another push in between
    assert np.array_equal(sim.rest(*theta, 2.0, 0.0), first)


def test_same_seed_gives_bit_identical_readings_and_outcomes():
    theta = np.array(EVAL_TRUTHS[0])
    target = np.array([0.939693, -0.342020])

    def run(seed):
        s, rng = MujocoPush2DSimulator(), np.random.default_rng(seed)
        ys = [s.probe(theta, np.array([u]), rng) for u in (1.0, 3.0, 2.0)]
        return np.concatenate(ys), s.execute(theta, np.array([1.2, -0.4]), target)["realized"], s.engine_calls

    a, b = run(7), run(7)
    assert np.array_equal(a[0], b[0]) and a[1] == b[1]
    assert a[2] == {"rest": 4}  # three distinct probes + one push, each run once


def test_probes_shrink_posterior_variance(sim):
    model = Push2DModel()
    theta = np.array(EVAL_TRUTHS[1])
    pf = ParticleFilter.gaussian(model, model.sigma, n_particles=1024)
    noisy = MujocoPush2DSimulator()
    rng, rngs = np.random.default_rng(3), [np.random.default_rng(4)]
    state = pf.initial(rngs)
    action = np.array([[2.0 * np.cos(0.5), 2.0 * np.sin(0.5)]])

    def var(s):
        miss = model.loss(action, s.particles, np.array([[1.0, 0.0]]))[:, 0]
        return weighted_variance(miss, s.weights)[0]

    v0 = var(state)
    for u in (1.0, 2.0, 3.0, 2.0, 3.0):
        state = pf.update(state, np.array([u]), noisy.probe(theta, np.array([u]), rng)[None], rngs)
    assert var(state) < 0.05 * v0


def test_small_study_has_blind_and_probe_rows(tmp_path):
    config = parse_config({
        "name": "push2d-small", "task": "push2d", "seed": 1, "repeats": 2,
        "instances": {"split": "t", "truths": [[0.4, 1.0, 1.75]], "contexts": [[0.939693, -0.342020], [0.433013, 0.25]]},
        "probes": {"schedule": "random", "budget": 5, "budgets": [2, 5]},
        "belief": {"particles": 128}, "simulator": {"engine": "mujoco"},
        "blind_prior_samples": 500, "unit_instances": 1,
    })
    res = run_study(config, tmp_path / "run")
    ep = res.episodes
    assert set(zip(ep["method"], ep["k"])) == {("blind_bayes", 0), ("blind_robust", 0), ("probe_robust", 2), ("probe_robust", 5)}
    assert len(ep) == 2 * 2 * 4 and np.all(np.isfinite(ep["realized"])) and (ep["status"] == "ok").all()
    assert ep[ep["k"] == 5]["realized"].mean() < ep[ep["method"] == "blind_robust"]["realized"].mean()


def test_loss_in_place_equals_the_closed_form_expression_bit_for_bit():
    """The loss computed in place (memory) gives exactly the expression's values, for [S, d] and [E, N, d]."""
    from probecommit.tasks.push1d.model import stop_distance

    model = Push2DModel()
    rng = np.random.default_rng(5)
    grid = np.asarray(model.action_grid, dtype=float)
    mag = np.hypot(grid[:, 0], grid[:, 1])
    unit = grid / np.where(mag > 0, mag, 1.0)[:, None]

    def reference(d, t_sq, along):
        return np.sqrt(np.maximum(d * d + t_sq - 2.0 * d * along, 0.0)) / model.margin

    theta = model.sample_prior(rng, 300)
    t = np.array([0.9, -0.3])
    d = stop_distance(mag[:, None], model.mu_scale * theta[None, :, 0], theta[None, :, 1], theta[None, :, 2])
    assert np.array_equal(model.loss(grid, theta, t), reference(d, float(t @ t), (unit @ t)[:, None]))
    theta3 = model.sample_prior(rng, 3 * 64).reshape(3, 64, -1)
    targets = rng.uniform(-1.5, 1.5, size=(3, 2))
    d3 = stop_distance(mag[None, :, None], model.mu_scale * theta3[:, None, :, 0], theta3[:, None, :, 1], theta3[:, None, :, 2])
    want = reference(d3, np.sum(targets * targets, axis=1)[:, None, None], (targets @ unit.T)[:, :, None])
    assert np.array_equal(model.loss(grid, theta3, targets), want)
