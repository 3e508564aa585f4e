"""Executors: Blind-Bayes, Blind-Robust and Probe-Robust(k).

Tie-break rule (every executor, documented in docs/decisions.md): among actions
whose score equals the minimum (within ``SCORE_TIE_TOLERANCE``), choose the one
closest to a *reference* point computed from the belief alone (the weighted mean of
the decision coordinate over the scenarios scored); if still tied, the lowest
action index. The truth is never used.
"""

from __future__ import annotations

import numpy as np

SCORE_TIE_TOLERANCE = 1e-12


def select_action(scores: np.ndarray, actions: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Index of the best action per episode under the documented tie-break.

    Args:
        scores: ``[E, A]`` lower is better.
        actions: ``[A]`` the action grid (scalar actions in the decision coordinate).
        reference: ``[E]`` tie-break reference point from the belief.

    Returns:
        ``[E]`` integer indices into ``actions``.
    """
    scores = np.asarray(scores, dtype=float)
    best = np.min(scores, axis=1, keepdims=True)
    tied = scores <= best + SCORE_TIE_TOLERANCE
    distance = np.abs(np.asarray(actions, dtype=float)[None, :] - np.asarray(reference, dtype=float)[:, None])
    distance = np.where(tied, distance, np.inf)
    # argmin returns the first (lowest-index) minimum, which is the final tie-break.
    return np.argmin(distance, axis=1)


def scenario_failure_fraction(failures: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Unweighted fraction of retained scenarios that fail, per action.

    Args:
        failures: ``[E, A, N]`` boolean failure of action ``a`` under particle ``n``.
        mask: ``[E, N]`` retained scenarios.

    Returns:
        ``[E, A]`` failure fraction.
    """
    kept = np.maximum(np.sum(mask, axis=-1), 1)
    return np.einsum("ean,en->ea", failures.astype(np.float64), mask.astype(np.float64)) / kept[:, None]


def interval_success_counts(lo: np.ndarray, hi: np.ndarray, mask: np.ndarray, actions: np.ndarray) -> np.ndarray:
    """Retained scenarios whose open success interval ``(lo, hi)`` contains each action.

    An ``O(E (N + A))`` alternative to materializing ``[E, A, N]`` failures, for
    tasks whose success set is an interval of a sorted 1-D action grid: each
    scenario adds one to a contiguous run of actions (a difference array).

    Args:
        lo, hi: ``[E, N]`` open interval ends per scenario.
        mask: ``[E, N]`` retained scenarios.
        actions: ``[A]`` strictly increasing action grid.

    Returns:
        ``[E, A]`` integer counts, identical to counting ``lo < a < hi`` directly.
    """
    actions = np.asarray(actions, dtype=float)
    n_e, n_a = mask.shape[0], actions.shape[0]
    first = np.searchsorted(actions, lo, side="right")  # first a > lo
    last = np.searchsorted(actions, hi, side="left")  # one past the last a < hi
    live = mask & (first < last)
    rows = np.broadcast_to(np.arange(n_e)[:, None] * (n_a + 1), mask.shape)
    flat = np.concatenate([(rows + first)[live], (rows + last)[live]])
    step = np.concatenate([np.ones(int(live.sum()), np.int64), -np.ones(int(live.sum()), np.int64)])
    diff = np.bincount(flat, weights=step, minlength=n_e * (n_a + 1)).reshape(n_e, n_a + 1)
    return np.cumsum(diff, axis=1)[:, :n_a].astype(np.int64)


def scenario_max_loss(losses: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Scenario minimax score: the maximum loss over retained scenarios ``[E, A]``."""
    return np.max(np.where(mask[:, None, :], losses, -np.inf), axis=-1)


def prior_expected_loss(losses: np.ndarray) -> np.ndarray:
    """Mean loss over a prior sample: ``losses[A, S] -> [A]`` (Blind-Bayes objective)."""
    return np.mean(np.asarray(losses, dtype=float), axis=-1)
