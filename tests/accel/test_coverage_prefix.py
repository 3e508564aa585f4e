"""The compiled coverage score finds its covering prefix without sorting the particles (two scans
for the first particle at or above the truth and at or below it): the same scores as the NumPy
reference's sorted cumulative sum, bit for bit, where ties (in weight and in the decision
coordinate) decide which particle ends the prefix."""

from __future__ import annotations

import numpy as np
import pytest

from probecommit.accel import retained as fast_retained
from probecommit.core import retained


@pytest.mark.parametrize("seed", range(6))
def test_ties_in_weight_and_position_give_the_references_score_exactly(seed):
    rng = np.random.default_rng(seed)
    e, n = 60, 257
    weights = np.exp(-rng.integers(0, 3 + seed, (e, n)).astype(float))  # a few weight values: many ties
    weights[:5] = 1.0  # all tied
    weights /= weights.sum(axis=1, keepdims=True)
    z = np.round(rng.uniform(-2, 2, (e, n)) * 2) / 2  # a coarse grid: many particles share a position
    z_true = z[np.arange(e), rng.integers(0, n, e)]  # every truth on a particle
    z_true[::3] += 0.25  # and some between grid points
    got = fast_retained.coverage_with_hull(z, weights, z_true, 4.0)
    want = retained.coverage_with_hull(z, weights, z_true, 4.0)
    for a, b in zip(got, want):
        np.testing.assert_array_equal(a, b)
    assert np.mean(got[0] <= 1.0) > 0.9  # nearly every truth inside its hull: the prefix decides


def test_a_hand_case():
    # Descending stable order: p2 (0.4), p0 (0.3), p1 (0.3), p3 (0.0). Truth 1.5: p2 at 2 covers the
    # top side, p0 at 3 does not, p1 at 1 covers the bottom: the prefix is p2, p0, p1, mass 1.0.
    weights = np.array([[0.3, 0.3, 0.4, 0.0]])
    z = np.array([[3.0, 1.0, 2.0, 0.0]])
    score, lo, hi = fast_retained.coverage_with_hull(z, weights, np.array([1.5]), 4.0)
    assert score.tolist() == [1.0] and lo.tolist() == [0.0] and hi.tolist() == [3.0]
    score, _, _ = fast_retained.coverage_with_hull(z, weights, np.array([2.0]), 4.0)  # on p2 itself
    assert score.tolist() == [0.4]
    score, _, _ = fast_retained.coverage_with_hull(z, weights, np.array([2.5]), 4.0)  # p2 then p0
    assert score.tolist() == [0.7]


@pytest.mark.parametrize("levels", [2, 16, 17, 40, None])
def test_long_prefixes_of_few_or_many_weight_values_give_the_references_score_exactly(levels):
    # A truth near the top of the belief needs one of the few particles above it: the covering prefix
    # is long (hundreds of particles, of a few weight values or of many), and its sorted sum is the
    # reference's cumulative sum, bit for bit.
    rng = np.random.default_rng(levels or 0)
    e, n = 40, 300
    if levels is None:
        weights = rng.random((e, n))
    else:
        weights = np.exp(-rng.integers(0, levels, (e, n)).astype(float) / 3)
    weights /= weights.sum(axis=1, keepdims=True)
    z = rng.uniform(-2, 2, (e, n))
    z_true = np.sort(z, axis=1)[:, -3]  # two particles above the truth
    got = fast_retained.coverage_with_hull(z, weights, z_true, 4.0)
    want = retained.coverage_with_hull(z, weights, z_true, 4.0)
    for a, b in zip(got, want):
        np.testing.assert_array_equal(a, b)
    assert np.median(got[0]) > 0.3  # long prefixes: a third of the mass and more
