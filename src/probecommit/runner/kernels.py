"""Compiled kernel of the margin search: every margin's success counts in one visit of a retained set.

A margin search scores the same retained scenarios under dozens of margins ``gamma``; a
scenario's success interval under ``gamma`` is ``centre -+ half * gamma`` (the model's
``success_interval_parts``). Counting each margin on its own reads every scenario once per
margin. The predicate ``lo < a < hi`` is monotone in ``gamma`` for every scenario and
action (the width ``half * gamma`` grows with ``gamma``; a NaN end behaves as the counting
kernels treat it, see below), so the margins under which an action succeeds are a prefix of
the margins sorted from the largest down. This kernel finds that prefix's length for each
retained scenario and each action inside its widest interval (a binary search over the
margins, each test the same IEEE operations as the per-margin count) and turns the lengths
into counts with a histogram: the same integers as the per-margin count, for every margin
(tested against ``core.executors``' count, margin by margin).
"""

from __future__ import annotations

import numpy as np

from probecommit.core.compiled import AVAILABLE as HAVE_KERNELS
from probecommit.core.compiled import helper, kernel

if HAVE_KERNELS:

    @helper(inline=True)
    def _ends(centre, half, margin):  # pragma: no cover - compiled
        """The interval ``centre -+ half * margin`` with a NaN end read as +inf (as the counting
        kernels of ``core.kernels`` keep their intervals): the same IEEE operations."""
        width = half * margin
        low = centre - width
        high = centre + width
        if low != low:
            low = np.inf
        if high != high:
            high = np.inf
        return low, high

    @helper(inline=True)
    def _succeeds(centre, half, margin, value):  # pragma: no cover - compiled
        """``lo < value < hi`` of :func:`_ends`."""
        low, high = _ends(centre, half, margin)
        return (low < value) and (value < high)

    @helper(inline=True)
    def _first_above(actions, value, strict, inv_step):  # pragma: no cover - compiled
        """The first index whose action is ``> value`` (``strict``) or ``>= value`` (``searchsorted``
        right or left; NaN sorts last): a first guess from the grid's mean spacing (``inv_step``,
        1 / spacing, or 0), walked to the exact answer with the grid's own comparisons."""
        n = actions.shape[0]
        if value != value:
            return n
        i = n // 2
        if inv_step > 0.0:
            guess = (value - actions[0]) * inv_step
            i = 0 if guess < 0.0 else n if guess > n else int(guess)
        if strict:
            while i < n and actions[i] <= value:
                i += 1
            while i > 0 and actions[i - 1] > value:
                i -= 1
        else:
            while i < n and actions[i] < value:
                i += 1
            while i > 0 and actions[i - 1] >= value:
                i -= 1
        return i

    @kernel("i8[::1](f8[:, ::1], f8[:, ::1], b1[:, ::1], f8[::1], f8[::1], i8[:, :, ::1], i8[::1])")
    def _margin_success_counts(centre, half, mask, margins, actions, out, kept):  # pragma: no cover - compiled
        """Add to ``out[m, e, a]`` the retained scenarios of row ``e`` under which action ``a`` succeeds
        at ``margins[m]`` (sorted from the largest down), and to ``kept[e]`` each row's retained count."""
        n_e, n_s = mask.shape
        n_m, n_a = margins.shape[0], actions.shape[0]
        hist = np.zeros((n_a, n_m + 1), dtype=np.int64)  # hist[a, j]: scenarios succeeding at the first j margins
        spread = margins[0] - margins[n_m - 1]
        inv_step = (n_a - 1) / (actions[n_a - 1] - actions[0]) if n_a > 1 and actions[n_a - 1] > actions[0] else 0.0
        per_spacing = (n_m - 1) / spread if n_m > 1 and spread > 0.0 else 0.0  # 1 / the mean spacing
        for e in range(n_e):
            count = 0
            for s in range(n_s):
                if not mask[e, s]:
                    continue
                count += 1
                c, h = centre[e, s], half[e, s]
                # The actions that succeed at the widest margin (an interval of the sorted grid):
                # only they can succeed at any.
                low, high = _ends(c, h, margins[0])
                stop = _first_above(actions, high, False, inv_step)
                scale = 1.0 / h if 0.0 < h < np.inf and c == c and abs(c) < np.inf else 0.0
                for a in range(_first_above(actions, low, True, inv_step), stop):
                    value = actions[a]
                    # succeeds at the first j margins: a guess from the margins' mean spacing (the
                    # margin at which the width reaches the action), then walked to the exact j
                    # with the predicate itself (it holds at margins[0], so j >= 1)
                    j = n_m
                    if scale > 0.0 and per_spacing > 0.0:
                        guess = (margins[0] - abs(value - c) * scale) * per_spacing + 1.0
                        j = 1 if guess < 1.0 else n_m if guess > n_m else int(guess)
                    while j < n_m and _succeeds(c, h, margins[j], value):
                        j += 1
                    while j > 1 and not _succeeds(c, h, margins[j - 1], value):
                        j -= 1
                    hist[a, j] += 1
            kept[e] += count
            for a in range(n_a):
                run = 0
                for m in range(n_m - 1, -1, -1):
                    run += hist[a, m + 1]
                    out[m, e, a] += run
                hist[a, :] = 0
        return kept

    @kernel("i8[:, ::1](i8[:, :, ::1], i8[::1], f8[:, ::1], f8, f8[:, ::1])")
    def _choose_by_counts(successes, kept, tie_cost, tolerance, score):  # pragma: no cover - compiled
        """Per margin and row, ``core.executors.select_action`` of the failure fractions
        ``(kept - successes) / max(kept, 1)`` (NumPy's int-to-float division), writing the chosen
        action's fraction into ``score[m, e]``: the lowest fraction, ties within ``tolerance``
        broken by the lowest ``tie_cost``, then the lowest index (``np.argmin``, a NaN cost first)."""
        n_m, n_e, n_a = successes.shape
        index = np.empty((n_m, n_e), dtype=np.int64)
        fractions = np.empty(n_a)
        for m in range(n_m):
            for e in range(n_e):
                denominator = max(kept[e], 1)
                best = np.inf
                for a in range(n_a):
                    fractions[a] = (kept[e] - successes[m, e, a]) / denominator
                    best = min(best, fractions[a])
                bound = best + tolerance
                chosen, lowest = -1, np.inf
                for a in range(n_a):
                    if fractions[a] <= bound:
                        cost = tie_cost[e, a]
                        if cost != cost:
                            chosen = a
                            break
                        if chosen < 0 or cost < lowest:
                            chosen, lowest = a, cost
                if lowest == np.inf and tie_cost[e, chosen] == tie_cost[e, chosen]:
                    chosen = 0  # every cost of the row is +inf where it counts: argmin takes the first
                index[m, e] = chosen
                score[m, e] = fractions[chosen]
        return index


def margin_choices(blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]], margins: np.ndarray, actions: np.ndarray,
                   tie_cost: np.ndarray, tolerance: float) -> tuple[np.ndarray, np.ndarray] | None:
    """Per margin, the action each row's executor chooses ``[M, E]`` and its failure fraction ``[M, E]``,
    or None without compiled kernels (the caller chooses margin by margin then).

    The same as ``core.executors.retained_scores`` of the margin's model followed by
    ``select_action`` (a grown set's blocks counted together, as there).

    Args:
        blocks: ``(centre, half, mask)`` of each block of the retained set: its scenarios'
            success-interval parts (margin one) and which are retained, each ``[E, S]``.
        margins: ``[M]`` margins, each > 0, sorted from the largest down.
        actions: ``[A]`` the sorted action grid.
        tie_cost: ``[E, A]`` the tie-break cost (``model.tie_break_cost``).
        tolerance: ``core.executors.SCORE_TIE_TOLERANCE``.
    """
    if not HAVE_KERNELS:
        return None
    margins = np.ascontiguousarray(margins, dtype=np.float64)
    if margins.size == 0 or np.any(margins <= 0) or np.any(np.diff(margins) >= 0):
        raise ValueError("margins must be positive and strictly decreasing")
    actions = np.ascontiguousarray(actions, dtype=np.float64)
    n_e = blocks[0][2].shape[0]
    successes = np.zeros((margins.size, n_e, actions.size), dtype=np.int64)
    kept = np.zeros(n_e, dtype=np.int64)
    for centre, half, mask in blocks:
        _margin_success_counts(np.ascontiguousarray(centre, dtype=np.float64), np.ascontiguousarray(half, dtype=np.float64),
                               np.ascontiguousarray(mask, dtype=np.bool_), margins, actions, successes, kept)
    score = np.empty((margins.size, n_e))
    index = _choose_by_counts(successes, kept, np.ascontiguousarray(tie_cost, dtype=np.float64), float(tolerance), score)
    return index, score


def margin_success_counts(centre: np.ndarray, half: np.ndarray, mask: np.ndarray, margins: np.ndarray,
                          actions: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Success counts ``[M, E, A]`` of every margin over one block and the retained counts ``[E]``
    (what :func:`margin_choices` chooses from), or None without compiled kernels."""
    if not HAVE_KERNELS:
        return None
    margins = np.ascontiguousarray(margins, dtype=np.float64)
    if margins.size == 0 or np.any(margins <= 0) or np.any(np.diff(margins) >= 0):
        raise ValueError("margins must be positive and strictly decreasing")
    actions = np.ascontiguousarray(actions, dtype=np.float64)
    successes = np.zeros((margins.size, mask.shape[0], actions.size), dtype=np.int64)
    kept = np.zeros(mask.shape[0], dtype=np.int64)
    _margin_success_counts(np.ascontiguousarray(centre, dtype=np.float64), np.ascontiguousarray(half, dtype=np.float64),
                           np.ascontiguousarray(mask, dtype=np.bool_), margins, actions, successes, kept)
    return successes, kept
