"""Insertion's model: reweighting by reading level equals predicting every particle (compiled and NumPy)."""

import numpy as np
import pytest

from probecommit.core.likelihood import GaussianLikelihood, TemperedLikelihood
from probecommit.tasks.insertion.model import InsertionModel
from probecommit.tasks.rig.model import RigModel

MODELS = [InsertionModel.deployed(), InsertionModel.corrected(), RigModel()]


@pytest.mark.parametrize("model", MODELS, ids=lambda m: f"{type(m).__name__}-{m.variant}")
@pytest.mark.parametrize("temperature", [None, 4.0])
def test_reading_levels_reweight_as_predicting_every_particle(model, temperature, monkeypatch):
    """Per-level log-likelihoods picked per particle (compiled and NumPy) equal predicting every particle."""
    rng = np.random.default_rng(11)
    e, n = 7, 301
    low, high = np.asarray(model.prior_low), np.asarray(model.prior_high)
    theta = low + (high - low) * rng.random((e, n, 2))
    u = rng.choice(np.asarray(model.probe_grid)[:, 0], e)
    theta[:, :5, 0] = u[:, None] + rng.uniform(-1, 1, (e, 5)) * 0.2 + 4.0  # near the boundary
    y = np.column_stack([np.where(rng.random(e) < 0.5, model.reading_levels[0], 0.0) + 0.5 * rng.standard_normal(e)])
    likelihood = GaussianLikelihood(model.sigma)
    if temperature:
        likelihood = TemperedLikelihood(likelihood, temperature)
    log_w = np.log(rng.dirichlet(np.ones(n), e))
    pred = model.predict(u, theta)
    assert set(np.unique(pred)) <= set(model.reading_levels)
    expected = log_w + likelihood.log_likelihood(y, pred)
    level_pred = np.empty((e, 2, 1))
    level_pred[:, :, 0] = model.reading_levels
    level_ll = likelihood.log_likelihood(y, level_pred)
    assert np.array_equal(model.add_reading_log_likelihood(u, theta, log_w, level_ll), expected)
    monkeypatch.setenv("PROBECOMMIT_KERNELS", "numpy")  # the NumPy path, the same bits
    assert np.array_equal(model.add_reading_log_likelihood(u, theta, log_w, level_ll), expected)
