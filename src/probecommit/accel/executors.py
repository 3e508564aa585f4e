"""Compiled scenario counts for the set executors (``core.executors``'s interval fast path).

For a binary loss whose success set is an open interval of a sorted 1-D action grid, the
executor needs, per episode and action, how many retained scenarios succeed: each action
inside the retained intervals' span is compared with every retained interval. The counts are
integers, so they equal the NumPy reference (a difference array) exactly.
"""

from __future__ import annotations

import numpy as np

from probecommit.accel.compiled import helper, kernel
from probecommit.accel.retained import retained_summary
from probecommit.core.executors import SCORE_TIE_TOLERANCE, SetKernels, margin_success_counts


@helper(inline=True)
def _keep(lo_kept, hi_kept, k, lo, hi, keep):  # pragma: no cover - compiled
    """Write a scenario's open interval at slot ``k``; the next slot (``k + 1`` if it is retained).
    Every scenario is written and only a retained one kept: no branch on the mask. A NaN end
    holds nothing at the low side and bounds nothing at the high side (NumPy's order: NaN last)."""
    lo_kept[k] = np.inf if lo != lo else lo
    hi_kept[k] = np.inf if hi != hi else hi
    return k + keep


@helper(inline=True)
def _count_row(lo_kept, hi_kept, k, actions, out_row):  # pragma: no cover - compiled
    """``out_row[a]`` = how many of the first ``k`` intervals hold ``lo < actions[a] < hi``: every action
    inside the intervals' span compared with every interval (a loop the compiler vectorizes)."""
    if k == 0:
        return
    first = np.searchsorted(actions, np.min(lo_kept[:k]), side="right")
    last = np.searchsorted(actions, np.max(hi_kept[:k]), side="left")
    for a in range(first, last):
        value = actions[a]
        count = 0
        for s in range(k):
            count += (lo_kept[s] < value) & (value < hi_kept[s])
        out_row[a] = count


@kernel("i8[:, ::1](f8[:, ::1], f8[:, ::1], b1[:, ::1], f8[::1])")
def _interval_counts(lo, hi, mask, actions):  # pragma: no cover - compiled
    n_e, n_s = mask.shape
    out = np.zeros((n_e, actions.shape[0]), dtype=np.int64)
    lo_kept, hi_kept = np.empty(n_s), np.empty(n_s)
    for e in range(n_e):
        k = 0
        for s in range(n_s):
            k = _keep(lo_kept, hi_kept, k, lo[e, s], hi[e, s], mask[e, s])
        _count_row(lo_kept, hi_kept, k, actions, out[e])
    return out


@kernel("i8[:, ::1](f8[:, ::1], f8[:, ::1], f8, b1[:, ::1], f8[::1])")
def _scaled_counts(centre, half, margin, mask, actions):  # pragma: no cover - compiled
    n_e, n_s = mask.shape
    out = np.zeros((n_e, actions.shape[0]), dtype=np.int64)
    lo_kept, hi_kept = np.empty(n_s), np.empty(n_s)
    for e in range(n_e):
        k = 0
        for s in range(n_s):
            width = half[e, s] * margin
            k = _keep(lo_kept, hi_kept, k, centre[e, s] - width, centre[e, s] + width, mask[e, s])
        _count_row(lo_kept, hi_kept, k, actions, out[e])
    return out


@kernel("i8[:, ::1](f8[:, :, ::1], i8, i8, f8, f8, f8, b1[:, ::1], f8[::1], i8[::1])")
def _affine_counts(scenarios, centre_at, width_at, slope, intercept, margin, mask, actions, kept):  # pragma: no cover
    n_e, n_s = mask.shape
    out = np.zeros((n_e, actions.shape[0]), dtype=np.int64)
    lo_kept, hi_kept = np.empty(n_s), np.empty(n_s)
    for e in range(n_e):
        k = 0
        for s in range(n_s):
            width = (scenarios[e, s, width_at] * slope + intercept) * margin
            centre = scenarios[e, s, centre_at]
            k = _keep(lo_kept, hi_kept, k, centre - width, centre + width, mask[e, s])
        _count_row(lo_kept, hi_kept, k, actions, out[e])
        kept[e] = k
    return out


@helper(inline=True)
def _succeeds(centre, half, margin, value):  # pragma: no cover - compiled
    """``lo < value < hi`` of the interval ``centre -+ half * margin``, its ends made as
    :func:`_scaled_counts` makes and :func:`_keep` keeps them (the same IEEE operations)."""
    width = half * margin
    low, high = centre - width, centre + width
    low = np.inf if low != low else low
    high = np.inf if high != high else high
    return (low < value) & (value < high)


@helper(inline=True)
def _holds(centre, half, margin, value, side):  # pragma: no cover - compiled
    """:func:`_succeeds` for an action on ``side`` of the centre (``+1`` right, ``-1`` left, ``0`` on it),
    inside the interval at some margin (so ``half > 0`` and the centre finite): right of the centre
    ``low <= centre < value`` at every margin (``centre - width`` rounds to at most ``centre`` for
    ``width >= 0``), so only ``value < high`` is checked; left of it only ``low < value``."""
    if side == 0:
        return _succeeds(centre, half, margin, value)
    width = half * margin
    if side > 0:
        high = centre + width
        return value < (np.inf if high != high else high)
    low = centre - width
    return (np.inf if low != low else low) < value


@helper(inline=True)
def _grid_guess(value, origin, per_step, n):  # pragma: no cover - compiled
    """Where ``value`` falls on a grid of ``n`` actions if it were evenly spaced (clamped to ``[0, n]``):
    a first guess that :func:`_first_above` and :func:`_first_from` walk to the exact index."""
    x = (value - origin) * per_step
    if not x > 0.0:
        return 0
    if not x < n:
        return n
    return int(x)


@helper(inline=True)
def _first_above(actions, value, origin, per_step):  # pragma: no cover - compiled
    """``np.searchsorted(actions, value, side="right")`` (sorted actions, no NaN): from a guess, walked to
    the index ``i`` with ``actions[i - 1] <= value < actions[i]``, which is unique, so exact for any
    sorted grid; on an evenly spaced grid the guess is right and no binary search's branches are taken."""
    n = actions.shape[0]
    i = _grid_guess(value, origin, per_step, n)
    while i < n and actions[i] <= value:
        i += 1
    while i > 0 and actions[i - 1] > value:
        i -= 1
    return i


@helper(inline=True)
def _first_from(actions, value, origin, per_step):  # pragma: no cover - compiled
    """``np.searchsorted(actions, value, side="left")``, as :func:`_first_above`:
    ``actions[i - 1] < value <= actions[i]``."""
    n = actions.shape[0]
    i = _grid_guess(value, origin, per_step, n)
    while i < n and actions[i] < value:
        i += 1
    while i > 0 and actions[i - 1] >= value:
        i -= 1
    return i


@kernel("i8[:, :, ::1](f8[:, ::1], f8[:, ::1], f8[::1], b1[:, ::1], f8[::1])")
def _margin_counts(centre, half, margins, mask, actions):  # pragma: no cover - compiled
    """``out[m, e, a]``: the retained scenarios of row ``e`` under which action ``a`` succeeds at
    ``margins[m]`` (positive, finite, sorted from the largest down).

    Whether an action succeeds is monotone in the margin: ``half * gamma`` is rounded monotonically,
    so the interval shrinks as ``gamma`` does, and a scenario whose interval is empty or NaN at the
    largest margin holds nothing at any. So the margins under which an action succeeds are the
    first ``j`` of the list: each retained scenario visits only the actions inside its widest
    interval (found from the grid's spacing and walked exact: no binary search), finds ``j``
    (guessed from the margins' spacing, then walked to the exact ``j`` with the predicate itself, one
    side of it for an action off the centre: :func:`_holds`) and
    adds one to ``hist[a, j]``; a row's counts are those histograms summed from the right. The same
    integers as counting each margin (``_scaled_counts``), for every margin."""
    n_e, n_s = mask.shape
    n_m, n_a = margins.shape[0], actions.shape[0]
    out = np.zeros((n_m, n_e, n_a), dtype=np.int64)
    hist = np.zeros((n_a, n_m + 1), dtype=np.int64)
    widest = margins[0]
    # 1 / the margins' mean spacing: where the width reaches an action, a first guess of j
    per_spacing = (n_m - 1) / (widest - margins[n_m - 1]) if n_m > 1 else 0.0
    # 1 / the actions' mean spacing: a guess of each scenario's first and last action, walked exact
    origin = actions[0] if n_a else 0.0
    per_step = (n_a - 1) / (actions[n_a - 1] - origin) if n_a > 1 and actions[n_a - 1] > origin else 0.0
    for e in range(n_e):
        for s in range(n_s):
            if not mask[e, s]:
                continue
            c, h = centre[e, s], half[e, s]
            width = h * widest
            low, high = c - width, c + width
            low = np.inf if low != low else low
            high = np.inf if high != high else high
            first = _first_above(actions, low, origin, per_step)
            last = _first_from(actions, high, origin, per_step)
            scale = 1.0 / h if 0.0 < h < np.inf else 0.0
            for a in range(first, last):
                value = actions[a]
                side = 1 if value > c else -1 if value < c else 0
                # j: the margins at which the action succeeds are margins[:j] (j >= 1: it does at the
                # widest). A guess from the spacing, then walked to the exact j with the predicate itself.
                j = n_m
                if scale > 0.0 and per_spacing > 0.0:
                    guess = (widest - abs(value - c) * scale) * per_spacing + 1.0
                    j = 1 if not guess >= 1.0 else n_m if guess > n_m else int(guess)
                while j < n_m and _holds(c, h, margins[j], value, side):
                    j += 1
                while j > 1 and not _holds(c, h, margins[j - 1], value, side):
                    j -= 1
                hist[a, j] += 1
        for a in range(n_a):
            run = 0
            for m in range(n_m - 1, -1, -1):
                run += hist[a, m + 1]
                out[m, e, a] = run
                hist[a, m + 1] = 0
    return out


@kernel("Tuple((i8[:, ::1], f8[:, ::1]))(i8[:, :, ::1], i8[::1], f8[:, :, ::1], f8)")
def _margin_choices(successes, kept, ties, tolerance):  # pragma: no cover - compiled
    """``core.executors.margin_choices`` row by row: the failure fraction of each action, then
    ``select_action``'s steps (the row's minimum, NaN if any; the actions within ``tolerance`` of it;
    the first least tie cost among them, the others at infinity, the first NaN if any). ``ties`` is
    ``[M, E, A]``, or ``[1, E, A]`` for every margin."""
    n_m, n_e, n_a = successes.shape
    per_margin = ties.shape[0] > 1
    index = np.zeros((n_m, n_e), dtype=np.int64)
    score = np.empty((n_m, n_e))
    row = np.empty(n_a)
    for m in range(n_m):
        for e in range(n_e):
            total = kept[e]
            count = np.float64(total if total > 1 else 1)
            best = np.inf
            for a in range(n_a):
                row[a] = np.float64(total - successes[m, e, a]) / count
                if best == best and (row[a] < best or row[a] != row[a]):
                    best = row[a]
            limit = best + tolerance
            chosen = 0
            tie = ties[m if per_margin else 0, e]
            least = tie[0] if row[0] <= limit else np.inf
            if least == least:
                for a in range(1, n_a):
                    cost = tie[a] if row[a] <= limit else np.inf
                    if cost != cost:
                        chosen = a
                        break
                    if cost < least:
                        least, chosen = cost, a
            index[m, e] = chosen
            score[m, e] = row[chosen]
    return index, score


def margin_choices(successes: np.ndarray, kept: np.ndarray, ties: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``core.executors.margin_choices``, compiled: no ``[M, E, A]`` scores, masks or costs formed
    (``ties`` ``[M, E, A]`` or ``[1, E, A]``)."""
    return _margin_choices(np.ascontiguousarray(successes, dtype=np.int64), np.ascontiguousarray(kept, dtype=np.int64),
                           np.ascontiguousarray(ties, dtype=np.float64), SCORE_TIE_TOLERANCE)


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


def margin_counts(centre: np.ndarray, half: np.ndarray, margins: np.ndarray, mask: np.ndarray,
                  actions: np.ndarray) -> np.ndarray:
    """``core.executors.margin_success_counts``, compiled: every margin counted in one visit of the
    scenarios. Margins that are not positive, finite and strictly decreasing are counted by the
    reference (the monotone shortcut needs them so)."""
    margins = np.ascontiguousarray(margins, dtype=np.float64).reshape(-1)
    if not (margins.size and np.all(np.isfinite(margins)) and np.all(margins > 0) and np.all(np.diff(margins) < 0)):
        return margin_success_counts(centre, half, margins, mask, actions)
    f64 = np.float64
    return _margin_counts(np.ascontiguousarray(centre, dtype=f64), np.ascontiguousarray(half, dtype=f64), margins,
                          np.ascontiguousarray(mask, dtype=np.bool_), _grid(actions))


#: The set executors' compiled kernels (``ProbeRobust(kernels=KERNELS)``).
KERNELS = SetKernels(retained_summary=retained_summary, interval_success_counts=interval_counts,
                     scaled_interval_success_counts=scaled_counts, affine_interval_success_counts=affine_counts,
                     margin_success_counts=margin_counts, margin_choices=margin_choices)
