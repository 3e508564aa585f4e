"""A hand-checkable 1-D tap model and tap batch for the band-replay tests (ex21, ex24): a tap reads one of two
levels, so which particles a reading contradicts, and what a resampling keeps, can be worked out by hand."""

from types import SimpleNamespace

import numpy as np


class TwoLevels:
    """A 1-D model: a tap at ``u`` reads 0 (pocket) when ``|u - x| < 1``, else 10 (top); jitter scale ``jitter``."""

    prior_low, prior_high = np.array([-5.0]), np.array([5.0])
    reading_levels = (0.0, 10.0)

    def __init__(self, jitter: float = 0.5):
        self.jitter_scale = np.array([jitter])

    def predict(self, u, theta):
        u = np.asarray(u, float).reshape(-1, 1)
        return np.where(np.abs(u - theta[..., 0]) < 1.0, 0.0, 10.0)[..., None]

    def add_reading_log_likelihood(self, u, theta, log_weights, level_ll):
        top = self.predict(u, theta)[..., 0] == 10.0
        return log_weights + np.where(top, level_ll[:, 1:2], level_ll[:, 0:1])


def tap_batch(u, y):
    """Taps ``u`` and readings ``y`` ``[E, k]`` as the filter's batch reads them."""
    u, y = np.asarray(u, float), np.asarray(y, float)
    return SimpleNamespace(u=u[..., None], y=y[..., None], n_episodes=u.shape[0])
