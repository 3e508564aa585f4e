"""How stable a choice made on development instances is (pure NumPy; hand-checked in the tests).

Why: the paper's cover schedule and its robust-filter settings are each the winner of a
search on 24 development instances; ours differ. Whether that difference is a finding or a
draw is a question about the search itself: resample the development instances (whole
clusters, the project's bootstrap) and ask how often the paper's candidate wins and how far
it trails the winner, paired on the same resample.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from probecommit.audit.stats import percentile_interval, resample_counts

#: Two mean values closer than this are a tie (means of 0/1 outcomes over whole clusters).
TIE = 1e-12


def winners(primary: np.ndarray, secondary: np.ndarray | None = None) -> np.ndarray:
    """Row-wise winner index: lowest ``primary``; ties to the lowest ``secondary``, then the first column.

    ``primary`` and ``secondary`` are ``[B, C]`` (resamples x candidates).
    """
    primary = np.atleast_2d(np.asarray(primary, dtype=float))
    best = primary <= primary.min(axis=1, keepdims=True) + TIE
    if secondary is not None:
        sec = np.where(best, np.atleast_2d(np.asarray(secondary, dtype=float)), np.inf)
        best &= sec <= sec.min(axis=1, keepdims=True) + TIE
    return best.argmax(axis=1)


def choice_stability(values: np.ndarray, clusters: Sequence, target: int, *, secondary: np.ndarray | None = None,
                     resamples: int = 2000, seed: int = 0) -> dict[str, float | list[float]]:
    """The search's winner, the share of cluster-bootstrap resamples choosing ``target``, and the gap.

    Args:
        values: ``[E, C]`` each episode's loss under each candidate (the search's criterion).
        clusters: ``[E]`` the episode's instance; resampled whole.
        target: the candidate column to follow (the paper's choice).
        secondary: ``[E, C]`` the tie-break criterion, or None (ties go to the first column).

    Returns:
        ``winner`` (column on the full data), ``share_target`` (resamples whose winner is
        ``target``), ``share_winner`` (resamples keeping the full-data winner) and ``gap``:
        ``target`` minus the full-data winner's mean, paired on each resample, ``[point, lo, hi]``.
    """
    values = np.asarray(values, dtype=float)
    labels, inverse = np.unique(np.asarray(clusters), return_inverse=True)
    m = labels.size
    sums = np.stack([np.bincount(inverse, weights=values[:, c], minlength=m) for c in range(values.shape[1])], axis=1)
    n = np.bincount(inverse, minlength=m).astype(float)
    sec_sums = None
    if secondary is not None:
        secondary = np.asarray(secondary, dtype=float)
        sec_sums = np.stack([np.bincount(inverse, weights=secondary[:, c], minlength=m)
                             for c in range(secondary.shape[1])], axis=1)
    full = sums.sum(axis=0) / n.sum()
    win = int(winners(full[None, :], None if sec_sums is None else (sec_sums.sum(axis=0) / n.sum())[None, :])[0])
    counts = resample_counts(m, resamples, seed)
    means = (counts @ sums) / (counts @ n)[:, None]
    sec_means = None if sec_sums is None else (counts @ sec_sums) / (counts @ n)[:, None]
    chosen = winners(means, sec_means)
    lo, hi = percentile_interval(means[:, target] - means[:, win])
    return {"winner": win, "share_target": float(np.mean(chosen == target)),
            "share_winner": float(np.mean(chosen == win)),
            "gap": [float(full[target] - full[win]), float(lo), float(hi)]}
