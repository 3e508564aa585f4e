"""Top-weight retained sets and decision-coordinate intervals.

The retained set at mass ``nu`` is the shortest prefix of the particles sorted by
descending weight (stable: ties in particle-index order) whose cumulative mass
reaches ``nu``. Sets are nested in ``nu``. Right after a resampling all weights tie,
so the prefix is the first ``ceil(nu * N)`` copies in parent order.
"""

from __future__ import annotations

import numpy as np

# Cumulative sums of float weights may fall a hair short of an exactly reachable
# mass (e.g. 820 copies of 1/1024 against nu = 0.8); this tolerance absorbs that.
MASS_TOLERANCE = 1e-12


def weight_order(weights: np.ndarray) -> np.ndarray:
    """Particle indices sorted by descending weight, ties in index order ``[E, N]``."""
    return np.argsort(-np.asarray(weights), axis=-1, kind="stable")


def prefix_mass(weights: np.ndarray, order: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Sorted order and cumulative mass ``W_m`` of the first ``m+1`` particles."""
    if order is None:
        order = weight_order(weights)
    return order, np.cumsum(np.take_along_axis(weights, order, axis=-1), axis=-1)


def retained_count(weights: np.ndarray, nu: float | np.ndarray, order: np.ndarray | None = None) -> np.ndarray:
    """Size ``m(nu)`` of the shortest prefix reaching mass ``nu`` per episode ``[E]``."""
    _, cum = prefix_mass(weights, order)
    nu = np.broadcast_to(np.asarray(nu, dtype=float), cum.shape[:-1])
    reached = cum >= (nu[..., None] - MASS_TOLERANCE)
    count = np.argmax(reached, axis=-1) + 1
    # Mass never reached (nu > 1): keep everything.
    return np.where(reached.any(axis=-1), count, cum.shape[-1])


def retained_mask(weights: np.ndarray, nu: float | np.ndarray) -> np.ndarray:
    """Boolean mask ``[E, N]`` of the retained top-weight ``nu``-mass subset."""
    weights = np.asarray(weights, dtype=float)
    order = weight_order(weights)
    count = retained_count(weights, nu, order)
    rank_kept = np.arange(weights.shape[-1])[None, :] < count[:, None]
    mask = np.zeros_like(rank_kept)
    np.put_along_axis(mask, order, rank_kept, axis=-1)
    return mask


def masked_interval(z: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Range ``[lo, hi]`` of ``z[E, N]`` over ``mask[E, N]`` per episode."""
    lo = np.min(np.where(mask, z, np.inf), axis=-1)
    hi = np.max(np.where(mask, z, -np.inf), axis=-1)
    return lo, hi


def weighted_mean(z: np.ndarray, weights: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
    """Weighted mean of ``z`` over ``mask`` (all particles if None) ``[E]``."""
    w = weights if mask is None else np.where(mask, weights, 0.0)
    return _weighted_mean(z, w, np.sum(w, axis=-1), mask)


def _weighted_mean(z: np.ndarray, w: np.ndarray, total: np.ndarray, mask: np.ndarray | None) -> np.ndarray:
    """:func:`weighted_mean` from the masked weights ``w`` and their sum ``total`` (shared by every
    latent of :func:`belief_reference`). The unweighted fallback is computed only for the rows that
    need it (every row's value where one does: the same numbers as computing it always)."""
    positive = total > 0
    weighted = np.sum(w * z, axis=-1) / np.where(positive, total, 1.0)
    if positive.all():
        return weighted
    # A retained set of zero-weight particles only: fall back to the unweighted mean.
    plain = np.sum(np.where(mask, z, 0.0), axis=-1) / np.maximum(np.sum(mask, axis=-1), 1) if mask is not None else np.mean(z, axis=-1)
    return np.where(positive, weighted, plain)


def belief_reference(particles: np.ndarray, weights: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
    """Weighted mean of every latent over ``mask`` ``[E, d]``: the executors' tie-break reference
    (the masked weights and their sum formed once for every latent)."""
    w = weights if mask is None else np.where(mask, weights, 0.0)
    total = np.sum(w, axis=-1)
    return np.stack([_weighted_mean(particles[..., j], w, total, mask) for j in range(particles.shape[-1])], axis=-1)


def retained_summary(weights: np.ndarray, nu: float | np.ndarray, z: np.ndarray,
                     particles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The retained set at mass ``nu`` with what an executor needs from it, in one pass.

    Args:
        weights: Normalized weights ``[E, N]``.
        nu: Retained mass, one for all episodes or ``[E]``.
        z: Decision coordinate of every particle ``[E, N]``.
        particles: ``[E, N, d]``.

    Returns:
        ``(mask, lo, hi, reference)``: :func:`retained_mask`, the decision interval over
        it (:func:`masked_interval`) and the weighted mean of every latent over it
        (:func:`belief_reference`).
    """
    weights = np.asarray(weights, dtype=float)
    mask = retained_mask(weights, np.broadcast_to(np.asarray(nu, dtype=float), weights.shape[:1]))
    lo, hi = masked_interval(z, mask)
    return mask, lo, hi, belief_reference(particles, weights, mask)


def weighted_variance(z: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Posterior variance of ``z[E, N]`` under normalized ``weights`` ``[E, N]``, per episode ``[E]``."""
    mean = np.sum(weights * z, axis=-1)
    return np.sum(weights * (z - mean[:, None]) ** 2, axis=-1)


def coverage_score(z: np.ndarray, weights: np.ndarray, z_true: np.ndarray, domain_width: float) -> np.ndarray:
    """Coverage score per episode.

    Args:
        z: Decision coordinate of every particle ``[E, N]``.
        weights: Normalized weights ``[E, N]``.
        z_true: True decision coordinate ``[E]``.
        domain_width: ``D``, the decision domain width that scales distance past the hull.

    Returns:
        ``[E]`` scores; ``<= 1`` when the truth is inside the hull (clipped at 1
        against round-off), ``1 + d / D`` exactly when it escapes.
    """
    return coverage_with_hull(z, weights, z_true, domain_width)[0]


def coverage_with_hull(z: np.ndarray, weights: np.ndarray, z_true: np.ndarray,
                       domain_width: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`coverage_score` and the hull ``(min z, max z)`` per episode.

    The score is the mass of the shortest top-weight prefix (the retained-set order) whose
    decision-coordinate span covers the truth; a truth outside the hull scores ``1 + d / D``.
    """
    z = np.asarray(z, dtype=float)
    z_true = np.asarray(z_true, dtype=float)
    order, cum = prefix_mass(np.asarray(weights, dtype=float))
    z_sorted = np.take_along_axis(z, order, axis=-1)
    run_lo = np.minimum.accumulate(z_sorted, axis=-1)
    run_hi = np.maximum.accumulate(z_sorted, axis=-1)
    covers = (run_lo <= z_true[:, None]) & (z_true[:, None] <= run_hi)
    first = np.argmax(covers, axis=-1)
    inside = covers.any(axis=-1)
    # A float cumulative sum of normalized weights can overshoot 1 by an ulp
    # (0.44697 + 0.29545 + 0.25758 -> 1.0000000000000002); clip so that s > 1
    # means escape and nothing else. This never changes which prefix covers.
    s_inside = np.minimum(np.take_along_axis(cum, first[:, None], axis=-1)[:, 0], 1.0)
    hull_lo, hull_hi = run_lo[:, -1], run_hi[:, -1]
    distance = np.maximum(hull_lo - z_true, 0.0) + np.maximum(z_true - hull_hi, 0.0)
    return np.where(inside, s_inside, 1.0 + distance / float(domain_width)), hull_lo, hull_hi


def median_over_particles(values: np.ndarray) -> np.ndarray:
    """``np.median(values, axis=1)`` of ``values[E, N, m]``: ``[E, m]``, the same bits.

    Why: a grown set fills its points' other latents with the particles' median, once per grown
    set. ``np.median`` partitions at three places (the two middle order statistics, and the last
    for its NaN check), which takes NumPy's multi-``kth`` path, about five times as slow as one
    ``kth``. Here the upper middle is one partition and the lower middle the largest value below
    it: the same order statistics, averaged by the same ``np.mean`` of the pair. Rows holding a NaN
    or a zero are ``np.median``'s own (which of ``-0.0`` and ``0.0`` lands in the middle depends on
    the algorithm; a NaN makes the median NaN), as are a dtype other than float64 and N < 2.
    """
    values = np.asarray(values)
    n_e, n, m = values.shape
    if n < 2 or values.dtype != np.float64:
        return np.median(values, axis=1)
    part = np.empty((n_e, m, n))  # a copy of our own, partitioned in place (never the caller's array)
    part[...] = np.swapaxes(values, 1, 2)
    part = part.reshape(n_e * m, n)
    half = n // 2
    part.partition(half, axis=1)
    # As np.median: the mean of the middle pair (N even) or of the middle value alone (N odd).
    middle = part[:, half : half + 1]
    if n % 2 == 0:
        middle = np.concatenate([part[:, :half].max(axis=1, keepdims=True), middle], axis=1)
    out = np.mean(middle, axis=1).reshape(n_e, m)
    # A NaN anywhere (np.max propagates it), or a zero in the middle, is np.median's to answer.
    special = (np.isnan(part.max(axis=1)) | (middle == 0).any(axis=1)).reshape(n_e, m).any(axis=1)
    if special.any():
        out[special] = np.median(values[special], axis=1)
    return out
