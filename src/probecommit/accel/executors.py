"""Compiled scenario counts for the set executors (``core.executors``'s interval fast path).

For a binary loss whose success set is an open interval of a sorted 1-D action grid, the
executor needs, per episode and action, how many retained scenarios succeed. Each scenario
adds one to a contiguous run of actions (a difference array). The counts are integers, so
they equal the NumPy reference exactly.
"""

from __future__ import annotations

import numpy as np

from probecommit.accel.compiled import helper, kernel
from probecommit.accel.retained import retained_summary
from probecommit.core.executors import SetKernels


@helper(inline=True)
def _add_interval(diff, actions, lo, hi):  # pragma: no cover - compiled
    """Add the open interval ``(lo, hi)`` to the difference array of the actions it holds.
    A NaN end holds nothing at the low side and bounds nothing at the high side (NumPy's order)."""
    if lo != lo:
        return
    first = np.searchsorted(actions, lo, side="right")  # first a > lo
    last = actions.shape[0] if hi != hi else np.searchsorted(actions, hi, side="left")  # one past the last a < hi
    if first < last:
        diff[first] += 1
        diff[last] -= 1


@helper(inline=True)
def _take_counts(diff, out_row):  # pragma: no cover - compiled
    """The running sum of a difference array into ``out_row``; the array cleared for the next row."""
    run = 0
    for a in range(out_row.shape[0]):
        run += diff[a]
        out_row[a] = run
    diff[:] = 0


@kernel("i8[:, ::1](f8[:, ::1], f8[:, ::1], b1[:, ::1], f8[::1])")
def _interval_counts(lo, hi, mask, actions):  # pragma: no cover - compiled
    n_e, n_s = mask.shape
    out = np.zeros((n_e, actions.shape[0]), dtype=np.int64)
    diff = np.zeros(actions.shape[0] + 1, dtype=np.int64)
    for e in range(n_e):
        for s in range(n_s):
            if mask[e, s]:
                _add_interval(diff, actions, lo[e, s], hi[e, s])
        _take_counts(diff, out[e])
    return out


@kernel("i8[:, ::1](f8[:, ::1], f8[:, ::1], f8, b1[:, ::1], f8[::1])")
def _scaled_counts(centre, half, margin, mask, actions):  # pragma: no cover - compiled
    n_e, n_s = mask.shape
    out = np.zeros((n_e, actions.shape[0]), dtype=np.int64)
    diff = np.zeros(actions.shape[0] + 1, dtype=np.int64)
    for e in range(n_e):
        for s in range(n_s):
            if mask[e, s]:
                width = half[e, s] * margin
                _add_interval(diff, actions, centre[e, s] - width, centre[e, s] + width)
        _take_counts(diff, out[e])
    return out


@kernel("i8[:, ::1](f8[:, :, ::1], i8, i8, f8, f8, f8, b1[:, ::1], f8[::1], i8[::1])")
def _affine_counts(scenarios, centre_at, width_at, slope, intercept, margin, mask, actions, kept):  # pragma: no cover
    n_e, n_s = mask.shape
    out = np.zeros((n_e, actions.shape[0]), dtype=np.int64)
    diff = np.zeros(actions.shape[0] + 1, dtype=np.int64)
    for e in range(n_e):
        k = 0
        for s in range(n_s):
            if mask[e, s]:
                k += 1
                width = (scenarios[e, s, width_at] * slope + intercept) * margin
                centre = scenarios[e, s, centre_at]
                _add_interval(diff, actions, centre - width, centre + width)
        _take_counts(diff, out[e])
        kept[e] = k
    return out


def _grid(actions: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(actions, dtype=np.float64).reshape(-1)


def interval_counts(lo: np.ndarray, hi: np.ndarray, mask: np.ndarray, actions: np.ndarray) -> np.ndarray:
    """``core.executors.interval_success_counts``, compiled."""
    return _interval_counts(np.ascontiguousarray(lo, dtype=np.float64), np.ascontiguousarray(hi, dtype=np.float64),
                            np.ascontiguousarray(mask, dtype=np.bool_), _grid(actions))


def scaled_counts(centre: np.ndarray, half: np.ndarray, margin: float, mask: np.ndarray,
                  actions: np.ndarray) -> np.ndarray:
    """``core.executors.scaled_interval_success_counts``, compiled (the ends made per retained scenario)."""
    f64 = np.float64
    return _scaled_counts(np.ascontiguousarray(centre, dtype=f64), np.ascontiguousarray(half, dtype=f64), float(margin),
                          np.ascontiguousarray(mask, dtype=np.bool_), _grid(actions))


def affine_counts(scenarios: np.ndarray, affine: tuple[int, int, float, float], margin: float, mask: np.ndarray,
                  actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Success counts ``[E, A]`` of a model whose interval parts are affine in its latents
    (``success_interval_affine``), read from ``scenarios[E, N, d]`` in place, and the retained count ``[E]``."""
    centre_at, width_at, slope, intercept = affine
    kept = np.empty(mask.shape[0], dtype=np.int64)
    counts = _affine_counts(np.ascontiguousarray(scenarios, dtype=np.float64), int(centre_at), int(width_at),
                            float(slope), float(intercept), float(margin), np.ascontiguousarray(mask, dtype=np.bool_),
                            _grid(actions), kept)
    return counts, kept


#: The set executors' compiled kernels (``ProbeRobust(kernels=KERNELS)``).
KERNELS = SetKernels(retained_summary=retained_summary, interval_success_counts=interval_counts,
                     scaled_interval_success_counts=scaled_counts, affine_interval_success_counts=affine_counts)
