"""Compiled kernels (numba) for the hot loops of the executor, with NumPy fallbacks.

numba is an optional, pinned dependency (``pip install 'probecommit[fast]'``, part of
``all``). Every kernel here has a NumPy twin in the calling module and a test that the
two agree bit for bit (``tests/core/test_kernels.py``); without numba, or with
``PROBECOMMIT_NO_NUMBA=1``, the NumPy path runs. Compiled code is cached on disk
(``cache=True``), so only the first run on a machine pays the compile time.
"""

from __future__ import annotations

import os

import numpy as np

try:  # pragma: no cover - exercised in both states by the tests' environment switch
    if os.environ.get("PROBECOMMIT_NO_NUMBA"):
        raise ImportError("disabled by PROBECOMMIT_NO_NUMBA")
    import numba

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover
    numba = None
    HAVE_NUMBA = False


if HAVE_NUMBA:

    @numba.njit(cache=True, nogil=True, inline="always")
    def _position(actions, value, step, right):  # pragma: no cover - compiled
        """``searchsorted(actions, value, side)`` on a sorted grid; exact.

        An arithmetic first guess on an evenly spaced grid (``step > 0``), or the middle
        otherwise, then walked to the exact answer with the grid's own comparisons.
        """
        n = actions.shape[0]
        if value != value:  # NaN sorts last, as in NumPy
            return n
        if step > 0.0:
            guess = (value - actions[0]) / step
            if guess < 0.0:
                i = 0
            elif guess > n:
                i = n
            else:
                i = int(guess)
        else:
            i = n // 2
        if right:  # first index with a > value
            while i < n and actions[i] <= value:
                i += 1
            while i > 0 and actions[i - 1] > value:
                i -= 1
        else:  # first index with a >= value
            while i < n and actions[i] < value:
                i += 1
            while i > 0 and actions[i - 1] >= value:
                i -= 1
        return i

    @numba.njit(cache=True, nogil=True)
    def _interval_success_counts(lo, hi, mask, actions, step):  # pragma: no cover - compiled
        n_e, n_s = mask.shape
        n_a = actions.shape[0]
        out = np.zeros((n_e, n_a), dtype=np.int64)
        diff = np.zeros(n_a + 1, dtype=np.int64)
        for e in range(n_e):
            diff[:] = 0
            for s in range(n_s):
                if mask[e, s]:
                    first = _position(actions, lo[e, s], step, True)
                    last = _position(actions, hi[e, s], step, False)
                    if first < last:
                        diff[first] += 1
                        diff[last] -= 1
            run = 0
            for a in range(n_a):
                run += diff[a]
                out[e, a] = run
        return out


if HAVE_NUMBA:

    @numba.njit(cache=True, nogil=True)
    def _systematic_resample(weights, offsets):  # pragma: no cover - compiled
        n_rows, n = weights.shape
        out = np.empty((n_rows, n), dtype=np.int64)
        cumulative = np.empty(n)
        for r in range(n_rows):
            total = 0.0
            for i in range(n):
                total += weights[r, i]
                cumulative[i] = total
            cumulative[n - 1] = 1.0
            j = 0
            for i in range(n):
                # searchsorted(cumulative, position, side="right"), walking forward: positions increase
                position = (offsets[r] + i) / n
                while j < n and cumulative[j] <= position:
                    j += 1
                out[r, i] = j if j < n else n - 1
        return out


def systematic_resample_compiled(weights: np.ndarray, offsets: np.ndarray) -> np.ndarray | None:
    """The compiled systematic resampler (see ``core.belief.systematic_resample``), or None without numba."""
    if not HAVE_NUMBA:
        return None
    return _systematic_resample(np.ascontiguousarray(weights, dtype=np.float64), np.ascontiguousarray(offsets, dtype=np.float64))


def uniform_step(actions: np.ndarray) -> float:
    """The spacing of an evenly spaced grid (within 1e-9 relative), else 0."""
    n = actions.shape[0]
    if n < 3:
        return 0.0
    step = (actions[-1] - actions[0]) / (n - 1)
    return float(step) if step > 0 and np.max(np.abs(np.diff(actions) - step)) <= 1e-9 * step else 0.0


def interval_success_counts_compiled(lo: np.ndarray, hi: np.ndarray, mask: np.ndarray, actions: np.ndarray) -> np.ndarray | None:
    """The compiled interval count (see ``core.executors.interval_success_counts``), or None without numba."""
    if not HAVE_NUMBA:
        return None
    actions = np.ascontiguousarray(actions, dtype=np.float64)
    return _interval_success_counts(np.ascontiguousarray(lo, dtype=np.float64), np.ascontiguousarray(hi, dtype=np.float64),
                                    np.ascontiguousarray(mask, dtype=np.bool_), actions, uniform_step(actions))
