"""Compiled kernels agree bit for bit with their NumPy paths."""

from __future__ import annotations

import numpy as np
import pytest

from probecommit.core import kernels
from probecommit.core.executors import (
    interval_success_counts,
    interval_success_counts_numpy,
    scaled_interval_success_counts,
)

pytestmark = pytest.mark.skipif(not kernels.HAVE_KERNELS, reason="numba not installed (pip install 'probecommit[fast]')")


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


def test_interval_counts_scan_and_difference_paths_agree_with_numpy():
    """A span of at most ``_SCAN_ACTIONS_MAX`` actions is counted action by action, a wider one
    through a difference array: on a 601-action grid, rows whose retained intervals span a few
    actions up to hundreds, a row with nothing retained and one with one interval all count
    as NumPy does."""
    grid = np.round(np.arange(-30.0, 30.0 + 1e-9, 0.1), 10)
    rng = np.random.default_rng(5)
    x = rng.uniform(-1.0, 1.0, (30, 400)) * np.geomspace(0.05, 30.0, 30)[:, None]
    x[:, :50] = np.round(x[:, :50] * 10) / 10  # ends on grid points
    w = rng.uniform(0.0, 1.0, (30, 400))
    lo, hi = x - w, x + w
    lo[2, 3], hi[4, 5] = np.nan, np.nan
    mask = rng.random((30, 400)) < 0.7
    mask[0] = False
    mask[1] = False
    mask[1, 17] = True
    spans = np.array([np.nanmax(hi[e][mask[e]]) - np.nanmin(lo[e][mask[e]]) for e in range(2, 30)]) / 0.1
    assert np.any(spans > kernels._SCAN_ACTIONS_MAX) and np.any(spans <= kernels._SCAN_ACTIONS_MAX)
    expected = interval_success_counts_numpy(lo, hi, mask, grid)
    np.testing.assert_array_equal(interval_success_counts(lo, hi, mask, grid), expected)
    np.testing.assert_array_equal(scaled_interval_success_counts(x, w, 1.0, mask, grid),
                                  interval_success_counts_numpy(x - w, x + w, mask, grid))
    assert expected[1].sum() > 0 and expected[0].sum() == 0


@pytest.mark.parametrize("grid", [
    np.round(np.arange(-10.0, 10.0 + 1e-9, 0.5), 10),  # insertion's aims
    np.linspace(-1.0, 1.0, 41),  # a spacing that is not a binary fraction
    np.linspace(-1.0, 1.0, 41) + 1e-12 * np.random.default_rng(2).standard_normal(41),  # "even" within tolerance only
    np.sort(np.random.default_rng(7).uniform(-10, 10, 41)),  # uneven: the walk
])
def test_each_interval_end_is_numpys_searchsorted(grid):
    """One scenario per row, so the counts show each end's position alone: the kernel's guess
    and walk give NumPy's ``searchsorted`` at grid points, one ulp either side, near misses,
    beyond the grid and at the non-finite values."""
    near = np.concatenate([grid, np.nextafter(grid, np.inf), np.nextafter(grid, -np.inf), grid + 1e-13, grid - 1e-13,
                           (grid[1:] + grid[:-1]) / 2])
    values = np.concatenate([near, np.random.default_rng(1).uniform(2 * grid[0], 2 * grid[-1], 500),
                             [np.inf, -np.inf, np.nan, 1e300, -1e300, 0.0, -0.0]])[:, None]
    mask = np.ones_like(values, dtype=bool)
    wide = np.full_like(values, 1e308)
    # The mean spacing passed for any grid, even the uneven one, whose first guesses are then
    # wrong by several cells: the walk still ends at the exact answer.
    mean_step = (grid[-1] - grid[0]) / (len(grid) - 1)
    for lo, hi in ((values, wide), (-wide, values)):
        expected = interval_success_counts_numpy(lo, hi, mask, grid)
        np.testing.assert_array_equal(interval_success_counts(lo, hi, mask, grid), expected)
        np.testing.assert_array_equal(kernels._interval_success_counts(lo, hi, mask, grid, mean_step), expected)
    with np.errstate(invalid="ignore"):  # inf - inf: a NaN end, which sorts last
        centre, half = values, np.full_like(values, np.inf)
        np.testing.assert_array_equal(scaled_interval_success_counts(centre, half, 1.0, mask, grid),
                                      interval_success_counts_numpy(centre - half, centre + half, mask, grid))


@pytest.mark.parametrize("margin", [1.0, 0.73, 1.37])
def test_scaled_interval_counts_match_counting_the_numpy_ends(margin):
    """The kernel forms centre -+ half * margin per scenario: the same ends as NumPy's, bit for bit
    (random doubles would expose a fused multiply-add), from a strided centre too."""
    rng = np.random.default_rng(4)
    grid = np.round(np.arange(-10.0, 10.0 + 1e-9, 0.5), 10)
    theta = rng.uniform(-12, 12, (40, 500, 2))
    theta[:, :60, 0] = np.round(theta[:, :60, 0] * 2) / 2
    centre = theta[..., 0]  # a strided view, as a model's parts give it
    half = rng.uniform(0.0, 2.0, (40, 500))
    half[:, :60] = 0.5 * rng.integers(0, 4, (40, 60))  # ends exactly on grid points when the margin is one
    mask = rng.random((40, 500)) < 0.8
    width = half * margin
    expected = interval_success_counts_numpy(centre - width, centre + width, mask, grid)
    np.testing.assert_array_equal(scaled_interval_success_counts(centre, half, margin, mask, grid), expected)
    assert not centre.flags.c_contiguous and expected.sum() > 0


@pytest.mark.parametrize("margin", [1.0, 0.73, 1.37])
def test_affine_interval_counts_equal_counting_the_models_parts(margin):
    """Insertion's parts ``(x, 0.6 c + 1.1)`` formed per retained scenario inside the kernel give
    the counts of the NumPy ends the model's ``success_interval`` forms, bit for bit, with ends
    on grid points and clearances where a fused multiply-add would round otherwise."""
    from probecommit.tasks.insertion.model import InsertionModel

    model = InsertionModel(margin=margin)
    rng = np.random.default_rng(11)
    grid = np.asarray(model.action_grid, dtype=float).reshape(-1)
    theta = np.stack([rng.uniform(-12, 12, (40, 500)), rng.uniform(-1.5, 3.0, (40, 500))], axis=-1)
    theta[:, :60, 0] = np.round(theta[:, :60, 0] * 2) / 2
    theta[:, :60, 1] = rng.choice([-1.0, 0.0, 0.65, 1.5, 2.4], (40, 60))  # half-widths 0.5, 1.1, ...: ends on the grid
    mask = rng.random((40, 500)) < 0.8
    lo, hi = model.success_interval(theta)
    expected = interval_success_counts_numpy(lo, hi, mask, grid)
    kept = np.full(40, -1)
    got = kernels.affine_interval_success_counts_compiled(theta, model.success_interval_affine(), margin, mask, grid, kept)
    np.testing.assert_array_equal(got, expected)
    np.testing.assert_array_equal(kept, mask.sum(axis=-1))
    assert expected.sum() > 0


def test_only_a_model_whose_parts_are_insertions_declares_them_affine():
    from probecommit.tasks.insertion.model import InsertionModel
    from probecommit.tasks.rig.model import RigModel

    theta = np.random.default_rng(2).uniform(0.5, 1.5, (3, 7, 2))
    centre_at, width_at, slope, intercept = InsertionModel().success_interval_affine()
    centre, half = InsertionModel().success_interval_parts(theta)
    np.testing.assert_array_equal(theta[..., centre_at], centre)
    np.testing.assert_array_equal(theta[..., width_at] * slope + intercept, half)
    assert RigModel().success_interval_affine() is None  # the rig's window is its own


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


@pytest.mark.parametrize("n", [1, 7, 8, 9, 127, 128, 129, 136, 255, 256, 1000, 1024, 1033, 4096, 10007, 16384, 32768])
def test_pairwise_sum_follows_numpy_bit_for_bit(n):
    rng = np.random.default_rng(n)
    rows = rng.standard_normal((40, n)) * np.exp(rng.uniform(-30, 30, (40, n)))  # sums that round a lot
    ours = np.array([kernels._row_sum(row) for row in rows])
    np.testing.assert_array_equal(ours, np.sum(rows, axis=-1))


def test_repeated_additions_match_the_plain_loop_bit_for_bit():
    """``_add_repeated`` jumps through each binade of a running sum: its totals and stopping
    points equal adding one at a time, for weights of every scale, exact powers of two (a
    resampled 1/1024), values halfway between two multiples of the spacing, zeros, sums
    starting at zero, subnormal or above the value, targets reached or not."""
    rng = np.random.default_rng(17)
    m = 4000
    values = rng.random(m) * 10.0 ** rng.integers(-12, 1, m)
    values[:200] = 2.0 ** -rng.integers(1, 40, 200)  # powers of two: sums exact for a while
    values[200:300] = (2 * rng.integers(1, 2**20, 100) + 1) * 2.0 ** -60  # odd multiples: halfway cases later
    values[300:320] = 0.0
    totals = np.where(rng.random(m) < 0.4, 0.0, rng.random(m) * 10.0 ** rng.integers(-8, 1, m))
    totals[200:300] = rng.uniform(2.0 ** -7, 2.0 ** -6, 100)  # spacing 2^-59 there: the odd multiples lie halfway
    totals[320:340] = 5e-324 * rng.integers(1, 100, 20)  # subnormal starts
    totals[340:360] = -0.0
    counts = rng.integers(0, 3000, m)
    targets = np.where(rng.random(m) < 0.3, np.inf, totals + values * counts * rng.uniform(0.0, 1.2, m))
    targets[360:380] = totals[360:380]  # reached at the first addition
    steps, got = np.empty(m, dtype=np.int64), np.empty(m)
    kernels._add_repeated_rows(totals, values, counts, targets, steps, got)
    for i in range(m):
        total, taken = float(totals[i]), 0
        while taken < counts[i]:
            total += float(values[i])
            taken += 1
            if total >= targets[i]:
                break
        assert (steps[i], np.float64(got[i]).tobytes()) == (taken, np.float64(total).tobytes()), i
    assert np.any(steps < counts) and np.any(steps == counts)


def _weight_cases():
    rng = np.random.default_rng(11)
    e, n = 60, 1024
    cases = {
        "continuous": np.exp(3 * rng.standard_normal((e, n))),
        "concentrated": np.exp(30 * rng.standard_normal((e, n))),
        "few values (a tap reading)": np.exp(-2.0 * rng.integers(0, 4, (e, n))),
        "all tied (just resampled)": np.ones((e, n)),
        "mostly zero": np.where(rng.random((e, n)) < 0.9, 0.0, rng.random((e, n))),
        "one bucket, all distinct": 1 + 1e-3 * rng.random((e, n)),
        "tiny rows": rng.random((e, 5)),
        # Particle counts whose pairwise tree is not perfect (sums of products through an array).
        "1000 particles": np.exp(3 * rng.standard_normal((e, 1000))),
        "200 particles": np.exp(-2.0 * rng.integers(0, 4, (e, 200))),
        # A resampled belief after a few taps: runs of copies sharing a weight.
        "runs of few values": np.repeat(np.exp(-3.0 * rng.integers(0, 5, (e, n // 8))), 8, axis=1),
        # At and just past the few-weight table's capacity (16 distinct values).
        "sixteen values": np.exp(-0.25 * rng.integers(0, 16, (e, n))),
        "seventeen values": np.exp(-0.25 * np.concatenate([np.arange(17)[None].repeat(e, 0),
                                                           rng.integers(0, 17, (e, n - 17))], axis=1)),
        # Two values, the first particle's the lighter or the heavier (the two-weight table's rows).
        "two values": np.where(rng.random((e, n)) < 0.3, 1.0, np.exp(-2.0)),
        "two values, heavier first": np.concatenate([np.ones((e, 1)), np.where(rng.random((e, n - 1)) < 0.7, np.exp(-2.0), 1.0)],
                                                     axis=1),
        "two values and a signed zero": np.where(rng.random((e, n)) < 0.5, np.where(rng.random((e, n)) < 0.5, -0.0, 0.0), 1.0),
        # -0.0 ties with 0.0 (the stable order keeps them in index order).
        "signed zeros": np.where(rng.random((e, n)) < 0.5, np.where(rng.random((e, n)) < 0.5, -0.0, 0.0),
                                 np.exp(-rng.integers(0, 3, (e, n)))),
    }
    return {name: w / w.sum(axis=1, keepdims=True) for name, w in cases.items()}


@pytest.mark.parametrize("name", list(_weight_cases()))
@pytest.mark.parametrize("nu", [0.05, 0.5, 0.8, 0.999, 1.0, 1.5, "per-row"])
@pytest.mark.parametrize("latents", [2, 3])  # two: the mass and both weighted sums from one pass per leaf
def test_retained_summary_matches_numpy(name, nu, latents):
    from probecommit.core.retained import retained_summary, retained_summary_numpy

    weights = _weight_cases()[name]
    rng = np.random.default_rng(5)
    e, n = weights.shape
    nu_rows = rng.uniform(0.05, 1.0, e) if nu == "per-row" else np.full(e, nu)
    z = rng.standard_normal((e, n))
    z[0, :3] = np.nan  # a NaN in the decision coordinate propagates only if retained
    z[1:4] = np.where(rng.random((3, n)) < 0.5, 0.0, -0.0) + np.where(rng.random((3, n)) < 0.1, 1.0, 0.0)  # zeros
    particles = rng.standard_normal((e, n, latents))
    fast = retained_summary(weights, nu_rows, z, particles)
    slow = retained_summary_numpy(weights, nu_rows, z, particles)
    for a, b in zip(fast, slow):
        np.testing.assert_array_equal(a, b)
    if kernels.HAVE_KERNELS:  # the set's interval in the order of a plain scan, signed zeros included
        mask, lo, hi, _ = fast
        for row in range(e):
            low, high = np.inf, -np.inf
            for value, keep in zip(z[row].tolist(), mask[row].tolist()):
                low = min(low, value if keep else np.inf)
                high = max(high, value if keep else -np.inf)
            if np.isnan(z[row][mask[row]]).any():
                low = high = np.nan
            assert np.float64(lo[row]).tobytes() == np.float64(low).tobytes()
            assert np.float64(hi[row]).tobytes() == np.float64(high).tobytes()


def test_retained_summary_leaves_odd_weights_to_numpy():
    weights = np.array([[0.5, 0.6, -0.1]])
    assert kernels.retained_summary_compiled(weights, np.array([0.8]), np.zeros((1, 3)), np.zeros((1, 3, 1))) is None


@pytest.mark.parametrize("name", list(_weight_cases()))
def test_coverage_score_matches_numpy(name):
    from probecommit.core.retained import coverage_score, coverage_score_numpy, coverage_with_hull

    weights = _weight_cases()[name]
    rng = np.random.default_rng(9)
    e, n = weights.shape
    z = np.round(rng.standard_normal((e, n)), 1)  # ties in z, and truths exactly on particles
    z_true = np.concatenate([z[: e // 3, 0], rng.uniform(-1, 1, e - e // 3 - 4), [-9.0, 9.0, z[0].min(), z[0].max()]])
    np.testing.assert_array_equal(coverage_score(z, weights, z_true, 20.0), coverage_score_numpy(z, weights, z_true, 20.0))
    # With the hull, from a strided coordinate (one latent of the particles), signed zeros included.
    particles = np.stack([z, rng.standard_normal((e, n))], axis=-1)
    particles[2, :2, 0], particles[3, :2, 0] = [0.0, -0.0], [-0.0, 0.0]
    particles[2:4, 2:, 0] = np.abs(particles[2:4, 2:, 0]) + 0.5  # rows whose hull starts at a zero
    particles[4:6, :2, 0], particles[4:6, 2:, 0] = [[-0.0, 0.0], [0.0, -0.0]], -np.abs(particles[4:6, 2:, 0]) - 0.5
    strided = particles[..., 0]
    score, low, high = coverage_with_hull(strided, weights, z_true, 20.0)
    rows = np.ascontiguousarray(strided)
    for ours, numpys in ((score, coverage_score_numpy(rows, weights, z_true, 20.0)), (low, rows.min(axis=1)),
                         (high, rows.max(axis=1))):
        assert np.array_equal(ours.view(np.int64), numpys.view(np.int64))
    z[1, 0] = np.nan  # outside the kernel's domain: the NumPy path answers
    assert kernels.coverage_score_compiled(weights, z, z_true, 20.0) is None
    np.testing.assert_array_equal(coverage_with_hull(z, weights, z_true, 20.0)[1], z.min(axis=1))


def test_jitter_resampled_matches_numpy():
    from probecommit.core.belief import jitter_resampled

    rng = np.random.default_rng(4)
    particles = rng.uniform(-1, 1, (9, 64, 3))
    rows = np.array([0, 4, 8])
    parents = np.sort(rng.integers(0, 64, (3, 64)), axis=1)
    noise = rng.standard_normal((3, 64, 3)) * 5  # pushes many copies past the box
    scale, low, high = np.array([0.1, 0.2, 0.0]), np.full(3, -1.0), np.full(3, 1.0)
    fast = jitter_resampled(particles, rows, parents, noise, scale, low, high)
    expected = particles.copy()
    expected[rows] = np.clip(np.take_along_axis(particles[rows], parents[:, :, None], axis=1) + scale * noise, low, high)
    np.testing.assert_array_equal(fast, expected)
    np.testing.assert_array_equal(fast[[1, 2, 3]], particles[[1, 2, 3]])  # rows that did not resample


@pytest.mark.parametrize("n", [1, 7, 128, 1000, 1024, 4099])
def test_weighted_variance_matches_numpy(n):
    """Posterior variance: the same products summed in NumPy's pairwise order, strided z included."""
    from probecommit.core.retained import weighted_variance, weighted_variance_numpy

    rng = np.random.default_rng(n)
    particles = rng.uniform(-10, 10, (6, n, 2))
    weights = rng.dirichlet(np.ones(n), 6)
    weights[1] = 1.0 / n  # uniform, as after a resampling
    weights[2, : n // 2] = 0.0
    z = particles[..., 0]  # strided, as a commit passes it
    z_nan = z.copy()
    z_nan[3, n // 2] = np.nan
    for values in (z, z_nan, np.ascontiguousarray(z)):
        assert np.array_equal(kernels.weighted_variance_compiled(values, weights), weighted_variance_numpy(values, weights),
                              equal_nan=True)
        assert np.array_equal(weighted_variance(values, weights), weighted_variance_numpy(values, weights), equal_nan=True)
    assert kernels.weighted_variance_compiled(z[0], weights[0]) is None  # 1-D: NumPy's path


@pytest.mark.parametrize("n", [1, 7, 64, 1023, 4099])
def test_exp_exact_is_numpy_exp_bit_for_bit(n):
    rng = np.random.default_rng(n)
    for trial in range(20):
        # Log-weights far below the best (results zero), at the subnormal edge, near the fast
        # path's floor, ordinary ones, and the non-finite cases.
        kinds = np.stack([rng.uniform(-3000, -746, n), rng.uniform(-746.5, -744, n), rng.uniform(-710, -690, n),
                          rng.uniform(-60, 5, n)])
        x = kinds[rng.integers(0, 4, n), np.arange(n)]
        x[rng.random(n) < 0.02] = -np.inf
        x[rng.random(n) < 0.01] = np.nan
        x[rng.random(n) < 0.01] = np.inf
        expected = np.exp(x).view(np.int64)
        assert np.array_equal(kernels.exp_exact(x).view(np.int64), expected)
        in_place = x.copy()
        assert kernels.exp_exact(in_place, out=in_place) is in_place
        assert np.array_equal(in_place.view(np.int64), expected)
        rows = x.reshape(1, n)  # a 2-D row of weights, and a strided view (NumPy's own exp then)
        assert np.array_equal(kernels.exp_exact(rows).view(np.int64).ravel(), expected)
        assert np.array_equal(kernels.exp_exact(x[::2]).view(np.int64), expected[::2])


def _numpy_normalized(log_weights):
    """``core.belief.normalized_weights`` the unfused way: ``_normalize``, NumPy's ``exp`` and the ESS."""
    from probecommit.core.belief import _normalize, effective_sample_size

    log_w, log_norm = _normalize(log_weights.copy())
    weights = np.exp(log_w)
    return log_w, log_norm, weights, effective_sample_size(weights)


@pytest.mark.parametrize("n", [1, 5, 128, 1000, 1024, 4096])
def test_normalized_weights_match_numpy_bit_for_bit(n):
    from probecommit.core.belief import normalized_weights

    rng = np.random.default_rng(n)
    e = 50
    # A tap's two levels (ties in runs), continuous log-likelihoods, particles thousands of nats
    # below the best (weights exactly zero), at the subnormal edge, and impossible ones (-inf).
    log_weights = np.where(rng.random((e, n)) < 0.5, -0.5, -450.0) + np.repeat(rng.uniform(-5, 5, (e, 1)), n, 1)
    log_weights[e // 2:] = rng.uniform(-60, 0, (e - e // 2, n)) * rng.choice([1.0, 30.0], (e - e // 2, 1))
    impossible = rng.random((e, n)) < 0.05
    impossible[:5] = False  # rows without a zero weight (their zeroing passes are skipped)
    log_weights[impossible] = -np.inf
    log_weights[:, 1 % n] = -720.0  # subnormal after the shift; after normalizing in the continuous rows
    log_weights[:, 0] = 0.0  # every row keeps a finite best
    compiled = kernels.normalized_weights_compiled(log_weights)
    assert compiled is not None
    ours = normalized_weights(log_weights.copy())
    for a, b in zip(ours, _numpy_normalized(log_weights)):
        assert np.array_equal(a.view(np.int64), np.asarray(b).view(np.int64))


@pytest.mark.parametrize("case", ["lost row", "nan", "plus inf"])
def test_normalized_weights_leave_the_odd_rows_to_numpy(case):
    from probecommit.core.belief import normalized_weights

    log_weights = np.log(np.random.default_rng(3).random((4, 64)))
    log_weights[2, 1:] = {"lost row": -np.inf, "nan": np.nan, "plus inf": np.inf}[case]
    log_weights[2, 0] = -np.inf if case == "lost row" else log_weights[2, 0]
    assert kernels.normalized_weights_compiled(log_weights) is None
    ours = normalized_weights(log_weights.copy())
    for a, b in zip(ours, _numpy_normalized(log_weights)):
        assert np.array_equal(a.view(np.int64), np.asarray(b).view(np.int64))
