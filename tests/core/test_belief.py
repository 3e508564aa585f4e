"""The batched particle filter against exact grid posteriors, and resampling."""

from dataclasses import dataclass, field

import numpy as np
import pytest

from probecommit.core.belief import ParticleFilter, effective_sample_size, normalize_log_weights, systematic_resample
from probecommit.core.likelihood import GaussianLikelihood


@dataclass
class ToyModel:
    """y = theta_0^2 + u * theta_0 (+ theta_1 * u^2 in 2-D), Gaussian noise."""

    d: int = 1
    prior_low: np.ndarray = field(default=None)
    prior_high: np.ndarray = field(default=None)
    jitter_scale: np.ndarray = field(default=None)
    reading_levels = None  # ForwardModel: no few-level fast path

    def __post_init__(self):
        self.prior_low = np.zeros(self.d)
        self.prior_high = np.ones(self.d)
        self.jitter_scale = np.full(self.d, 0.01)

    def predict(self, u, theta):
        u = np.asarray(u, float).reshape(theta.shape[0], 1)
        y = theta[..., 0] ** 2 + u * theta[..., 0]
        if self.d == 2:
            y = y + theta[..., 1] * u**2
        return y[..., None]


SIGMA = 0.15
PROBES = np.array([0.3, -0.8, 1.0, 0.5])


def grid_posterior(model, truth, y, bins):
    """Exact posterior on a fine grid, summed into ``bins`` per coordinate."""
    fine = 400 if model.d == 1 else 200
    axes = [(np.arange(fine) + 0.5) / fine] * model.d
    mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(1, -1, model.d)
    logp = np.zeros(mesh.shape[1])
    lik = GaussianLikelihood(SIGMA)
    for u, yj in zip(PROBES, y):
        logp += lik.log_likelihood(np.array([[yj]]), model.predict(np.array([u]), mesh))[0]
    p = np.exp(logp - logp.max())
    p /= p.sum()
    return np.histogramdd(mesh[0], bins=[bins] * model.d, range=[(0, 1)] * model.d, weights=p)[0]


def particle_histogram(state, bins, d):
    return np.histogramdd(state.particles[0], bins=[bins] * d, range=[(0, 1)] * d, weights=state.weights[0])[0]


@pytest.mark.parametrize("d,bins", [(1, 20), (2, 6)])
def test_belief_matches_grid_posterior_and_improves_with_n(d, bins):
    model = ToyModel(d)
    truth = np.full(d, 0.62)
    noise_rng = np.random.default_rng(0)
    y = model.predict(PROBES, np.repeat(truth[None, None, :], len(PROBES), axis=0))[:, 0, 0]
    y = y + SIGMA * noise_rng.standard_normal(len(y))
    exact = grid_posterior(model, truth, y, bins)
    tv = {}
    for n in (256, 8192):
        dists = []
        for seed in range(8):
            # No jitter: the bootstrap filter is then a consistent estimate of the exact posterior.
            pf = ParticleFilter.gaussian(model, SIGMA, n_particles=n, jitter=False)
            rngs = [np.random.default_rng(seed)]
            state = pf.initial(rngs)
            for u, yj in zip(PROBES, y):
                state = pf.update(state, np.array([u]), np.array([[yj]]), rngs)
            dists.append(0.5 * np.abs(particle_histogram(state, bins, d) - exact).sum())
        tv[n] = float(np.mean(dists))
    assert tv[8192] < 0.05
    assert tv[8192] < 0.6 * tv[256]


def test_batched_update_equals_per_episode_updates():
    model = ToyModel(2)
    pf = ParticleFilter.gaussian(model, SIGMA, n_particles=300)
    seeds = [3, 4, 5]
    batched_rngs = [np.random.default_rng(s) for s in seeds]
    state = pf.initial(batched_rngs)
    ys = np.array([[0.1], [0.9], [0.5]])
    for u in PROBES:
        state = pf.update(state, np.full(3, u), ys, batched_rngs)
    for e, s in enumerate(seeds):
        rngs = [np.random.default_rng(s)]
        single = pf.initial(rngs)
        for u in PROBES:
            single = pf.update(single, np.array([u]), ys[e : e + 1], rngs)
        np.testing.assert_array_equal(single.particles[0], state.particles[e])
        np.testing.assert_array_equal(single.log_weights[0], state.log_weights[e])


def test_update_reports_the_log_predictive_it_normalized_with():
    model = ToyModel(2)
    pf = ParticleFilter.gaussian(model, SIGMA, n_particles=300)
    rngs = [np.random.default_rng(s) for s in (1, 2, 3)]
    state = pf.initial(rngs)
    ys = np.array([[0.1], [0.9], [1e200]])  # the last is impossible to every particle (-inf): a reset
    for u in PROBES:
        before = pf.log_predictive(state, np.full(3, u), ys)
        state = pf.update(state, np.full(3, u), ys, rngs)
        np.testing.assert_array_equal(state.log_evidence, before)
        np.testing.assert_array_equal(state.lost, ~np.isfinite(before))
    assert state.lost[2] and not state.lost[0]


def test_systematic_resampling_is_unbiased():
    rng = np.random.default_rng(1)
    w = rng.dirichlet(np.ones(7))
    n = 7
    draws = 20000
    idx = systematic_resample(np.tile(w, (draws, 1)), rng.random(draws))
    counts = np.stack([np.bincount(row, minlength=n) for row in idx])
    np.testing.assert_allclose(counts.mean(axis=0), n * w, atol=0.03)
    # Systematic resampling: every count is floor or ceil of N w_i.
    assert np.all(counts >= np.floor(n * w) - 1e-9) and np.all(counts <= np.ceil(n * w) + 1e-9)
    assert np.all(np.diff(idx, axis=1) >= 0)


def test_systematic_resampling_degenerate_weights():
    w = np.zeros((2, 5))
    w[0, 3] = 1.0
    w[1, [0, 4]] = 0.5
    idx = systematic_resample(w, np.array([0.999, 0.0]))
    assert idx[0].tolist() == [3] * 5
    assert set(idx[1].tolist()) <= {0, 4}


def test_all_impossible_particles_reset_to_uniform():
    logw = np.array([[-np.inf, -np.inf], [0.0, -np.inf]])
    out = normalize_log_weights(logw)
    np.testing.assert_allclose(np.exp(out), [[0.5, 0.5], [1.0, 0.0]])
    np.testing.assert_allclose(effective_sample_size(np.exp(out)), [2.0, 1.0])


def test_resampling_triggers_below_half_ess_and_resets_weights():
    model = ToyModel(1)
    pf = ParticleFilter.gaussian(model, 0.01, n_particles=200)
    rngs = [np.random.default_rng(0)]
    state = pf.initial(rngs)
    state = pf.update(state, np.array([0.0]), np.array([[0.25]]), rngs)
    assert state.resampled[0]
    np.testing.assert_allclose(state.weights[0], 1 / 200)
    assert np.all((state.particles >= 0) & (state.particles <= 1))
    # The weights are exp(log-weights), bit for bit, in the rows that resampled and the rows that did not.
    pf = ParticleFilter.gaussian(model, 0.2, n_particles=200)
    rngs = [np.random.default_rng(s) for s in range(6)]
    state = pf.initial(rngs)
    state = pf.update(state, np.zeros(6), np.array([[0.3], [0.0], [0.9], [0.3], [1.0], [0.5]]), rngs)
    assert 0 < state.resampled.sum() < 6
    assert np.exp(state.log_weights).tobytes() == state.weights.tobytes()


def test_rejects_bad_sigma():
    with pytest.raises(ValueError, match="sigma"):
        GaussianLikelihood(-0.5)


class _OpaqueGaussian:
    """A Gaussian likelihood the filter cannot see inside (no ``arithmetic``): the generic path."""

    def __init__(self, sigma):
        self.inner = GaussianLikelihood(sigma)

    def log_likelihood(self, y, pred):
        return self.inner.log_likelihood(y, pred)


def _two_level_models():
    from probecommit.tasks.insertion.model import InsertionModel
    from probecommit.tasks.rig.model import RigModel

    return [InsertionModel.deployed(), InsertionModel.corrected(), RigModel()]


@pytest.mark.parametrize("model", _two_level_models(), ids=lambda m: f"{type(m).__name__}-{m.variant}")
def test_filter_with_reading_levels_equals_the_generic_update(model):
    """Eight updates (with resampling) through the level path give the generic path's states bit for bit."""
    rng = np.random.default_rng(2)
    e = 9
    truths = np.column_stack([rng.uniform(-8, 8, e), rng.uniform(0.75, 1.25, e)])
    fast = ParticleFilter.gaussian(model, model.sigma, n_particles=256)
    generic = ParticleFilter(model=model, likelihood=_OpaqueGaussian(model.sigma), n_particles=256)
    rngs_a = [np.random.default_rng(s) for s in range(e)]
    rngs_b = [np.random.default_rng(s) for s in range(e)]
    a, b = fast.initial(rngs_a), generic.initial(rngs_b)
    resampled = 0
    for _ in range(8):
        u = rng.choice(np.asarray(model.probe_grid)[:, 0], e)
        y = model.predict(u, truths[:, None, :])[:, 0, :] + 0.5 * rng.standard_normal((e, 1))
        a, b = fast.update(a, u, y, rngs_a), generic.update(b, u, y, rngs_b)
        resampled += int(a.resampled.sum())
        for name in ("particles", "log_weights", "log_evidence", "resampled", "lost"):
            assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert resampled > 0
