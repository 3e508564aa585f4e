"""Retained sets: nesting in nu, the post-resampling tie rule, intervals."""

import math

import numpy as np
import pytest

from hypothesis import given, settings
from hypothesis import strategies as st

from probecommit.core.retained import (masked_interval, median_over_particles, retained_count, retained_mask,
                                       weighted_mean)


def test_retained_sets_are_nested_in_nu():
    rng = np.random.default_rng(0)
    w = rng.dirichlet(np.full(50, 0.3), size=20)
    w[:, :5] = w[:, 5:10]  # plant exact ties
    w /= w.sum(axis=1, keepdims=True)
    prev = np.zeros_like(w, dtype=bool)
    for nu in np.linspace(0.05, 1.0, 20):
        mask = retained_mask(w, nu)
        assert np.all(prev <= mask)
        assert np.all(np.sum(np.where(mask, w, 0), axis=1) >= nu - 1e-9)
        prev = mask


def test_shortest_prefix_by_descending_weight():
    w = np.array([[0.1, 0.4, 0.2, 0.3]])
    assert retained_mask(w, 0.5).tolist() == [[False, True, False, True]]
    assert retained_mask(w, 0.7).tolist() == [[False, True, False, True]]
    assert retained_mask(w, 0.71).tolist() == [[False, True, True, True]]


@pytest.mark.parametrize("n", [1024, 512, 100, 7])
def test_tie_rule_after_resampling_keeps_first_ceil_nu_n_in_parent_order(n):
    w = np.full((1, n), 1.0 / n)
    mask = retained_mask(w, 0.8)
    k = math.ceil(0.8 * n)
    assert retained_count(w, 0.8)[0] == k
    assert mask[0, :k].all() and not mask[0, k:].any()


def test_zero_weight_particles_come_last():
    w = np.array([[0.0, 0.5, 0.0, 0.5]])
    assert retained_mask(w, 1.0).tolist() == [[False, True, False, True]]


def test_interval_and_mean():
    z = np.array([[3.0, -1.0, 2.0, 10.0]])
    mask = np.array([[True, True, True, False]])
    lo, hi = masked_interval(z, mask)
    assert (lo[0], hi[0]) == (-1.0, 3.0)
    w = np.array([[0.5, 0.5, 0.0, 0.0]])
    assert weighted_mean(z, w, mask)[0] == 1.0


# Values with the cases where algorithms could differ: repeated values, both zeros, NaN and infinities.
_MEDIAN_VALUES = st.sampled_from([-2.0, -1.0, -0.0, 0.0, 0.5, 1.0, 3.0, np.inf, -np.inf, np.nan, 1e-300, -7.25])


@settings(max_examples=300, deadline=None)
@given(st.integers(1, 4), st.integers(1, 40), st.integers(1, 3), st.data())
def test_median_over_particles_is_numpys_bit_for_bit(n_e, n, m, data):
    values = np.array(data.draw(st.lists(_MEDIAN_VALUES, min_size=n_e * n * m, max_size=n_e * n * m))).reshape(n_e, n, m)
    assert median_over_particles(values).tobytes() == np.median(values, axis=1).tobytes()


def test_median_over_particles_on_beliefs_and_views():
    rng = np.random.default_rng(5)
    particles = rng.normal(size=(64, 1024, 3))
    particles[:3, :600, 1] = 0.25  # ties in the middle
    particles[3, 512:, 2] = -0.0  # a zero in the middle: NumPy's own rows
    particles[4, 7, 0] = np.nan
    for view in (particles, particles[:, :, 1:], particles[:, :1023], particles[::2, :, :1]):
        assert median_over_particles(view).tobytes() == np.median(view, axis=1).tobytes()
    assert median_over_particles(particles[:, :, 1:]).shape == (64, 2)
    column = np.ascontiguousarray(particles[:, :, :1])  # partitioned as a copy, never in the caller's array
    before = column.copy()
    median_over_particles(column)
    assert column.tobytes() == before.tobytes()
