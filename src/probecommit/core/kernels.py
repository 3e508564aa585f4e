"""Compiled kernels (numba) for the hot loops of the executor, with NumPy fallbacks.

numba is an optional, pinned dependency (``pip install 'probecommit[fast]'``, part of
``all``). Every kernel here has a NumPy twin in the calling module and a test that the
two agree bit for bit (``tests/core/test_kernels.py``); without numba, or with
``PROBECOMMIT_NO_NUMBA=1``, the NumPy path runs. The kernels run from a module built
ahead of time when it is current, else through numba's JIT with its on-disk cache
(:mod:`probecommit.core.compiled`): either way, the same functions below.
"""

from __future__ import annotations

import math

import numpy as np

from probecommit.core.compiled import AVAILABLE as HAVE_KERNELS
from probecommit.core.compiled import helper, kernel

#: A count compares every grid action inside the retained intervals' span with each interval
#: when the span covers at most this many actions; a wider span takes a difference array.
_SCAN_ACTIONS_MAX = 64

if HAVE_KERNELS:

    @helper(inline=True)
    def _position(actions, value, inv_step, right):  # pragma: no cover - compiled
        """``searchsorted(actions, value, side)`` on a sorted grid; exact.

        An arithmetic first guess on an evenly spaced grid (``inv_step`` = 1 / spacing > 0;
        a product, not a division, which costs more than the rest of the guess), or the
        middle otherwise, then walked to the exact answer with the grid's own comparisons.
        """
        n = actions.shape[0]
        if value != value:  # NaN sorts last, as in NumPy
            return n
        if inv_step > 0.0:
            guess = (value - actions[0]) * inv_step
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

    @helper(inline=True)
    def _add_interval(diff, actions, lo, hi, inv_step):  # pragma: no cover - compiled
        """Add one scenario's open interval ``(lo, hi)`` to the difference array of the grid actions."""
        first = _position(actions, lo, inv_step, True)
        last = _position(actions, hi, inv_step, False)
        if first < last:
            diff[first] += 1
            diff[last] -= 1

    @helper(inline=True)
    def _take_counts(diff, out_row):  # pragma: no cover - compiled
        """Write the counts of a difference array into ``out_row`` and clear it for the next episode."""
        run = 0
        for a in range(out_row.shape[0]):
            run += diff[a]
            out_row[a] = run
        diff[:] = 0

    @helper(inline=True)
    def _count_scratch(n_e, n_s, actions, step):  # pragma: no cover - compiled
        """The counts ``[E, A]`` (zeros), the difference array ``[A + 1]``, the inverse grid step
        and the retained intervals' ends ``[S]`` (twice) of a count."""
        out = np.zeros((n_e, actions.shape[0]), dtype=np.int64)
        diff = np.zeros(actions.shape[0] + 1, dtype=np.int64)
        return out, diff, (1.0 / step if step > 0.0 else 0.0), np.empty(n_s), np.empty(n_s)

    @helper(inline=True)
    def _keep_interval(lo_kept, hi_kept, k, low, high, keep):  # pragma: no cover - compiled
        """Write an interval at slot ``k`` of the kept ends; the next slot (``k + 1`` if ``keep``).

        Every scenario is written and only a retained one kept, so the retained intervals are
        gathered without a branch on the mask. A NaN end becomes +inf, which counts as
        :func:`_position` sorts NaN: a NaN low end is never counted, a NaN high end bounds nothing.
        """
        lo_kept[k] = low if low == low else np.inf
        hi_kept[k] = high if high == high else np.inf
        return k + keep

    @helper()
    def _count_kept_intervals(lo, hi, k, actions, inv_step, diff, out_row):  # pragma: no cover - compiled
        """``out_row[a]`` (zeros on entry) = how many of the first ``k`` intervals hold
        ``lo < actions[a] < hi``.

        Each action inside the intervals' span is compared with every kept interval (a loop the
        compiler vectorizes) when the span covers at most ``_SCAN_ACTIONS_MAX`` actions; a wider
        one adds each interval to a difference array. Both count the same predicate.
        """
        l0 = l1 = l2 = l3 = np.inf  # four running extremes: one would be a chain of dependent minima
        h0 = h1 = h2 = h3 = -np.inf
        s = 0
        stop = k - k % 4
        while s < stop:
            l0, l1, l2, l3 = min(l0, lo[s]), min(l1, lo[s + 1]), min(l2, lo[s + 2]), min(l3, lo[s + 3])
            h0, h1, h2, h3 = max(h0, hi[s]), max(h1, hi[s + 1]), max(h2, hi[s + 2]), max(h3, hi[s + 3])
            s += 4
        lo_min, hi_max = min(min(l0, l1), min(l2, l3)), max(max(h0, h1), max(h2, h3))
        while s < k:
            lo_min, hi_max = min(lo_min, lo[s]), max(hi_max, hi[s])
            s += 1
        first = _position(actions, lo_min, inv_step, True)
        last = _position(actions, hi_max, inv_step, False)
        if last - first <= _SCAN_ACTIONS_MAX:
            for a in range(first, last):
                value = actions[a]
                count = 0
                for s in range(k):
                    count += (lo[s] < value) & (value < hi[s])
                out_row[a] = count
        else:
            for s in range(k):
                _add_interval(diff, actions, lo[s], hi[s], inv_step)
            _take_counts(diff, out_row)

    @kernel("i8[:, ::1](f8[:, ::1], f8[:, ::1], b1[:, ::1], f8[::1], f8)")
    def _interval_success_counts(lo, hi, mask, actions, step):  # pragma: no cover - compiled
        n_e, n_s = mask.shape
        out, diff, inv_step, lo_kept, hi_kept = _count_scratch(n_e, n_s, actions, step)
        for e in range(n_e):
            k = 0
            for s in range(n_s):
                k = _keep_interval(lo_kept, hi_kept, k, lo[e, s], hi[e, s], mask[e, s])
            _count_kept_intervals(lo_kept, hi_kept, k, actions, inv_step, diff, out[e])
        return out


if HAVE_KERNELS:

    @kernel(
        "i8[:, ::1](f8[:, ::1], f8[:, ::1], f8, b1[:, ::1], f8[::1], f8)",
        "i8[:, ::1](f8[:, :], f8[:, ::1], f8, b1[:, ::1], f8[::1], f8)",
    )
    def _scaled_interval_success_counts(centre, half, margin, mask, actions, step):  # pragma: no cover - compiled
        """:func:`_interval_success_counts` of ``centre -+ half * margin``, made per retained
        scenario here (the same IEEE operations as NumPy's, so the same ends)."""
        n_e, n_s = mask.shape
        out, diff, inv_step, lo_kept, hi_kept = _count_scratch(n_e, n_s, actions, step)
        for e in range(n_e):
            k = 0
            for s in range(n_s):
                width = half[e, s] * margin
                k = _keep_interval(lo_kept, hi_kept, k, centre[e, s] - width, centre[e, s] + width, mask[e, s])
            _count_kept_intervals(lo_kept, hi_kept, k, actions, inv_step, diff, out[e])
        return out

    @kernel("i8[:, ::1](f8[:, :, ::1], i8, i8, f8, f8, f8, b1[:, ::1], f8[::1], f8, i8[::1])")
    def _affine_interval_success_counts(scenarios, centre_at, width_at, slope, intercept, margin, mask, actions,
                                        step, kept):  # pragma: no cover - compiled
        """:func:`_scaled_interval_success_counts` with ``centre = scenarios[..., centre_at]`` and
        ``half = slope * scenarios[..., width_at] + intercept`` formed per retained scenario (a
        product, then a sum, as NumPy forms them), so no ``[E, N]`` part is materialized; ``kept[e]``
        takes the row's retained count (``mask.sum(axis=-1)``, which NumPy takes slowly of booleans)."""
        n_e, n_s = mask.shape
        out, diff, inv_step, lo_kept, hi_kept = _count_scratch(n_e, n_s, actions, step)
        for e in range(n_e):
            k = 0
            for s in range(n_s):
                half = scenarios[e, s, width_at] * slope
                half = half + intercept
                width = half * margin
                centre = scenarios[e, s, centre_at]
                k = _keep_interval(lo_kept, hi_kept, k, centre - width, centre + width, mask[e, s])
            _count_kept_intervals(lo_kept, hi_kept, k, actions, inv_step, diff, out[e])
            kept[e] = k
        return out


if HAVE_KERNELS:

    @kernel("i8[:, ::1](f8[:, ::1], f8[::1])")
    def _systematic_resample(weights, offsets):  # pragma: no cover - compiled
        n_rows, n = weights.shape
        out = np.empty((n_rows, n), dtype=np.int64)
        cumulative = np.empty(n)
        positions = np.empty(n)
        for r in range(n_rows):
            total = 0.0
            for i in range(n):
                total += weights[r, i]
                cumulative[i] = total
            cumulative[n - 1] = 1.0
            offset = offsets[r]
            for i in range(n):  # the divisions apart, in a loop of their own (vectorized)
                positions[i] = (offset + i) / n
            j = 0
            for i in range(n):
                # searchsorted(cumulative, position, side="right"), walking forward: positions increase
                position = positions[i]
                while j < n and cumulative[j] <= position:
                    j += 1
                out[r, i] = j if j < n else n - 1
        return out


if HAVE_KERNELS:

    @kernel("f8[:, :, ::1](f8[:, :, ::1], i8[::1], i8[:, ::1], f8[:, :, ::1], f8[::1], f8[::1], f8[::1])")
    def _jitter_resampled(particles, rows, parents, noise, scale, low, high):  # pragma: no cover - compiled
        out = particles.copy()
        n_rows, n = parents.shape
        d = particles.shape[2]
        for i in range(n_rows):
            r = rows[i]
            for k in range(n):
                p = parents[i, k]
                for j in range(d):
                    value = particles[r, p, j] + scale[j] * noise[i, k, j]
                    # np.clip: NaN stays NaN, otherwise max with low, then min with high
                    if value == value:
                        value = min(max(value, low[j]), high[j])
                    out[r, k, j] = value
        return out


def jitter_resampled_compiled(particles: np.ndarray, rows: np.ndarray, parents: np.ndarray, noise: np.ndarray,
                              scale: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray | None:
    """The compiled resample-and-jitter step (see ``core.belief.jitter_resampled``), or None without compiled kernels."""
    if not HAVE_KERNELS:
        return None
    f64 = np.float64
    return _jitter_resampled(np.ascontiguousarray(particles, dtype=f64), np.ascontiguousarray(rows, dtype=np.int64),
                             np.ascontiguousarray(parents, dtype=np.int64), np.ascontiguousarray(noise, dtype=f64),
                             np.ascontiguousarray(scale, dtype=f64), np.ascontiguousarray(low, dtype=f64),
                             np.ascontiguousarray(high, dtype=f64))


def systematic_resample_compiled(weights: np.ndarray, offsets: np.ndarray) -> np.ndarray | None:
    """The compiled systematic resampler (see ``core.belief.systematic_resample``), or None without compiled kernels."""
    if not HAVE_KERNELS:
        return None
    return _systematic_resample(np.ascontiguousarray(weights, dtype=np.float64), np.ascontiguousarray(offsets, dtype=np.float64))


def scaled_interval_success_counts_compiled(centre: np.ndarray, half: np.ndarray, margin: float, mask: np.ndarray,
                                            actions: np.ndarray) -> np.ndarray | None:
    """The compiled count over ``centre -+ half * margin`` (see ``core.executors.scaled_interval_success_counts``),
    or None without compiled kernels. ``centre`` may be a strided view (one latent of the scenarios): read in place."""
    if not HAVE_KERNELS:
        return None
    actions = np.ascontiguousarray(actions, dtype=np.float64)
    return _scaled_interval_success_counts(np.asarray(centre, dtype=np.float64), np.asarray(half, dtype=np.float64),
                                           float(margin), np.ascontiguousarray(mask, dtype=np.bool_), actions,
                                           uniform_step(actions))


def affine_interval_success_counts_compiled(scenarios: np.ndarray, affine: tuple[int, int, float, float], margin: float,
                                            mask: np.ndarray, actions: np.ndarray,
                                            kept: np.ndarray | None = None) -> np.ndarray | None:
    """The compiled count over ``centre -+ half * margin`` of a model whose parts are affine in its
    latents (``TaskModel.success_interval_affine``), read from ``scenarios[E, N, d]`` in place;
    None without compiled kernels. ``kept`` (int64 ``[E]``), if given, takes each row's retained count."""
    if not HAVE_KERNELS:
        return None
    centre_at, width_at, slope, intercept = affine
    actions = np.ascontiguousarray(actions, dtype=np.float64)
    kept = np.empty(mask.shape[0], dtype=np.int64) if kept is None else kept
    return _affine_interval_success_counts(np.ascontiguousarray(scenarios, dtype=np.float64), int(centre_at),
                                           int(width_at), float(slope), float(intercept), float(margin),
                                           np.ascontiguousarray(mask, dtype=np.bool_), actions, uniform_step(actions),
                                           kept)


def uniform_step(actions: np.ndarray) -> float:
    """The spacing of an evenly spaced grid (within 1e-9 relative), else 0."""
    n = actions.shape[0]
    if n < 3:
        return 0.0
    step = (actions[-1] - actions[0]) / (n - 1)
    return float(step) if step > 0 and np.max(np.abs(np.diff(actions) - step)) <= 1e-9 * step else 0.0


def interval_success_counts_compiled(lo: np.ndarray, hi: np.ndarray, mask: np.ndarray, actions: np.ndarray) -> np.ndarray | None:
    """The compiled interval count (see ``core.executors.interval_success_counts``), or None without compiled kernels."""
    if not HAVE_KERNELS:
        return None
    actions = np.ascontiguousarray(actions, dtype=np.float64)
    return _interval_success_counts(np.ascontiguousarray(lo, dtype=np.float64), np.ascontiguousarray(hi, dtype=np.float64),
                                    np.ascontiguousarray(mask, dtype=np.bool_), actions, uniform_step(actions))


# --- The top-weight retained set ------------------------------------------------------------
#
# NumPy's path (core.retained) sorts every row in full (a stable argsort) and takes the
# cumulative mass in that order. The kernel gets the same bits without the full sort. A row
# whose prefix lies among its ``_FEW_WEIGHTS`` heaviest distinct weights (a tap belief's) needs no
# order at all: the cumulative sums are those of its distinct values from the largest down
# (``_few_weight_prefix``; the coverage score's table of them, ``_few_weight_table``). Otherwise it
# buckets the weights by their leading 16 bits (sign, exponent, four mantissa bits: one
# bucket per sixteenth of an octave below the row's largest weight), finds the buckets that
# certainly hold the prefix's mass, and sorts only those candidates. Every non-candidate
# weighs strictly less than every candidate, so the candidates' order and cumulative sums
# are exactly the first entries of the full sort's. Sums that NumPy takes with ``np.sum``
# follow its pairwise summation bit for bit (``_pairwise_sum``; tested).

#: Buckets below the largest weight; anything 16 octaves down shares the last one.
_N_BUCKETS = 256
#: Slack on the bucket mass (summed in another order) before the candidates surely reach nu.
_BUCKET_SLACK = 1e-9
#: Buckets at most this long are sorted by insertion (they are usually ties or tiny).
_INSERTION_SORT_MAX = 48
#: A coverage prefix of at most this many particles is sorted directly, without buckets.
_FEW = 48
#: A row of at most this many distinct weights takes its prefix without ordering particles.
_FEW_WEIGHTS = 16

if HAVE_KERNELS:

    @helper(inline=True)
    def _block_sum(a, start, n):  # pragma: no cover - compiled
        """NumPy's pairwise-sum leaf (``n <= 128``): sequential below 8, else 8 running sums."""
        if n < 8:
            total = 0.0
            for i in range(n):
                total += a[start + i]
            return total
        r0, r1, r2, r3 = a[start], a[start + 1], a[start + 2], a[start + 3]
        r4, r5, r6, r7 = a[start + 4], a[start + 5], a[start + 6], a[start + 7]
        i = 8
        stop = n - n % 8
        while i < stop:
            r0 += a[start + i]
            r1 += a[start + i + 1]
            r2 += a[start + i + 2]
            r3 += a[start + i + 3]
            r4 += a[start + i + 4]
            r5 += a[start + i + 5]
            r6 += a[start + i + 6]
            r7 += a[start + i + 7]
            i += 8
        total = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        while i < n:
            total += a[start + i]
            i += 1
        return total

    @helper(inline=True)
    def _perfect_blocks(n, values):  # pragma: no cover - compiled
        """The number of 128-blocks when NumPy's pairwise tree over ``n > 128`` values is perfect
        (``n = 128 * 2^k``, and ``values`` holds a slot per block), else 0."""
        blocks = n // 128
        return blocks if n % 128 == 0 and blocks & (blocks - 1) == 0 and blocks <= values.shape[0] else 0

    @helper(inline=True)
    def _combine_levels(values, blocks):  # pragma: no cover - compiled
        """The sum of the perfect tree whose leaves are ``values[:blocks]``, pairs added level by level."""
        while blocks > 1:
            blocks //= 2
            for b in range(blocks):
                values[b] = values[2 * b] + values[2 * b + 1]
        return values[0]

    @helper()
    def _pairwise_sum_with(a, start, n, node_start, node_n, node_open, values):  # pragma: no cover - compiled
        """``np.sum(a[start:start + n])`` in NumPy's pairwise order: halves (rounded down to a
        multiple of 8) until blocks of at most 128. Iterative, with an explicit stack in the
        caller's scratch arrays (128 entries each; :func:`_pairwise_scratch`): numba's on-disk
        cache does not survive recursive functions, and a caller summing many rows allocates once."""
        if n <= 128:
            return _block_sum(a, start, n)
        blocks = _perfect_blocks(n, values)
        if blocks:
            # n = 128 * 2^k (N = 1024 particles, say): the halves are exact, the tree is perfect,
            # so its leaves are the 128-blocks in order, combined pairwise level by level.
            for b in range(blocks):
                values[b] = _block_sum(a, start + 128 * b, 128)
            return _combine_levels(values, blocks)
        # Pending nodes (start, length, children done?) and finished partial sums.
        top, n_values = 0, 0
        node_start[0], node_n[0], node_open[0] = start, n, False
        while top >= 0:
            s, m, expanded = node_start[top], node_n[top], node_open[top]
            top -= 1
            if m <= 128:
                values[n_values] = _block_sum(a, s, m)
                n_values += 1
            elif expanded:  # both halves summed: combine them (addition commutes exactly)
                n_values -= 1
                values[n_values - 1] = values[n_values - 1] + values[n_values]
            else:
                half = m // 2
                half -= half % 8
                top += 1
                node_start[top], node_n[top], node_open[top] = s, m, True
                top += 1
                node_start[top], node_n[top], node_open[top] = s + half, m - half, False
                top += 1
                node_start[top], node_n[top], node_open[top] = s, half, False
        return values[0]

    @helper(inline=True)
    def _block_dot(a, p, e, j, start, n):  # pragma: no cover - compiled
        """:func:`_block_sum` of the products ``a[i] * p[e, i, j]``, formed as it reads them."""
        if n < 8:
            total = 0.0
            for i in range(n):
                total += a[start + i] * p[e, start + i, j]
            return total
        r0, r1 = a[start] * p[e, start, j], a[start + 1] * p[e, start + 1, j]
        r2, r3 = a[start + 2] * p[e, start + 2, j], a[start + 3] * p[e, start + 3, j]
        r4, r5 = a[start + 4] * p[e, start + 4, j], a[start + 5] * p[e, start + 5, j]
        r6, r7 = a[start + 6] * p[e, start + 6, j], a[start + 7] * p[e, start + 7, j]
        i = start + 8
        stop = start + n - n % 8
        while i < stop:
            r0 += a[i] * p[e, i, j]
            r1 += a[i + 1] * p[e, i + 1, j]
            r2 += a[i + 2] * p[e, i + 2, j]
            r3 += a[i + 3] * p[e, i + 3, j]
            r4 += a[i + 4] * p[e, i + 4, j]
            r5 += a[i + 5] * p[e, i + 5, j]
            r6 += a[i + 6] * p[e, i + 6, j]
            r7 += a[i + 7] * p[e, i + 7, j]
            i += 8
        total = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        while i < start + n:
            total += a[i] * p[e, i, j]
            i += 1
        return total

    @helper()
    def _row_dot_with(a, p, e, j, product, node_start, node_n, node_open, values):  # pragma: no cover - compiled
        """``np.sum(a * p[e, :, j])`` bit for bit: the products summed in NumPy's pairwise order,
        formed inside the leaves when the tree is perfect (``N = 128 * 2^k``, or at most 128),
        else written to ``product`` and summed by :func:`_row_sum_with`."""
        n = a.shape[0]
        if n <= 128:
            return 0.0 + _block_dot(a, p, e, j, 0, n)
        blocks = _perfect_blocks(n, values)
        if blocks:
            for b in range(blocks):
                values[b] = _block_dot(a, p, e, j, 128 * b, 128)
            return 0.0 + _combine_levels(values, blocks)
        for i in range(n):
            product[i] = a[i] * p[e, i, j]
        return _row_sum_with(product, node_start, node_n, node_open, values)

    @helper()
    def _pairwise_scratch():  # pragma: no cover - compiled
        """The stack of :func:`_pairwise_sum_with`: 128 entries, enough for any row (a halving adds two)."""
        return (np.empty(128, dtype=np.int64), np.empty(128, dtype=np.int64), np.empty(128, dtype=np.bool_),
                np.empty(128))

    @helper()
    def _pairwise_sum(a, start, n):  # pragma: no cover - compiled
        """:func:`_pairwise_sum_with` with its own scratch."""
        node_start, node_n, node_open, values = _pairwise_scratch()
        return _pairwise_sum_with(a, start, n, node_start, node_n, node_open, values)

    @kernel("f8(f8[::1])")
    def _row_sum(a):  # pragma: no cover - compiled
        """``np.sum(a)`` of a contiguous row, bit for bit (the reduction starts from 0.0)."""
        return 0.0 + _pairwise_sum(a, 0, a.shape[0])

    @helper()
    def _row_sum_with(a, node_start, node_n, node_open, values):  # pragma: no cover - compiled
        """:func:`_row_sum` on the caller's scratch."""
        return 0.0 + _pairwise_sum_with(a, 0, a.shape[0], node_start, node_n, node_open, values)

    @helper()
    def _bucket_order(w, nu, order, buckets, counts, mass, starts):  # pragma: no cover - compiled
        """Counting-sort the particles of the buckets that certainly reach mass ``nu`` (all of
        them for ``nu`` past one) into ``order``, index order within a bucket.

        Returns the last bucket taken; ``counts[b]`` is bucket ``b``'s size.
        """
        n = w.shape[0]
        bits = w.view(np.int64)  # non-negative doubles order as their bit patterns do
        top = np.int64(0)
        for i in range(n):
            if bits[i] > top:
                top = bits[i]
        top >>= 48
        counts[:] = 0
        mass[:] = 0.0
        for i in range(n):
            b = top - (bits[i] >> 48)
            if b > _N_BUCKETS - 1:
                b = _N_BUCKETS - 1
            buckets[i] = b
            counts[b] += 1
            mass[b] += w[i]
        last = _N_BUCKETS - 1
        reached = 0.0
        for b in range(_N_BUCKETS):
            reached += mass[b]
            if reached >= nu + _BUCKET_SLACK:
                last = b
                break
        total = 0
        for b in range(last + 1):
            starts[b] = total
            total += counts[b]
        for i in range(n):
            b = buckets[i]
            if b <= last:
                order[starts[b]] = i
                starts[b] += 1
        return last

    @helper()
    def _sort_bucket(w, order, begin, end):  # pragma: no cover - compiled
        """Sort ``order[begin:end]`` (index order on entry) by descending weight, stably."""
        for i in range(begin + 1, end):
            if w[order[i]] > w[order[i - 1]]:
                break
        else:
            return  # ties in index order (a resampled belief): already sorted
        if end - begin <= _INSERTION_SORT_MAX:
            for i in range(begin + 1, end):
                item = order[i]
                value = w[item]
                j = i - 1
                while j >= begin and w[order[j]] < value:
                    order[j + 1] = order[j]
                    j -= 1
                order[j + 1] = item
        else:
            block = order[begin:end].copy()
            keys = np.empty(end - begin)
            for i in range(end - begin):
                keys[i] = -w[block[i]]
            ranked = np.argsort(keys, kind="mergesort")
            for i in range(end - begin):
                order[begin + i] = block[ranked[i]]

    @helper()
    def _top_weight_prefix(w, nu, order, buckets, counts, mass, starts):  # pragma: no cover - compiled
        """Put the retained particles first in ``order`` and return their count: the shortest
        prefix of the stable descending weight order whose cumulative mass reaches
        ``nu - 1e-12``, or ``n`` (every particle) when none does."""
        n = w.shape[0]
        cumulative = 0.0
        target = nu - 1e-12
        tied = True
        for i in range(1, n):
            if w[i] != w[0]:
                tied = False
                break
        if tied:  # a belief just resampled: the order is the index order
            for i in range(n):
                order[i] = i
                cumulative += w[i]
                if cumulative >= target:
                    return i + 1
            return n
        last = _bucket_order(w, nu, order, buckets, counts, mass, starts)
        begin = 0
        for b in range(last + 1):
            end = begin + counts[b]
            _sort_bucket(w, order, begin, end)
            for i in range(begin, end):
                cumulative += w[order[i]]
                if cumulative >= target:
                    return i + 1
            begin = end
        return w.shape[0]

    @helper(inline=True)
    def _is_weight(value):  # pragma: no cover - compiled
        """Inside the kernels' domain: a finite, non-negative weight (NaN is not)."""
        return (value >= 0.0) & (value < np.inf)

    @helper(inline=True)
    def _before_stop(weight, i, w_stop, stop):  # pragma: no cover - compiled
        """Whether particle ``i`` (of ``weight``) comes no later than the particle ``stop`` (of
        ``w_stop``) in the stable descending weight order: heavier, or as heavy and not after it."""
        return (weight > w_stop) | ((weight == w_stop) & (i <= stop))

    @helper(inline=True)
    def _two_weight_table(w, values, counts):  # pragma: no cover - compiled
        """:func:`_few_weight_table` of a row of at most two distinct weights (most tap beliefs'),
        counted in one pass without branches; 0 when the row holds more (then the general table
        is taken). The values kept are the same: the row's first weight and the first that differs."""
        if values.shape[0] < 2:
            return 0
        n = w.shape[0]
        first = w[0]
        second = first
        for i in range(n):
            if w[i] != first:
                second = w[i]
                break
        n_first = n_second = 0
        other = False
        for i in range(n):
            is_first = w[i] == first
            is_second = w[i] == second
            n_first += is_first
            n_second += is_second
            other |= not (is_first | is_second)
        if other:
            return 0
        if second == first:
            values[0], counts[0] = first, n
            return 1
        if first > second:
            values[0], counts[0], values[1], counts[1] = first, n_first, second, n_second
        else:
            values[0], counts[0], values[1], counts[1] = second, n_second, first, n_first
        return 2

    @helper()
    def _few_weight_table(w, values, counts):  # pragma: no cover - compiled
        """The distinct weights of a non-empty row in descending order, with how many particles
        carry each, in ``values`` and ``counts``; returns how many there are, or -1 when there
        are more than ``values`` holds.

        A belief's weights take few values (each tap multiplies a weight by one of the reading
        levels' likelihoods; a resampling makes them equal) and come in runs (a parent's copies
        are neighbours), so a run's count goes to its value at once. The stable descending
        order's cumulative sums are those of the sorted distinct values, each repeated: they can
        be taken, with the same bits, without ordering particles.
        """
        n_values = _two_weight_table(w, values, counts)
        if n_values > 0:
            return n_values
        run_value = w[0]
        values[0], counts[0] = run_value, 0
        n_values, slot, run_length = 1, 0, 0
        for i in range(w.shape[0]):
            value = w[i]
            if value != run_value:
                counts[slot] += run_length
                run_value, run_length, slot = value, 0, -1
                for s in range(n_values):
                    if values[s] == value:
                        slot = s
                        break
                if slot < 0:
                    if n_values == values.shape[0]:
                        return -1
                    values[n_values], counts[n_values] = value, 0
                    slot = n_values
                    n_values += 1
            run_length += 1
        counts[slot] += run_length
        for a in range(1, n_values):  # descending by weight (distinct values: no ties to keep)
            value, count = values[a], counts[a]
            b = a - 1
            while b >= 0 and values[b] < value:
                values[b + 1], counts[b + 1] = values[b], counts[b]
                b -= 1
            values[b + 1], counts[b + 1] = value, count
        return n_values

    @helper()
    def _add_repeated(total, value, count, target):  # pragma: no cover - compiled
        """``total += value`` repeated ``count`` times, each sum rounded as IEEE doubles round it,
        stopping after the first sum ``>= target``: ``(sums taken, total)``, the same bits as the loop.

        A running sum of one value is a chain of dependent additions (a cumulative mass over a
        few-weight row adds each weight hundreds of times), but while the sum stays in one binade
        ``[2^E, 2^(E+1))`` of spacing ``u`` each addition adds the same amount: ``value`` rounded
        to a multiple of ``u``, unless it lies exactly halfway between two (then the rounding to
        even depends on the sum: taken one addition at a time, as are sums below ``value`` or
        not normal). So the sums of a binade are taken at once, in integers of ``u``, and the
        first one to reach ``target`` by a few exact comparisons.
        """
        steps = 0
        if value == 0.0 and count > 0:  # one addition (-0.0 becomes 0.0), then the sum never moves
            total += value
            return (1, total) if total >= target else (count, total)
        while steps < count:
            if value > 0.0 and total >= value and total >= 2.2250738585072014e-308 and total < np.inf:
                _, exponent = math.frexp(total)  # 2^(exponent - 1) <= total < 2^exponent
                unit = math.ldexp(1.0, exponent - 53)
                in_units = value / unit  # exact: a power of two apart, and below 2^53
                whole = math.floor(in_units)
                fraction = in_units - whole
                if fraction != 0.5:
                    step_units = int(whole) + (1 if fraction > 0.5 else 0)
                    if step_units == 0:  # the sum never moves again
                        if total >= target:
                            return steps + 1, total
                        return count, total
                    room = (1 << 53) - int(total / unit) - int(whole)
                    if room >= 1:
                        # Sums j = 0..k-1 of this binade have sum + value below 2^exponent.
                        k = min((room - 1) // step_units + 1, count - steps)
                        step = step_units * unit
                        if total + k * step >= target:  # every product and sum here is exact
                            j = max(1, min(k, int(math.ceil((target - total) / step))))
                            while j > 1 and total + (j - 1) * step >= target:
                                j -= 1
                            while total + j * step < target:
                                j += 1
                            return steps + j, total + j * step
                        total = total + k * step
                        steps += k
                        continue
            total += value
            steps += 1
            if total >= target:
                return steps, total
        return steps, total

    @kernel("void(f8[::1], f8[::1], i8[::1], f8[::1], i8[::1], f8[::1])")
    def _add_repeated_rows(totals, values, counts, targets, steps_out, totals_out):  # pragma: no cover - compiled
        """:func:`_add_repeated` of each entry (what its tests compare with the plain loop)."""
        for i in range(totals.shape[0]):
            steps_out[i], totals_out[i] = _add_repeated(totals[i], values[i], counts[i], targets[i])

    @helper(inline=True)
    def _count_and_below(w, value):  # pragma: no cover - compiled
        """How many weights equal ``value``, and the largest weight below it (-inf when none): one pass."""
        n = w.shape[0]
        c0 = c1 = c2 = c3 = 0
        m0 = m1 = m2 = m3 = -np.inf
        i = 0
        stop = n - n % 4
        while i < stop:
            v0, v1, v2, v3 = w[i], w[i + 1], w[i + 2], w[i + 3]
            c0 += v0 == value
            c1 += v1 == value
            c2 += v2 == value
            c3 += v3 == value
            a0, a1 = (v0 if v0 < value else -np.inf), (v1 if v1 < value else -np.inf)
            a2, a3 = (v2 if v2 < value else -np.inf), (v3 if v3 < value else -np.inf)
            m0 = a0 if a0 > m0 else m0
            m1 = a1 if a1 > m1 else m1
            m2 = a2 if a2 > m2 else m2
            m3 = a3 if a3 > m3 else m3
            i += 4
        count = c0 + c1 + c2 + c3
        below = max(max(m0, m1), max(m2, m3))
        while i < n:
            count += w[i] == value
            below = max(below, w[i] if w[i] < value else -np.inf)
            i += 1
        return count, below

    @helper(inline=True)
    def _many_distinct_early(w, values):  # pragma: no cover - compiled
        """Whether the first 64 weights of a row already hold more distinct values than ``values``
        has room for (a continuous belief): the few-weight prefix would not finish, so it is not tried."""
        n_values = 0
        for i in range(min(w.shape[0], 64)):
            value = w[i]
            seen = False
            for s in range(n_values):
                seen |= values[s] == value
            if not seen:
                if n_values == values.shape[0]:
                    return True
                values[n_values] = value
                n_values += 1
        return False

    @helper()
    def _few_weight_prefix(w, nu, values):  # pragma: no cover - compiled
        """:func:`_top_weight_prefix` for a row whose prefix lies among its few heaviest distinct
        weights: the prefix holds every particle heavier than some weight ``t`` and the first ``r``
        particles (in index order) of weight ``t``.

        A belief's weights take few values (each tap multiplies a weight by one of the reading
        levels' likelihoods; a resampling makes them equal), so the stable descending order's
        cumulative sums are those of the distinct values, from the largest down, each repeated as
        many times as particles carry it (:func:`_add_repeated`: the same bits), without ordering
        particles. The distinct values are visited one pass each (count this one, find the next
        below it), and only until the mass is reached: one to three passes for a tap belief.

        Returns:
            ``(m, t, r)``; ``m = n`` and ``t = -inf`` when the mass is never reached; ``m = -1``
            when the row holds more distinct weights than ``values`` has room for before the
            mass is reached (the caller sorts instead).
        """
        n = w.shape[0]
        if n == 0:
            return 0, -np.inf, 0
        if _many_distinct_early(w, values):
            return -1, 0.0, 0
        target = nu - 1e-12
        cumulative = 0.0
        taken = 0
        value = _row_max(w)  # finite, non-negative weights: no NaN, and either zero will do
        for _ in range(values.shape[0]):
            count, below = _count_and_below(w, value)
            added, cumulative = _add_repeated(cumulative, value, count, target)
            if added > 0 and cumulative >= target:
                return taken + added, value, added
            taken += count
            if below == -np.inf:
                return n, -np.inf, 0
            value = below
        return -1, 0.0, 0

    @kernel(
        "Tuple((b1, f8[::1], f8[::1], f8[::1]))(f8[:, ::1], f8[:, ::1], f8[::1], f8)",
        "Tuple((b1, f8[::1], f8[::1], f8[::1]))(f8[:, ::1], f8[:, :], f8[::1], f8)",
    )
    def _coverage_score(weights, z, z_true, width):  # pragma: no cover - compiled
        """The coverage score and the hull ``(min z, max z)`` per row, and whether every input
        was inside the kernel's domain (finite, non-negative weights; finite z and truth)."""
        n_e, n = weights.shape
        out = np.empty(n_e)
        hull_low = np.empty(n_e)
        hull_high = np.empty(n_e)
        order = np.empty(n, dtype=np.int64)
        buckets = np.empty(n, dtype=np.int64)
        counts = np.empty(_N_BUCKETS, dtype=np.int64)
        mass = np.empty(_N_BUCKETS)
        starts = np.empty(_N_BUCKETS, dtype=np.int64)
        few_values = np.empty(_FEW_WEIGHTS)
        few_counts = np.empty(_FEW_WEIGHTS, dtype=np.int64)
        for e in range(n_e):
            truth = z_true[e]
            w = weights[e]
            # The prefix covers the truth once it holds a particle at or left of it and one at or
            # right of it: it ends at the later (in the stable descending order) of the heaviest
            # particle on each side. When few particles come before that one, sort only them.
            # Branch-free (which side a particle lies on is a coin flip): the heaviest on each side
            # is tracked with its weight, which starts below any weight (-1) for "none yet".
            hull_lo, hull_hi = np.inf, -np.inf
            left = right = -1
            left_w = right_w = -1.0
            outside = not np.isfinite(truth)
            for i in range(n):
                value = z[e, i]
                weight = w[i]
                outside |= not (_is_weight(weight) & np.isfinite(value))
                hull_lo = min(hull_lo, value)
                hull_hi = max(hull_hi, value)
                heavier_left = (value <= truth) & (weight > left_w)
                left = i if heavier_left else left
                left_w = weight if heavier_left else left_w
                heavier_right = (value >= truth) & (weight > right_w)
                right = i if heavier_right else right
                right_w = weight if heavier_right else right_w
            if outside:
                return False, out, hull_low, hull_high
            hull_low[e], hull_high[e] = hull_lo, hull_hi
            if not (hull_lo <= truth <= hull_hi):  # escaped: 1 + distance past the hull / D
                out[e] = 1.0 + (max(hull_lo - truth, 0.0) + max(truth - hull_hi, 0.0)) / width
                continue
            stop = right if (w[right] < w[left] or (w[right] == w[left] and right > left)) else left
            w_stop = w[stop]
            count = 0
            for i in range(n):  # counted first, branch-free; only a short prefix is listed in order below
                count += _before_stop(w[i], i, w_stop, stop)
            if count <= _FEW:
                taken = 0
                for i in range(n):
                    if _before_stop(w[i], i, w_stop, stop):
                        order[taken] = i
                        taken += 1
                        if taken == count:
                            break
                _sort_bucket(w, order, 0, count)
                cumulative = 0.0
                for i in range(count):
                    cumulative += w[order[i]]
                out[e] = min(cumulative, 1.0)
                continue
            n_values = _few_weight_table(w, few_values, few_counts)
            if n_values >= 0:  # the prefix's weights: each heavier value in full, then the ties up to the stop
                ties = 0
                for i in range(stop + 1):
                    ties += w[i] == w_stop
                cumulative = 0.0
                for s in range(n_values):
                    value = few_values[s]
                    if value < w_stop:
                        break
                    _, cumulative = _add_repeated(cumulative, value, few_counts[s] if value > w_stop else ties, np.inf)
                out[e] = min(cumulative, 1.0)
                continue
            last = _bucket_order(w, np.inf, order, buckets, counts, mass, starts)
            cumulative = 0.0
            run_lo, run_hi = np.inf, -np.inf
            begin = 0
            found = False
            for b in range(last + 1):  # sort bucket by bucket, only until the prefix covers
                end = begin + counts[b]
                _sort_bucket(w, order, begin, end)
                for i in range(begin, end):
                    cumulative += w[order[i]]
                    run_lo = min(run_lo, z[e, order[i]])
                    run_hi = max(run_hi, z[e, order[i]])
                    if run_lo <= truth <= run_hi:
                        found = True
                        break
                if found:
                    break
                begin = end
            out[e] = min(cumulative, 1.0)
        return True, out, hull_low, hull_high

    @helper(inline=True)
    def _tie_cut(w, threshold, ties):  # pragma: no cover - compiled
        """The index of the ``ties``-th particle of weight ``threshold`` (index order), or -1 for
        none: a few-weight prefix keeps the ties up to it. Counted a block of 64 at a time (the
        count vectorizes), then particle by particle within the block that reaches ``ties``."""
        n = w.shape[0]
        if ties <= 0:
            return -1
        count = 0
        start = 0
        while start < n:
            stop = min(start + 64, n)
            block = 0
            for i in range(start, stop):
                block += w[i] == threshold
            if count + block >= ties:
                for i in range(start, stop):
                    count += w[i] == threshold
                    if count == ties:
                        return i
            count += block
            start = stop
        return -1

    @helper(inline=True)
    def _kept_interval(z, e, keep):  # pragma: no cover - compiled
        """``(min, max)`` of ``z[e]`` over ``keep`` and whether a kept value is NaN, as the scan
        ``low = min(low, z if kept else inf)`` (and ``max``) finds them: in four running extremes
        (one is a chain of dependent comparisons). Only which zero (+0.0 or -0.0) comes first can
        differ between the two orders, so an extreme of zero is taken again by the scan."""
        n = keep.shape[0]
        odd = False
        l0 = l1 = l2 = l3 = np.inf
        h0 = h1 = h2 = h3 = -np.inf
        i = 0
        stop = n - n % 4
        while i < stop:
            v0, v1, v2, v3 = z[e, i], z[e, i + 1], z[e, i + 2], z[e, i + 3]
            k0, k1, k2, k3 = keep[i], keep[i + 1], keep[i + 2], keep[i + 3]
            odd |= (k0 & (v0 != v0)) | (k1 & (v1 != v1)) | (k2 & (v2 != v2)) | (k3 & (v3 != v3))
            a0, a1 = (v0 if k0 else np.inf), (v1 if k1 else np.inf)
            a2, a3 = (v2 if k2 else np.inf), (v3 if k3 else np.inf)
            l0 = a0 if a0 < l0 else l0
            l1 = a1 if a1 < l1 else l1
            l2 = a2 if a2 < l2 else l2
            l3 = a3 if a3 < l3 else l3
            b0, b1 = (v0 if k0 else -np.inf), (v1 if k1 else -np.inf)
            b2, b3 = (v2 if k2 else -np.inf), (v3 if k3 else -np.inf)
            h0 = b0 if b0 > h0 else h0
            h1 = b1 if b1 > h1 else h1
            h2 = b2 if b2 > h2 else h2
            h3 = b3 if b3 > h3 else h3
            i += 4
        low = min(min(l0, l1), min(l2, l3))
        high = max(max(h0, h1), max(h2, h3))
        while i < n:
            value = z[e, i]
            odd |= keep[i] & (value != value)
            low = min(low, value if keep[i] else np.inf)
            high = max(high, value if keep[i] else -np.inf)
            i += 1
        if low == 0.0 or high == 0.0:
            low, high = np.inf, -np.inf
            for i in range(n):
                value = z[e, i]
                low = min(low, value if keep[i] else np.inf)
                high = max(high, value if keep[i] else -np.inf)
        return low, high, odd

    @helper(inline=True)
    def _eight(a, i):  # pragma: no cover - compiled
        """``a[i:i + 8]`` as a tuple (eight registers)."""
        return a[i], a[i + 1], a[i + 2], a[i + 3], a[i + 4], a[i + 5], a[i + 6], a[i + 7]

    @helper(inline=True)
    def _eight_products(v, p, e, i, j):  # pragma: no cover - compiled
        """``v[k] * p[e, i + k, j]`` for the eight ``k``."""
        return (v[0] * p[e, i, j], v[1] * p[e, i + 1, j], v[2] * p[e, i + 2, j], v[3] * p[e, i + 3, j],
                v[4] * p[e, i + 4, j], v[5] * p[e, i + 5, j], v[6] * p[e, i + 6, j], v[7] * p[e, i + 7, j])

    @helper(inline=True)
    def _eight_sums(r, v):  # pragma: no cover - compiled
        """Eight running sums ``r[k] + v[k]``."""
        return r[0] + v[0], r[1] + v[1], r[2] + v[2], r[3] + v[3], r[4] + v[4], r[5] + v[5], r[6] + v[6], r[7] + v[7]

    @helper(inline=True)
    def _eight_total(r):  # pragma: no cover - compiled
        """NumPy's combination of its eight running sums."""
        return ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))

    @helper(inline=True)
    def _block_sums_2d(a, p, e, start, n):  # pragma: no cover - compiled
        """:func:`_block_sum` of ``a`` and :func:`_block_dot` of ``a`` with ``p[e, :, 0]`` and
        ``p[e, :, 1]`` over one leaf of ``n >= 8`` values, in one pass: the same running sums."""
        w = _eight(a, start)
        x, y = _eight_products(w, p, e, start, 0), _eight_products(w, p, e, start, 1)
        i = start + 8
        stop = start + n - n % 8
        while i < stop:
            v = _eight(a, i)
            w = _eight_sums(w, v)
            x = _eight_sums(x, _eight_products(v, p, e, i, 0))
            y = _eight_sums(y, _eight_products(v, p, e, i, 1))
            i += 8
        total_w, total_x, total_y = _eight_total(w), _eight_total(x), _eight_total(y)
        while i < start + n:
            total_w += a[i]
            total_x += a[i] * p[e, i, 0]
            total_y += a[i] * p[e, i, 1]
            i += 1
        return total_w, total_x, total_y

    @kernel(
        "Tuple((b1, b1[:, ::1], f8[::1], f8[::1], f8[:, ::1]))(f8[:, ::1], f8[::1], f8[:, ::1], f8[:, :, ::1])",
        "Tuple((b1, b1[:, ::1], f8[::1], f8[::1], f8[:, ::1]))(f8[:, ::1], f8[::1], f8[:, :], f8[:, :, ::1])",
    )
    def _retained_summary(weights, nu, z, particles):  # pragma: no cover - compiled
        n_e, n = weights.shape
        d = particles.shape[2]
        mask = np.zeros((n_e, n), dtype=np.bool_)
        lo = np.empty(n_e)
        hi = np.empty(n_e)
        reference = np.empty((n_e, d))
        order = np.empty(n, dtype=np.int64)
        buckets = np.empty(n, dtype=np.int64)
        counts = np.empty(_N_BUCKETS, dtype=np.int64)
        mass = np.empty(_N_BUCKETS)
        starts = np.empty(_N_BUCKETS, dtype=np.int64)
        few_values = np.empty(_FEW_WEIGHTS)
        masked_w = np.empty(n)
        product = np.empty(n)
        node_start, node_n, node_open, values = _pairwise_scratch()
        # Two latents over a perfect pairwise tree (N = 1024, say): the mass and both weighted
        # sums of belief_reference from one pass over each leaf.
        blocks_2d = _perfect_blocks(n, values) if d == 2 else 0
        values_x = np.empty(values.shape[0])
        values_y = np.empty(values.shape[0])
        for e in range(n_e):
            w = weights[e]
            outside = False  # negative, NaN or infinite weights: the NumPy path answers
            for i in range(n):
                outside |= not _is_weight(w[i])
            if outside:
                return False, mask, lo, hi, reference
            m, threshold, ties = _few_weight_prefix(w, nu[e], few_values)
            few = m >= 0
            if not few:
                m = _top_weight_prefix(w, nu[e], order, buckets, counts, mass, starts)
                if m == n:
                    mask[e, :] = True
                else:
                    for i in range(m):
                        mask[e, order[i]] = True
            # Without a branch on the mask (retained particles are scattered through the row): the
            # mask of a few-weight row (heavier than the threshold, or a tie up to the ``ties``-th),
            # the masked weights that belief_reference sums, then masked_interval (NaN in a
            # retained z propagates, as np.min / np.max do).
            kept = 0
            if few:
                cut = _tie_cut(w, threshold, ties)
                for i in range(n):
                    keep = (w[i] > threshold) | ((w[i] == threshold) & (i <= cut))
                    mask[e, i] = keep
                    masked_w[i] = w[i] if keep else 0.0
                    kept += keep
            else:
                for i in range(n):
                    keep = mask[e, i]
                    masked_w[i] = w[i] if keep else 0.0
                    kept += keep
            low, high, retained_nan = _kept_interval(z, e, mask[e])
            if retained_nan:
                low = high = np.nan
            lo[e], hi[e] = low, high
            # belief_reference: weighted means over the mask, summed in NumPy's order.
            if blocks_2d:
                for b in range(blocks_2d):
                    values[b], values_x[b], values_y[b] = _block_sums_2d(masked_w, particles, e, 128 * b, 128)
                total = 0.0 + _combine_levels(values, blocks_2d)
                if total > 0:
                    reference[e, 0] = (0.0 + _combine_levels(values_x, blocks_2d)) / total
                    reference[e, 1] = (0.0 + _combine_levels(values_y, blocks_2d)) / total
                    continue
            else:
                total = _row_sum_with(masked_w, node_start, node_n, node_open, values)
            for j in range(d):
                if total > 0:
                    reference[e, j] = _row_dot_with(masked_w, particles, e, j, product, node_start, node_n, node_open,
                                                    values) / total
                else:
                    for i in range(n):
                        product[i] = particles[e, i, j] if mask[e, i] else 0.0
                    reference[e, j] = _row_sum_with(product, node_start, node_n, node_open, values) / max(kept, 1)
        return True, mask, lo, hi, reference


if HAVE_KERNELS:

    @kernel(
        "f8[::1](f8[:, ::1], f8[:, ::1])",
        "f8[::1](f8[:, :], f8[:, ::1])",
    )
    def _weighted_variance(z, weights):  # pragma: no cover - compiled
        n_e, n = weights.shape
        out = np.empty(n_e)
        product = np.empty(n)
        node_start, node_n, node_open, values = _pairwise_scratch()
        for e in range(n_e):
            # NumPy's sum(w * z), then sum(w * (z - mean) ** 2): the same products, summed in its order.
            for i in range(n):
                product[i] = weights[e, i] * z[e, i]
            mean = _row_sum_with(product, node_start, node_n, node_open, values)
            for i in range(n):
                deviation = z[e, i] - mean
                product[i] = weights[e, i] * (deviation * deviation)
            out[e] = _row_sum_with(product, node_start, node_n, node_open, values)
        return out


def weighted_variance_compiled(z: np.ndarray, weights: np.ndarray) -> np.ndarray | None:
    """The compiled posterior variance (see ``core.retained.weighted_variance``), or None without compiled
    kernels and for anything but two float64 ``[E, N]`` arrays with N >= 1. ``z`` may be strided."""
    if not HAVE_KERNELS:
        return None
    z, weights = np.asarray(z), np.asarray(weights)
    if (z.ndim != 2 or z.shape != weights.shape or z.shape[1] == 0
            or z.dtype != np.float64 or weights.dtype != np.float64):
        return None
    return _weighted_variance(z, np.ascontiguousarray(weights))


def retained_summary_compiled(weights: np.ndarray, nu: np.ndarray, z: np.ndarray,
                              particles: np.ndarray) -> tuple[np.ndarray, ...] | None:
    """The compiled retained set (see ``core.retained.retained_summary``), or None.

    None without compiled kernels, and for weights outside the kernel's domain (negative, NaN or
    infinite entries), which the NumPy path handles.
    """
    if not HAVE_KERNELS:
        return None
    # z is often a strided view (one latent of the particles): the kernel reads it in place.
    inside, *summary = _retained_summary(np.ascontiguousarray(weights, dtype=np.float64),
                                         np.ascontiguousarray(nu, dtype=np.float64), np.asarray(z, dtype=np.float64),
                                         np.ascontiguousarray(particles, dtype=np.float64))
    return tuple(summary) if inside else None


def coverage_score_compiled(weights: np.ndarray, z: np.ndarray, z_true: np.ndarray,
                            width: float) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The compiled coverage score with the hull it passes (see ``core.retained.coverage_with_hull``),
    ``(score, min z, max z)`` per row, or None.

    None without compiled kernels and outside the kernel's domain (weights that are negative or not
    finite, a decision coordinate or truth that is not finite), which NumPy handles. ``z`` may
    be a strided view (one latent of the particles): the kernel reads it in place.
    """
    if not HAVE_KERNELS:
        return None
    z = np.asarray(z, dtype=np.float64)
    inside, score, low, high = _coverage_score(np.ascontiguousarray(weights, dtype=np.float64), z,
                                               np.ascontiguousarray(z_true, dtype=np.float64), float(width))
    if not inside:
        return None
    # NumPy's min and max pick between -0.0 and 0.0 by position: rows whose hull ends at a zero take theirs.
    signed = np.flatnonzero((low == 0.0) | (high == 0.0))
    if signed.size:
        rows = np.ascontiguousarray(z[signed])
        low[signed], high[signed] = rows.min(axis=1), rows.max(axis=1)
    return score, low, high


if HAVE_KERNELS:
    _MASK32 = np.uint64(0xFFFFFFFF)
    _SHIFT16 = np.uint64(16)

    @kernel("u4[:, ::1](u8[:, ::1], i8)")
    def _seed_sequence_words(entropy, n_words):  # pragma: no cover - compiled
        """``SeedSequence`` (pool size 4) of each row of assembled entropy words, then
        ``generate_state(n_words, uint32)``: O'Neill's seed_seq hash, in uint64 arithmetic
        masked to 32 bits after every operation."""
        n_keys, n_entropy = entropy.shape
        out = np.empty((n_keys, n_words), dtype=np.uint32)
        mixer = np.empty(4, dtype=np.uint64)
        for key in range(n_keys):
            hash_const = np.uint64(0x43B0D7E5)  # INIT_A
            for i in range(4):
                value = entropy[key, i] if i < n_entropy else np.uint64(0)
                value = (value ^ hash_const) & _MASK32
                hash_const = (hash_const * np.uint64(0x931E8875)) & _MASK32  # MULT_A
                value = (value * hash_const) & _MASK32
                mixer[i] = value ^ (value >> _SHIFT16)
            for i_src in range(n_entropy if n_entropy > 4 else 4):
                for i_dst in range(4):
                    if i_src < 4 and i_src == i_dst:
                        continue
                    value = mixer[i_src] if i_src < 4 else entropy[key, i_src]
                    value = (value ^ hash_const) & _MASK32
                    hash_const = (hash_const * np.uint64(0x931E8875)) & _MASK32
                    value = (value * hash_const) & _MASK32
                    value = value ^ (value >> _SHIFT16)
                    # mix(x, y) = x * MIX_MULT_L - y * MIX_MULT_R, then xor-shift
                    result = ((mixer[i_dst] * np.uint64(0xCA01F9DD)) - (value * np.uint64(0x4973F715))) & _MASK32
                    mixer[i_dst] = result ^ (result >> _SHIFT16)
            hash_const = np.uint64(0x8B51F9DD)  # INIT_B
            for i in range(n_words):
                value = (mixer[i % 4] ^ hash_const) & _MASK32
                hash_const = (hash_const * np.uint64(0x58F38DED)) & _MASK32  # MULT_B
                value = (value * hash_const) & _MASK32
                out[key, i] = np.uint32(value ^ (value >> _SHIFT16))
        return out


def seed_sequence_words_compiled(entropy: np.ndarray, n_words: int) -> np.ndarray | None:
    """The state words ``[K, n_words]`` (uint32) that ``numpy.random.SeedSequence`` (pool
    size 4) generates from each row of assembled entropy words ``[K, L]``, or None without compiled kernels."""
    if not HAVE_KERNELS:
        return None
    return _seed_sequence_words(np.ascontiguousarray(entropy, dtype=np.uint64), int(n_words))


#: Arguments below this go through NumPy's ``exp`` apart: near and past the bottom of the
#: normal range (exp(-708) ~ 3.3e-308) the vectorized ``exp`` takes floating-point assists.
_EXP_FAST_FLOOR = -700.0
#: ``exp`` of anything below this is +0.0 (the smallest subnormal is exp(-744.44)).
_EXP_ZERO_BELOW = -746.0

if HAVE_KERNELS:

    @kernel("void(f8[::1], f8[::1])")
    def _clamp_for_exp(x, out):  # pragma: no cover - compiled
        """``out = x``, raised to ``_EXP_FAST_FLOOR`` where below it (NaN kept); branch-free."""
        for i in range(x.shape[0]):
            value = x[i]
            out[i] = _EXP_FAST_FLOOR if value < _EXP_FAST_FLOOR else value

    @kernel("i8(f8[::1], f8[::1])")
    def _zero_underflows(x, out):  # pragma: no cover - compiled
        """Zero the results whose argument was below ``_EXP_ZERO_BELOW``; count the other clamped ones."""
        n_between = 0
        for i in range(x.shape[0]):
            value = x[i]
            low = value < _EXP_FAST_FLOOR
            out[i] = 0.0 if (low and value < _EXP_ZERO_BELOW) else out[i]
            n_between += low and value >= _EXP_ZERO_BELOW
        return n_between


def _exp_of_between(arguments: np.ndarray, exps: np.ndarray) -> None:
    """``exps`` at the arguments in ``[-746, -700)``: NumPy's ``exp`` of the argument itself (rare)."""
    between = (arguments < _EXP_FAST_FLOOR) & (arguments >= _EXP_ZERO_BELOW)
    exps[between] = np.exp(arguments[between])


def exp_exact(x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``np.exp(x, out=out)``, the same bits, without the cost of arguments whose result underflows.

    Normalized log-weights often hold particles thousands of nats below the best; NumPy's
    vectorized ``exp`` takes floating-point assists on the lanes whose result is subnormal or
    zero (a row with 9 % of them took 5x as long here). A compiled pass raises those arguments to
    -700, NumPy's ``exp`` runs on that, and the raised lanes get their own result: +0.0 below
    -746, NumPy's ``exp`` of the argument itself in between (rare). Lanes are independent, so
    every result equals NumPy's over the whole array (tested bit for bit). Float64 C-contiguous
    arrays only (else plain ``np.exp``); ``out`` may be ``x``.
    """
    if (not HAVE_KERNELS or not isinstance(x, np.ndarray) or x.dtype != np.float64 or not x.flags.c_contiguous
            or (out is not None and (not isinstance(out, np.ndarray) or out.dtype != np.float64
                                     or out.shape != x.shape or not out.flags.c_contiguous))):
        return np.exp(x, out=out)
    if out is x:  # the arguments are needed after exp: keep them
        x = x.copy()
    elif out is None:
        out = np.empty_like(x)
    flat_x, flat_out = x.reshape(-1), out.reshape(-1)
    _clamp_for_exp(flat_x, flat_out)
    np.exp(out, out=out)
    if _zero_underflows(flat_x, flat_out):
        _exp_of_between(flat_x, flat_out)
    return out


# --- Normalizing a batch of log-weights -----------------------------------------------------
#
# ``core.belief`` normalizes log-weights, takes their weights and the ESS in about a dozen
# NumPy passes over the ``[E, N]`` batch (max, shift, exp, sum, log, shift, exp, square, sum
# and the underflow clamps of ``exp_exact``). These kernels fuse the passes around NumPy's own
# ``exp`` and ``log`` (whose bits a compiled ``exp`` does not reproduce), with ``exp_exact``'s
# treatment of the arguments below -700: the same operations on the same values, so the same
# bits (tested against the NumPy path).

if HAVE_KERNELS:

    @helper(inline=True)
    def _row_max(row):  # pragma: no cover - compiled
        """The largest value of a row as a scan keeping the first of equal values finds it (NaN if
        the row holds one), in four running maxima: one would be a chain of dependent comparisons.
        Only a maximum of zero can differ between the two orders (+0.0 and -0.0 are equal), so
        it is then taken again by the scan."""
        n = row.shape[0]
        odd = False
        t0 = t1 = t2 = t3 = -np.inf
        i = 0
        stop = n - n % 4
        while i < stop:
            v0, v1, v2, v3 = row[i], row[i + 1], row[i + 2], row[i + 3]
            odd |= (v0 != v0) | (v1 != v1) | (v2 != v2) | (v3 != v3)
            t0 = v0 if v0 > t0 else t0
            t1 = v1 if v1 > t1 else t1
            t2 = v2 if v2 > t2 else t2
            t3 = v3 if v3 > t3 else t3
            i += 4
        top = t0
        for value in (t1, t2, t3):
            top = value if value > top else top
        while i < n:
            value = row[i]
            odd |= value != value
            top = value if value > top else top
            i += 1
        if odd:
            return np.nan
        if top == 0.0:
            top = -np.inf
            for i in range(n):
                top = row[i] if row[i] > top else top
        return top

    @kernel("i8(f8[:, ::1], f8[::1], f8[:, ::1], b1[::1])")
    def _shift_and_clamp(log_weights, row_max, out, zero_rows):  # pragma: no cover - compiled
        """``row_max = max(log_weights, axis=1)``; ``out = log_weights - row_max`` raised to
        ``_EXP_FAST_FLOOR``; ``zero_rows[e]``: whether row ``e`` has a shifted value below -746
        (an ``exp`` of zero). Returns how many shifted values lie in ``[-746, -700)`` (their
        ``exp`` is NumPy's of the value itself), or -1 if a row holds NaN or has no finite
        maximum (nothing promised then)."""
        n_e, n = log_weights.shape
        between = 0
        for e in range(n_e):
            top = _row_max(log_weights[e])
            if top != top or not np.isfinite(top):
                return -1
            row_max[e] = top
            zero = False
            for i in range(n):
                value = log_weights[e, i] - top
                low = value < _EXP_FAST_FLOOR
                between += low & (value >= _EXP_ZERO_BELOW)
                zero |= value < _EXP_ZERO_BELOW
                out[e, i] = _EXP_FAST_FLOOR if low else value
            zero_rows[e] = zero
        return between

    @kernel("void(f8[:, ::1], f8[::1], f8[:, ::1], f8[::1], b1[::1])")
    def _zeroed_row_sums(log_weights, row_max, exps, sums, zero_rows):  # pragma: no cover - compiled
        """Zero the ``exp`` lanes whose shifted argument is below -746 (in the ``zero_rows`` only),
        then ``sums = np.sum(exps, axis=1)``."""
        n_e, n = log_weights.shape
        node_start, node_n, node_open, values = _pairwise_scratch()
        for e in range(n_e):
            top = row_max[e]
            if zero_rows[e]:
                for i in range(n):
                    exps[e, i] = 0.0 if log_weights[e, i] - top < _EXP_ZERO_BELOW else exps[e, i]
            sums[e] = _row_sum_with(exps[e], node_start, node_n, node_open, values)

    @kernel("i8(f8[:, ::1], f8[::1], f8[:, ::1], f8[:, ::1], b1[::1])")
    def _subtract_and_clamp(log_weights, log_norm, normalized, clamped, zero_rows):  # pragma: no cover - compiled
        """``normalized = log_weights - log_norm[:, None]`` and its copy raised to ``_EXP_FAST_FLOOR``
        in ``clamped``; ``zero_rows`` as :func:`_shift_and_clamp` sets it. Returns how many values
        lie in ``[-746, -700)``."""
        n_e, n = log_weights.shape
        between = 0
        for e in range(n_e):
            shift = log_norm[e]
            zero = False
            for i in range(n):
                value = log_weights[e, i] - shift
                normalized[e, i] = value
                low = value < _EXP_FAST_FLOOR
                between += low and value >= _EXP_ZERO_BELOW
                zero |= value < _EXP_ZERO_BELOW
                clamped[e, i] = _EXP_FAST_FLOOR if low else value
            zero_rows[e] = zero
        return between

    @kernel("void(f8[:, ::1], f8[:, ::1], f8[::1], b1[::1])")
    def _zeroed_sums_of_squares(normalized, weights, squares, zero_rows):  # pragma: no cover - compiled
        """Zero the weights whose argument is below -746 (in the ``zero_rows`` only);
        ``squares = np.sum(np.square(weights), axis=1)``."""
        n_e, n = normalized.shape
        node_start, node_n, node_open, values = _pairwise_scratch()
        square = np.empty(n)
        for e in range(n_e):
            if zero_rows[e]:
                for i in range(n):
                    value = 0.0 if normalized[e, i] < _EXP_ZERO_BELOW else weights[e, i]
                    weights[e, i] = value
                    square[i] = value * value
            else:
                for i in range(n):
                    square[i] = weights[e, i] * weights[e, i]
            squares[e] = _row_sum_with(square, node_start, node_n, node_open, values)


def normalized_weights_compiled(log_weights: np.ndarray) -> tuple[np.ndarray, ...] | None:
    """Normalize log-weights ``[E, N]`` in fused passes (see ``core.belief.normalized_weights``).

    Returns:
        ``(normalized log-weights, log normalizer [E], weights, sum of squared weights [E])``, the
        same bits as the NumPy path; None without compiled kernels, for an array that is not float64
        ``[E, N]`` with N >= 1, and for a row with NaN or no finite maximum (a lost belief),
        which the NumPy path handles.
    """
    if (not HAVE_KERNELS or not isinstance(log_weights, np.ndarray) or log_weights.dtype != np.float64
            or log_weights.ndim != 2 or log_weights.shape[1] == 0):
        return None
    log_weights = np.ascontiguousarray(log_weights)
    n_e = log_weights.shape[0]
    row_max = np.empty(n_e)
    exps = np.empty_like(log_weights)
    zero_rows = np.empty(n_e, dtype=np.bool_)  # rows with a weight of exactly zero (many have none)
    between = _shift_and_clamp(log_weights, row_max, exps, zero_rows)
    if between < 0:
        return None
    np.exp(exps, out=exps)
    if between:
        _exp_of_between(log_weights - row_max[:, None], exps)
    sums = np.empty(n_e)
    _zeroed_row_sums(log_weights, row_max, exps, sums, zero_rows)
    log_norm = row_max + np.log(sums)
    normalized = np.empty_like(log_weights)
    between = _subtract_and_clamp(log_weights, log_norm, normalized, exps, zero_rows)  # exps is spent: the weights
    np.exp(exps, out=exps)
    if between:
        _exp_of_between(normalized, exps)
    squares = np.empty(n_e)
    _zeroed_sums_of_squares(normalized, exps, squares, zero_rows)
    return normalized, log_norm, exps, squares
