"""The compiled production path (``probecommit.accel``) agrees with the NumPy reference (``probecommit.core``).

Stated tolerance: sums taken in the kernels' own order (log normalizer, effective sample size,
weighted means and variance) agree to ``RTOL = 1e-12`` relative (``ATOL = 1e-12`` absolute
near zero). Everything built from counts, a stable sort, a cumulative sum in order, comparisons
or integer hashing is exact: interval counts, retained masks and intervals, coverage scores and
hulls, resampling parents, jitter, the seed words.
"""

from __future__ import annotations

import numpy as np
import pytest

from probecommit.accel import belief as fast_belief
from probecommit.accel import executors as fast_executors
from probecommit.accel import retained as fast_retained
from probecommit.accel import seeding as fast_seeding
from probecommit.core import belief, executors, retained

RTOL = 1e-12
ATOL = 1e-12


def _weight_cases():
    rng = np.random.default_rng(11)
    e, n = 40, 1024
    cases = {
        "continuous": np.exp(3 * rng.standard_normal((e, n))),
        "concentrated": np.exp(30 * rng.standard_normal((e, n))),
        "few values (a tap reading)": np.exp(-2.0 * rng.integers(0, 4, (e, n))),
        "all tied (just resampled)": np.ones((e, n)),
        "mostly zero": np.where(rng.random((e, n)) < 0.9, 0.0, rng.random((e, n))),
        "tiny rows": rng.random((e, 5)),
        "1000 particles": np.exp(3 * rng.standard_normal((e, 1000))),
        "runs of few values": np.repeat(np.exp(-3.0 * rng.integers(0, 5, (e, n // 8))), 8, axis=1),
        "signed zeros": np.where(rng.random((e, n)) < 0.5, np.where(rng.random((e, n)) < 0.5, -0.0, 0.0),
                                 np.exp(-rng.integers(0, 3, (e, n)))),
    }
    return {name: w / w.sum(axis=1, keepdims=True) for name, w in cases.items()}


CASES = _weight_cases()


@pytest.mark.parametrize("grid", [
    np.round(np.arange(-10.0, 10.0 + 1e-9, 0.5), 10),  # insertion's aims: evenly spaced
    np.sort(np.random.default_rng(7).uniform(-10, 10, 41)),  # uneven
    np.array([0.0, 1.0]),
])
def test_interval_counts_are_exact_including_ties_and_non_finite(grid):
    rng = np.random.default_rng(3)
    x = rng.uniform(-12, 12, (50, 300))
    x[:, :40] = np.round(x[:, :40] * 2) / 2  # interval ends exactly on grid points
    w = rng.uniform(0.0, 2.0, (50, 300))
    lo, hi = x - w, x + w
    lo[0, :6] = [np.nan, np.inf, -np.inf, 1e300, -1e300, grid[0]]
    hi[0, :6] = [np.nan, np.inf, np.inf, 1e300, 1e300, grid[-1]]
    mask = rng.random((50, 300)) < 0.8
    expected = executors.interval_success_counts(lo, hi, mask, grid)
    np.testing.assert_array_equal(fast_executors.interval_counts(lo, hi, mask, grid), expected)
    for margin in (1.0, 0.73):
        np.testing.assert_array_equal(fast_executors.scaled_counts(x, w, margin, mask, grid),
                                      executors.scaled_interval_success_counts(x, w, margin, mask, grid))
    assert expected.sum() > 0


@pytest.mark.parametrize("margin", [1.0, 0.73, 1.37])
def test_affine_counts_equal_counting_the_models_parts(margin):
    from probecommit.tasks.insertion.model import InsertionModel

    model = InsertionModel(margin=margin)
    rng = np.random.default_rng(11)
    grid = np.asarray(model.action_grid, dtype=float).reshape(-1)
    theta = np.stack([rng.uniform(-12, 12, (40, 500)), rng.uniform(-1.5, 3.0, (40, 500))], axis=-1)
    theta[:, :60, 0] = np.round(theta[:, :60, 0] * 2) / 2
    theta[:, :60, 1] = rng.choice([-1.0, 0.0, 0.65, 1.5, 2.4], (40, 60))
    mask = rng.random((40, 500)) < 0.8
    counts, kept = fast_executors.affine_counts(theta, model.success_interval_affine(), margin, mask, grid)
    np.testing.assert_array_equal(counts, executors.interval_success_counts(*model.success_interval(theta), mask, grid))
    np.testing.assert_array_equal(kept, mask.sum(axis=-1))


GAMMA_GRID = np.round(np.arange(100, 29, -2) / 100.0, 2)  # the paper's margins, largest first


@pytest.mark.parametrize("margins", [
    GAMMA_GRID,
    np.array([1.37, 1.0, 0.999, 0.73, 0.5, 1e-3]),  # uneven, above 1, tiny
    np.array([0.8]),  # one margin
    np.array([0.5, 0.8]),  # not largest first: the reference counts them
])
@pytest.mark.parametrize("grid", [
    np.round(np.arange(-10.0, 10.0 + 1e-9, 0.5), 10),  # insertion's aims
    np.sort(np.random.default_rng(7).uniform(-10, 10, 41)),  # uneven
    np.array([-1.0, -1.0, 0.0, 0.0, 0.0, 2.5, 100.0]),  # repeated aims and a gap: the spacing's guess is far off
    np.array([0.25]),  # one aim
])
def test_margin_counts_are_every_margins_scaled_counts_exactly(margins, grid):
    """One visit of the scenarios counts every margin: the same integers as counting each margin,
    with interval ends on grid points, widths at which an end lands on an aim at some margin,
    non-finite and negative parts, and masked scenarios."""
    rng = np.random.default_rng(5)
    x = rng.uniform(-12, 12, (30, 400))
    x[:, :50] = np.round(x[:, :50] * 2) / 2  # centres on grid points
    w = rng.uniform(0.0, 3.0, (30, 400))
    w[:, 50:120] = np.abs(np.round(x[:, 50:120] * 2) / 2 + 0.5 - x[:, 50:120]) / rng.choice(margins, (30, 70))
    w[0, :8] = [np.nan, np.inf, -np.inf, -1.0, 0.0, -0.0, 1e300, 5e-324]
    x[1, :6] = [np.nan, np.inf, -np.inf, 1e300, -1e300, 3.0]
    w[1, :6] = [1.0, 1.0, np.inf, 1.0, 1e300, np.inf]
    mask = rng.random((30, 400)) < 0.8
    expected = executors.margin_success_counts(x, w, margins, mask, grid)
    assert expected.shape == (len(margins), 30, len(grid)) and expected.sum() > 0
    np.testing.assert_array_equal(fast_executors.margin_counts(x, w, margins, mask, grid), expected)


def test_margin_choices_are_select_action_of_each_margins_scores_exactly():
    """Every margin's action and score from its counts: the same as the reference's scores and
    ``select_action``, with ties within the tolerance, equal scores of unequal tie costs, an empty
    retained set, NaN and infinite tie costs, and a row of scores that differ by less than the tolerance."""
    rng = np.random.default_rng(9)
    m, e, a = 7, 60, 41
    kept = rng.integers(0, 40, e)
    kept[:3] = [0, 1, 10**12 + 1]
    successes = (rng.random((m, e, a)) * (kept[None, :, None] + 1)).astype(np.int64)
    successes[:, :, ::5] = successes[:, :, :1]  # equal scores: the tie costs decide
    ties = np.round(rng.uniform(0, 5, (m, e, a)) * 2) / 2  # tied costs too: the first index decides
    ties[0, 5, 3], ties[1, 6, :] = np.nan, np.nan
    ties[2, 7, :], ties[3, 8, 10:] = np.inf, -np.inf
    successes[4, 2, :] = 10**12 + 1 - np.arange(a)  # scores 1e-12 apart: within the tolerance of the best
    index, score = fast_executors.margin_choices(successes, kept, ties)
    want_index, want_score = executors.margin_choices(successes, kept, ties)
    np.testing.assert_array_equal(index, want_index)
    np.testing.assert_array_equal(score, want_score)
    assert index.dtype == want_index.dtype and score.dtype == want_score.dtype
    scores = (kept[None, :, None] - successes) / np.maximum(kept, 1)[None, :, None]
    for g in range(m):  # the reference is select_action margin by margin
        np.testing.assert_array_equal(want_index[g], executors.select_action(scores[g], ties[g]))


@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.parametrize("nu", [0.05, 0.8, 1.0, 1.5, "per-row"])
def test_retained_summary_sets_are_exact_and_references_within_tolerance(name, nu):
    weights = CASES[name]
    rng = np.random.default_rng(5)
    particles = rng.normal(size=(*weights.shape, 3))
    z = particles[..., 0]
    nu = rng.uniform(0.01, 1.0, weights.shape[0]) if nu == "per-row" else nu
    mask, lo, hi, reference = fast_retained.retained_summary(weights, nu, z, particles)
    want = retained.retained_summary(weights, nu, z, particles)
    np.testing.assert_array_equal(mask, want[0])
    np.testing.assert_array_equal(lo, want[1])
    np.testing.assert_array_equal(hi, want[2])
    np.testing.assert_allclose(reference, want[3], rtol=RTOL, atol=ATOL)


@pytest.mark.parametrize("name", list(CASES))
def test_coverage_score_and_hull_are_exact(name):
    weights = CASES[name]
    rng = np.random.default_rng(8)
    z = rng.normal(size=(weights.shape[0], weights.shape[1] + 1))[:, 1:]  # a strided view, as a latent of the particles
    z_true = rng.normal(scale=1.5, size=weights.shape[0])
    z_true[:3] = z[:3, 0]  # a truth exactly on a particle
    z_true[3:6] = [10.0, -10.0, np.nan]  # escaped both ways, and a NaN truth
    got = fast_retained.coverage_with_hull(z, weights, z_true, 4.0)
    want = retained.coverage_with_hull(z, weights, z_true, 4.0)
    for a, b in zip(got, want):
        np.testing.assert_array_equal(a, b)
    assert np.any(want[0] > 1) and np.any(want[0] <= 1)


@pytest.mark.parametrize("name", list(CASES))
def test_weighted_variance_within_tolerance(name):
    weights = CASES[name]
    z = np.random.default_rng(2).normal(3.0, 2.0, weights.shape)
    np.testing.assert_allclose(fast_retained.weighted_variance(z, weights), retained.weighted_variance(z, weights),
                               rtol=RTOL, atol=ATOL)


@pytest.mark.parametrize("n", [1, 5, 128, 1000, 1024, 4096])
def test_normalized_weights_within_tolerance_and_weights_are_numpys_exp(n):
    rng = np.random.default_rng(n)
    log_weights = rng.normal(scale=20.0, size=(16, n))
    log_weights[0] = -np.inf  # a lost row: uniform
    log_weights[1, : n // 2] = -np.inf
    log_w, log_norm, weights, ess = fast_belief.normalized_weights(log_weights.copy())
    want = belief.normalized_weights(log_weights.copy())
    np.testing.assert_allclose(log_w, want[0], rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(log_norm, want[1], rtol=RTOL, atol=ATOL)
    np.testing.assert_array_equal(weights, np.exp(log_w))  # a recomputed belief has the update's own bits
    np.testing.assert_allclose(weights, want[2], rtol=1e-10, atol=ATOL)
    np.testing.assert_allclose(ess, want[3], rtol=1e-10)
    assert log_norm[0] == -np.inf and np.all(log_w[0] == -np.log(n))


def test_systematic_resample_and_jitter_are_exact():
    rng = np.random.default_rng(0)
    weights = rng.random((64, 256)) ** 8
    weights[3] = 0.0
    weights[3, 17] = 1.0
    weights[5] = 1.0
    weights /= weights.sum(axis=1, keepdims=True)
    offsets = rng.random(64)
    offsets[0] = 0.0
    parents = fast_belief.systematic_resample(weights, offsets)
    np.testing.assert_array_equal(parents, belief.systematic_resample(weights, offsets))
    particles = rng.normal(size=(64, 256, 2))
    rows = np.array([1, 3, 5, 60])
    noise = rng.normal(size=(4, 256, 2))
    noise[0, 0, 0] = np.nan
    args = (particles, rows, parents[rows], noise, np.array([0.3, 0.1]), np.array([-1.0, -2.0]), np.array([1.0, 0.5]))
    np.testing.assert_array_equal(fast_belief.jitter_resampled(*args), belief.jitter_resampled(*args))


def test_seed_words_are_numpys_seed_sequence():
    rng = np.random.default_rng(4)
    entropy = rng.integers(0, 2**32, (50, 8), dtype=np.uint64)
    words = fast_seeding.seed_sequence_words(entropy, 8)
    for row, got in zip(entropy, words):
        sequence = np.random.SeedSequence(entropy=[int(v) for v in row[:4]], spawn_key=[int(v) for v in row[4:]])
        np.testing.assert_array_equal(got, sequence.generate_state(8, np.uint32))


def test_a_filter_with_the_compiled_kernels_tracks_the_reference():
    """The same probes through both paths: the beliefs agree to round-off, and the retained sets
    and actions of the executor are the same."""
    from probecommit.core.likelihood import GaussianLikelihood
    from probecommit.tasks.insertion.model import InsertionModel

    model = InsertionModel()
    runs = {}
    for name, kernels in (("numpy", belief.FilterKernels()), ("numba", fast_belief.KERNELS)):
        pf = belief.ParticleFilter(model, GaussianLikelihood(model.sigma), n_particles=512, kernels=kernels)
        rngs = [np.random.default_rng(i) for i in range(12)]
        state = pf.initial(rngs)
        for j in range(6):
            u = np.full(12, model.probe_grid[j % len(model.probe_grid)][0])
            y = np.where(np.arange(12) % 2 == 0, -1.2, 0.0)[:, None]
            state = pf.update(state, u, y, rngs)
        set_kernels = executors.NUMPY_KERNELS if name == "numpy" else fast_executors.KERNELS
        runs[name] = state, executors.ProbeRobust(model, kernels=set_kernels).act(state.particles, state.weights, 0.8)
    (s0, c0), (s1, c1) = runs["numpy"], runs["numba"]
    np.testing.assert_allclose(s1.log_weights, s0.log_weights, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(s1.particles, s0.particles, rtol=1e-10, atol=1e-10)
    np.testing.assert_array_equal(c1.mask, c0.mask)
    np.testing.assert_array_equal(c1.index, c0.index)
