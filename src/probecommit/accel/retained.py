"""Compiled retained sets, coverage score and posterior variance (``core.retained``'s, per episode in one pass).

Both the retained set and the coverage score accumulate the particles' mass in descending
weight (a stable order: ties in index order), one addition at a time, as NumPy's ``cumsum``
does: the sets, hulls and scores equal the reference's exactly.
The weighted means (the tie-break reference, the posterior variance) sum in loop order and
agree with NumPy's pairwise sums to round-off (``tests/accel``).
"""

from __future__ import annotations

import numpy as np

from probecommit.accel.compiled import helper, kernel
from probecommit.core.retained import MASS_TOLERANCE


#: Extra mass the candidates must hold beyond ``nu`` (their sum is taken in another order than
#: the prefix's cumulative sum, so it may differ by round-off).
_SLACK = 1e-9


#: Distinct weight values walked from the largest down before the prefix is found by sorting.
_FEW_VALUES = 16


@helper(inline=True)
def _prefix_stop(row, target):  # pragma: no cover - compiled
    """``(m, w)``: the length of the shortest descending prefix of ``row``'s values whose running
    sum reaches ``target`` (all of them if none does), and the value it stops at.

    A belief after taps, or just resampled, holds a few distinct weights: they are walked from the
    largest down, each added once per particle holding it. Otherwise the values that can lie in
    the prefix (:func:`_candidates`) are sorted and walked.
    """
    n = row.shape[0]
    total, count, previous = 0.0, 0, np.inf
    for _ in range(_FEW_VALUES):
        value, copies = -np.inf, 0
        for w in row:  # the largest value below the previous one, and how many particles hold it
            if w < previous:
                if w > value:
                    value, copies = w, 1
                elif w == value:
                    copies += 1
        if copies == 0:
            return n, previous
        for _ in range(copies):
            total += value
            count += 1
            if total >= target:
                return count, value
        previous = value
    values = _candidates(row, target)
    total = 0.0
    for i in range(values.shape[0]):
        total += values[i]
        if total >= target:
            return i + 1, values[i]
    return n, np.min(row)


@helper(inline=True)
def _candidates(row, nu):  # pragma: no cover - compiled
    """The weights that can lie in the top-weight prefix reaching ``nu``, sorted descending.

    Weights at least ``floor`` whose total surely exceeds ``nu`` hold the whole prefix (every
    other weight is lighter than each of them), so only they are sorted: the floor starts at the
    mean weight and is lowered fourfold until it holds enough, else every weight is sorted.
    """
    n = row.shape[0]
    floor = 1.0 / n
    for _ in range(8):
        total, m = 0.0, 0
        for w in row:
            if w >= floor:
                total += w
                m += 1
        if total >= nu + _SLACK:
            kept = np.empty(m)
            m = 0
            for w in row:
                if w >= floor:
                    kept[m] = w
                    m += 1
            return np.sort(kept)[::-1]
        floor *= 0.25
    return np.sort(row)[::-1]


@kernel("Tuple((b1[:, ::1], f8[::1], f8[::1], f8[:, ::1]))(f8[:, ::1], f8[::1], f8[:, ::1], f8[:, :, ::1], f8)")
def _retained_summary(weights, nu, z, particles, tolerance):  # pragma: no cover - compiled
    n_e, n = weights.shape
    d = particles.shape[2]
    mask = np.zeros((n_e, n), dtype=np.bool_)
    lo = np.empty(n_e)
    hi = np.empty(n_e)
    reference = np.zeros((n_e, d))
    for e in range(n_e):
        # The stable descending order's cumulative mass is that of the weights' values sorted
        # (tied particles share a value), so the values alone give where the prefix stops; the set
        # is every heavier particle and the first tied ones in index order.
        count, stop = _prefix_stop(weights[e], nu[e] - tolerance)
        ties = count
        for i in range(n):
            ties -= weights[e, i] > stop
        low, high, mass = np.inf, -np.inf, 0.0
        for p in range(n):
            w = weights[e, p]
            if w == stop and ties > 0:
                ties -= 1
            elif not w > stop:
                continue
            mask[e, p] = True
            low, high = min(low, z[e, p]), max(high, z[e, p])
            mass += w
            for j in range(d):
                reference[e, j] += w * particles[e, p, j]
        lo[e], hi[e] = low, high
        if mass > 0:
            reference[e] /= mass
        else:  # a set of zero-weight particles only: the unweighted mean
            kept = 0
            for p in range(n):
                if mask[e, p]:
                    reference[e] += particles[e, p]
                    kept += 1
            reference[e] /= kept
    return mask, lo, hi, reference


@helper(inline=True)
def _ranks_before(w, p, w_q, q):  # pragma: no cover - compiled
    """Whether particle ``p`` (weight ``w``) comes before ``q`` (weight ``w_q``) in the stable
    descending-weight order: heavier first, ties in index order."""
    return w > w_q or (w == w_q and p < q)


@helper(inline=True)
def _covering_mass(weights, z, truth):  # pragma: no cover - compiled
    """The mass of the shortest top-weight prefix whose span covers ``truth`` (inside the hull);
    -1 when a weight is NaN.

    The span covers the truth once the prefix holds a particle at or above it and one at or
    below it, so the prefix ends at the later of the first of each in the stable descending
    order: two scans find them, without sorting. Its mass is the sum of its weights in that
    order (the reference's cumulative sum), so only the prefix's values are sorted and added,
    largest first: tied particles share a value, so the sum is the reference's exactly.
    """
    n = weights.shape[0]
    above, below = -1, -1
    for p in range(n):
        w = weights[p]
        if w != w:  # NaN: no total order (the caller sorts as the reference does)
            return -1.0
        if z[p] >= truth and (above < 0 or _ranks_before(w, p, weights[above], above)):
            above = p
        if z[p] <= truth and (below < 0 or _ranks_before(w, p, weights[below], below)):
            below = p
    stop = below if _ranks_before(weights[above], above, weights[below], below) else above
    w_stop = weights[stop]
    values = np.empty(n)
    m = 0
    for p in range(n):
        if weights[p] > w_stop or (weights[p] == w_stop and p <= stop):
            values[m] = weights[p]
            m += 1
    prefix = np.sort(values[:m])
    mass = 0.0
    for i in range(m - 1, -1, -1):
        mass += prefix[i]
    return mass


@kernel("Tuple((f8[::1], f8[::1], f8[::1]))(f8[:, ::1], f8[:, ::1], f8[::1], f8)")
def _coverage_with_hull(weights, z, z_true, width):  # pragma: no cover - compiled
    n_e, n = weights.shape
    score = np.empty(n_e)
    hull_lo = np.empty(n_e)
    hull_hi = np.empty(n_e)
    for e in range(n_e):
        hull_lo[e], hull_hi[e] = np.min(z[e]), np.max(z[e])
        truth = z_true[e]
        if not (hull_lo[e] <= truth <= hull_hi[e]):  # escaped: 1 + distance past the hull / D
            distance = max(hull_lo[e] - truth, 0.0) + max(truth - hull_hi[e], 0.0)
            score[e] = 1.0 + distance / width
            continue
        mass = _covering_mass(weights[e], z[e], truth)
        if mass < 0:  # a NaN weight, no total order: the stable sort decides, as the reference's
            order = np.argsort(-weights[e], kind="mergesort")
            low, high, mass = np.inf, -np.inf, 0.0
            for i in range(n):  # the mass of the first top-weight prefix whose span covers the truth
                p = order[i]
                mass += weights[e, p]
                low, high = min(low, z[e, p]), max(high, z[e, p])
                if low <= truth <= high:
                    break
        score[e] = min(mass, 1.0)
    return score, hull_lo, hull_hi


@kernel("f8[::1](f8[:, ::1], f8[:, ::1])")
def _weighted_variance(z, weights):  # pragma: no cover - compiled
    n_e, n = weights.shape
    out = np.empty(n_e)
    for e in range(n_e):
        mean = 0.0
        for i in range(n):
            mean += weights[e, i] * z[e, i]
        total = 0.0
        for i in range(n):
            total += weights[e, i] * (z[e, i] - mean) ** 2
        out[e] = total
    return out


def retained_summary(weights: np.ndarray, nu, z: np.ndarray, particles: np.ndarray):
    """``core.retained.retained_summary``, compiled: ``(mask, lo, hi, reference)``."""
    weights = np.ascontiguousarray(weights, dtype=np.float64)
    nu_rows = np.ascontiguousarray(np.broadcast_to(np.asarray(nu, dtype=np.float64), weights.shape[:1]))
    return _retained_summary(weights, nu_rows, np.ascontiguousarray(z, dtype=np.float64),
                             np.ascontiguousarray(particles, dtype=np.float64), MASS_TOLERANCE)


def coverage_with_hull(z: np.ndarray, weights: np.ndarray, z_true: np.ndarray, domain_width: float):
    """``core.retained.coverage_with_hull``, compiled: ``(score, hull_lo, hull_hi)``."""
    return _coverage_with_hull(np.ascontiguousarray(weights, dtype=np.float64), np.ascontiguousarray(z, dtype=np.float64),
                               np.ascontiguousarray(z_true, dtype=np.float64).reshape(-1), float(domain_width))


def weighted_variance(z: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """``core.retained.weighted_variance``, compiled."""
    return _weighted_variance(np.ascontiguousarray(z, dtype=np.float64), np.ascontiguousarray(weights, dtype=np.float64))
