"""Compiled steps of the particle filter's update (``core.belief``'s NumPy reference, per episode in one pass).

The log normalizer is a log-sum-exp summed in loop order, so it agrees with NumPy's (pairwise)
to round-off; the weights are then NumPy's own ``exp`` of the normalized log-weights, so a belief
whose weights are recomputed later (``BeliefState.weights``) has the same bits as the update's.
Resampling and jitter are exact transcriptions (one cumulative sum in order, one search).
"""

from __future__ import annotations

import math

import numpy as np

from probecommit.accel.compiled import kernel
from probecommit.core.belief import FilterKernels


@kernel("f8[::1](f8[:, ::1], f8[:, ::1], f8[::1])")
def _normalize(log_weights, shifted_exps, row_max):  # pragma: no cover - compiled
    """Normalize log-weights ``[E, N]`` in place, given ``exp(log_weights - row_max)``; the log
    normalizer ``[E]`` (-inf: every weight zero, the row reset to uniform, "no information left")."""
    n_e, n = log_weights.shape
    log_norm = np.empty(n_e)
    for e in range(n_e):
        if not math.isfinite(row_max[e]):
            log_norm[e] = -np.inf
            log_weights[e] = -math.log(n)
            continue
        total = 0.0
        for i in range(n):
            total += shifted_exps[e, i]
        log_norm[e] = row_max[e] + math.log(total)
        for i in range(n):
            log_weights[e, i] -= log_norm[e]
    return log_norm


@kernel("f8[::1](f8[:, ::1])")
def _sum_of_squares(weights):  # pragma: no cover - compiled
    n_e, n = weights.shape
    out = np.empty(n_e)
    for e in range(n_e):
        total = 0.0
        for i in range(n):
            total += weights[e, i] * weights[e, i]
        out[e] = total
    return out


@kernel("i8[:, ::1](f8[:, ::1], f8[::1])")
def _systematic_resample(weights, offsets):  # pragma: no cover - compiled
    n_rows, n = weights.shape
    out = np.empty((n_rows, n), dtype=np.int64)
    cumulative = np.empty(n)
    for r in range(n_rows):
        total = 0.0
        for i in range(n):
            total += weights[r, i]
            cumulative[i] = total
        cumulative[n - 1] = 1.0  # round-off must not leave the last point unreachable
        j = 0
        for i in range(n):  # searchsorted(cumulative, position, "right"), walking forward: positions increase
            position = (offsets[r] + i) / n
            while j < n and cumulative[j] <= position:
                j += 1
            out[r, i] = min(j, n - 1)
    return out


@kernel("f8[:, :, ::1](f8[:, :, ::1], i8[::1], i8[:, ::1], f8[:, :, ::1], f8[::1], f8[::1], f8[::1])")
def _jitter_resampled(particles, rows, parents, noise, scale, low, high):  # pragma: no cover - compiled
    # Only the rows that do not resample are copied (most rows resample after a tap): each
    # resampled row is written below, whole.
    out = np.empty_like(particles)
    resampled = np.zeros(particles.shape[0], dtype=np.bool_)
    for i in range(rows.shape[0]):
        resampled[rows[i]] = True
    for e in range(particles.shape[0]):
        if not resampled[e]:
            out[e] = particles[e]
    n_rows, n = parents.shape
    for i in range(n_rows):
        r = rows[i]
        for k in range(n):
            for j in range(particles.shape[2]):
                value = particles[r, parents[i, k], j] + scale[j] * noise[i, k, j]
                out[r, k, j] = value if value != value else min(max(value, low[j]), high[j])  # np.clip keeps NaN
    return out


def normalized_weights(log_weights: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``core.belief.normalized_weights``, compiled: ``(log_w, log_norm, weights, ess)``; ``log_weights``
    is overwritten. The exponentials are NumPy's (vectorized); the kernel sums and shifts in one pass."""
    log_w = np.ascontiguousarray(log_weights, dtype=np.float64)
    row_max = np.max(log_w, axis=1)
    with np.errstate(invalid="ignore"):  # a row of -inf: reset in the kernel
        shifted_exps = np.subtract(log_w, np.where(np.isfinite(row_max), row_max, 0.0)[:, None])
        np.exp(shifted_exps, out=shifted_exps)  # in place: the same elementwise bits, one array fewer
    log_norm = _normalize(log_w, shifted_exps, row_max)
    weights = np.exp(log_w)
    return log_w, log_norm, weights, 1.0 / _sum_of_squares(weights)


def systematic_resample(weights: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """``core.belief.systematic_resample``, compiled."""
    return _systematic_resample(np.ascontiguousarray(weights, dtype=np.float64),
                                np.ascontiguousarray(offsets, dtype=np.float64))


def jitter_resampled(particles: np.ndarray, rows: np.ndarray, parents: np.ndarray, noise: np.ndarray,
                     scale: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """``core.belief.jitter_resampled``, compiled."""
    f64 = np.float64
    return _jitter_resampled(np.ascontiguousarray(particles, dtype=f64), np.ascontiguousarray(rows, dtype=np.int64),
                             np.ascontiguousarray(parents, dtype=np.int64), np.ascontiguousarray(noise, dtype=f64),
                             np.ascontiguousarray(scale, dtype=f64), np.ascontiguousarray(low, dtype=f64),
                             np.ascontiguousarray(high, dtype=f64))


#: The filter's compiled steps (``ParticleFilter(kernels=KERNELS)``).
KERNELS = FilterKernels(normalized_weights=normalized_weights, systematic_resample=systematic_resample,
                        jitter_resampled=jitter_resampled)
