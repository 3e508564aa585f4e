"""Probe selectors that read the belief: the next probe chosen for the decision.

The paper holds the probe selector fixed (random or a frozen schedule), so a run's
probes replay under any model. An adaptive selector picks each probe from the grid
by the expected posterior variance of the decision coordinate after observing it,
under the current belief. It is vectorized over candidate probes and particles; a
replay of an adaptive run under another model is *not* an identical-probes
comparison (the other model would have chosen other probes), which the runner says.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from probecommit.core.retained import weighted_variance


def expected_posterior_variance(model: Any, likelihood: Any, particles: np.ndarray, weights: np.ndarray,
                                candidates: np.ndarray, pseudo_truths: int = 32) -> np.ndarray:
    """Expected variance of the decision coordinate after one more probe, per candidate.

    For each candidate ``u`` the observation is drawn, under the belief, as the
    noise-free prediction of ``pseudo_truths`` particles chosen deterministically (the
    heaviest, ties in index order); each pseudo-observation reweights every particle
    by the model's likelihood, and the resulting variances of ``z`` are averaged
    with the pseudo-truths' renormalized weights. Noise-free pseudo-observations make
    the score deterministic, so adaptive rollouts stay reproducible.

    Args:
        model: The task model (``predict``, ``decision``).
        likelihood: The filter's likelihood (``log_likelihood(y[E, m], pred[E, N, m])``).
        particles: ``[E, N, d]``; weights: ``[E, N]`` normalized.
        candidates: ``[P, p]`` candidate probes.
        pseudo_truths: How many heavy particles stand in for the unknown truth.

    Returns:
        ``[E, P]`` expected posterior variance of the decision coordinate (lower is better).
    """
    n_e, n, _ = particles.shape
    m = min(pseudo_truths, n)
    heavy = np.argsort(-weights, axis=1, kind="stable")[:, :m]  # [E, M]
    w_heavy = np.take_along_axis(weights, heavy, axis=1)
    w_heavy = w_heavy / np.maximum(w_heavy.sum(axis=1, keepdims=True), 1e-300)
    z = model.decision(particles)
    out = np.empty((n_e, len(candidates)))
    for c, u in enumerate(np.asarray(candidates, dtype=float)):
        pred = model.predict(np.repeat(u[None, :], n_e, axis=0), particles)  # [E, N, m]
        y = np.take_along_axis(pred, heavy[:, :, None], axis=1)  # [E, M, m] pseudo-observations
        # Likelihood of every particle under every pseudo-observation: [E*M, N].
        flat_y = y.reshape(n_e * m, -1)
        flat_pred = np.repeat(pred, m, axis=0)
        loglik = likelihood.log_likelihood(flat_y, flat_pred).reshape(n_e, m, n)
        log_post = np.log(np.maximum(weights, 1e-300))[:, None, :] + loglik
        log_post -= log_post.max(axis=2, keepdims=True)
        post = np.exp(log_post)
        post /= post.sum(axis=2, keepdims=True)
        var = weighted_variance(np.repeat(z[:, None, :], m, axis=1).reshape(n_e * m, n), post.reshape(n_e * m, n))
        out[:, c] = np.sum(w_heavy * var.reshape(n_e, m), axis=1)
    return out


def choose_probes(scores: np.ndarray) -> np.ndarray:
    """Index of the best candidate per episode: the lowest score, ties to the lowest index."""
    return np.argmin(scores, axis=1)
