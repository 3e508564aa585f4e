"""Compiled kernels agree bit for bit with their NumPy paths."""

from __future__ import annotations

import numpy as np
import pytest

from probecommit.core import kernels
from probecommit.core.executors import interval_success_counts, interval_success_counts_numpy

pytestmark = pytest.mark.skipif(not kernels.HAVE_NUMBA, reason="numba not installed (pip install 'probecommit[fast]')")


@pytest.mark.parametrize("grid", [
    np.round(np.arange(-10.0, 10.0 + 1e-9, 0.5), 10),  # insertion's aims: evenly spaced
    np.sort(np.random.default_rng(7).uniform(-10, 10, 41)),  # uneven
    np.array([0.0, 1.0]),
])
def test_interval_counts_match_numpy_including_ties_and_non_finite(grid):
    rng = np.random.default_rng(3)
    x = rng.uniform(-12, 12, (50, 300))
    x[:, :40] = np.round(x[:, :40] * 2) / 2  # interval ends exactly on grid points
    w = rng.uniform(0.0, 2.0, (50, 300))
    lo, hi = x - w, x + w
    lo[0, :6] = [np.nan, np.inf, -np.inf, 1e300, -1e300, grid[0]]
    hi[0, :6] = [np.nan, np.inf, np.inf, 1e300, 1e300, grid[-1]]
    lo[1, :4] = np.nextafter(grid[:1], np.inf)[0], np.nextafter(grid[-1:], -np.inf)[0], grid[-1], grid[0]
    mask = rng.random((50, 300)) < 0.8
    np.testing.assert_array_equal(interval_success_counts(lo, hi, mask, grid), interval_success_counts_numpy(lo, hi, mask, grid))


def test_uniform_step_detects_even_grids_only():
    assert kernels.uniform_step(np.round(np.arange(-10.0, 10.5, 0.5), 10)) == 0.5
    assert kernels.uniform_step(np.array([0.0, 1.0, 3.0])) == 0.0


def test_systematic_resample_matches_numpy_and_is_row_independent():
    from probecommit.core.belief import systematic_resample, systematic_resample_numpy

    rng = np.random.default_rng(0)
    weights = rng.random((64, 256)) ** 8
    weights[3] = 0.0
    weights[3, 17] = 1.0  # all mass on one particle
    weights[5] = 1.0  # all tied
    weights /= weights.sum(axis=1, keepdims=True)
    offsets = rng.random(64)
    offsets[0] = 0.0
    fast, slow = systematic_resample(weights, offsets), systematic_resample_numpy(weights, offsets)
    np.testing.assert_array_equal(fast, slow)
    assert np.all(fast[3] == 17) and np.all(np.diff(fast, axis=1) >= 0)
    for r in (0, 31, 63):
        np.testing.assert_array_equal(systematic_resample(weights[r:r + 1], offsets[r:r + 1])[0], fast[r])
