"""Small statistics the explanations need (pure NumPy; hand-checked in the tests).

Each answers one question an explanation asks of stored data: how much more often a
gate's committed pool holds escaped episodes than the pool it rejects (with a cluster
bootstrap), what a stratum-standardized mean would be under another mix of strata, where a
realized draw sits among reseeded draws, and how much power an equivalence margin had.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from probecommit.audit.stats import percentile_interval, resample_counts

Triple = list[float]


def _ratio(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1.0), np.nan)


def pool_escape_ratio(committed: np.ndarray, escaped: np.ndarray, clusters: Sequence, *, resamples: int = 2000,
                      seed: int = 0) -> dict[str, Triple]:
    """Escape rate among committed and among rejected trajectories, and their ratio.

    The bootstrap resamples whole clusters (an instance's repeats together), the
    convention of every interval in the project.

    Args:
        committed: ``[T]`` whether each trajectory committed.
        escaped: ``[T]`` whether it escaped (the label under study).
        clusters: ``[T]`` cluster (instance) label.

    Returns:
        ``committed_rate``, ``rejected_rate`` and ``ratio`` (committed / rejected), each
        ``[point, lo, hi]``.
    """
    committed = np.asarray(committed, dtype=bool)
    escaped = np.asarray(escaped, dtype=float)
    labels, inverse = np.unique(np.asarray(clusters), return_inverse=True)
    m = labels.size

    def sums(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return (np.bincount(inverse[mask], weights=escaped[mask], minlength=m),
                np.bincount(inverse[mask], minlength=m).astype(float))

    ec, nc = sums(committed)
    er, nr = sums(~committed)
    counts = resample_counts(m, resamples, seed)
    rc, rr = _ratio(counts @ ec, counts @ nc), _ratio(counts @ er, counts @ nr)
    point_c, point_r = float(_ratio(ec.sum(), nc.sum())), float(_ratio(er.sum(), nr.sum()))
    out = {}
    for name, point, draws in (("committed_rate", point_c, rc), ("rejected_rate", point_r, rr),
                               ("ratio", float(_ratio(np.array(point_c), np.array(point_r))), _ratio(rc, rr))):
        lo, hi = percentile_interval(draws)
        out[name] = [point, lo, hi]
    return out


def standardized_mean(values: np.ndarray, strata: np.ndarray, weights: dict) -> float:
    """Direct standardization: ``sum_s w_s * mean(values | stratum s)``.

    The mean a sample would have had with the strata mixed in proportions ``weights``
    (normalized), each stratum keeping its own mean; NaN when a weighted stratum is empty.
    """
    values = np.asarray(values, dtype=float)
    strata = np.asarray(strata)
    total = float(sum(weights.values()))
    out = 0.0
    for stratum, w in weights.items():
        sel = strata == stratum
        if not sel.any():
            return math.nan
        out += (w / total) * float(values[sel].mean())
    return out


def percentile_of(value: float, draws: np.ndarray) -> float:
    """Mid-rank percentile of ``value`` among ``draws`` in [0, 1] (ties count one half)."""
    draws = np.asarray(draws, dtype=float)
    return float((np.sum(draws < value) + 0.5 * np.sum(draws == value)) / draws.size)


def _phi(x: float) -> float:
    return 0.5 * (1.0 + math.erf(x / math.sqrt(2.0)))


def equivalence_power(se: float, true_difference: float, margin: float, z: float = 1.959963984540054) -> float:
    """Probability that a normal ``estimate +- z se`` interval lies inside ``(-margin, margin)``.

    With the estimate ``N(true_difference, se)``: the chance the equivalence test passes.
    """
    if se <= 0:
        return float(abs(true_difference) < margin)
    upper = (margin - z * se - true_difference) / se
    lower = (-margin + z * se - true_difference) / se
    return max(0.0, _phi(upper) - _phi(lower))


def interval_se(lo: float, hi: float, z: float = 1.959963984540054) -> float:
    """The standard error a symmetric normal interval ``[lo, hi]`` implies."""
    return (hi - lo) / (2.0 * z)


def capture_failure(action: np.ndarray, x_hole: np.ndarray, c: np.ndarray, scale: float) -> np.ndarray:
    """Failure of an aim under a capture window ``scale * w(c)``, ``w(c) = 0.6 c + 1.1`` mm.

    The model's loss (``|a - x| >= w``) with the window scaled: what an engine whose
    capture is ``scale`` times the model's would report for the same aims.
    """
    window = scale * (0.6 * np.asarray(c, dtype=float) + 1.1)
    return (np.abs(np.asarray(action, dtype=float) - np.asarray(x_hole, dtype=float)) >= window).astype(float)


def conformal_quantile_draws(values: np.ndarray, counts: np.ndarray, alpha: float) -> np.ndarray:
    """The split-conformal quantile of each cluster-bootstrap resample of per-instance ``values``.

    ``counts`` is ``[B, M]`` multiplicities (``audit.stats.resample_counts``); resample ``b`` is
    ``values`` repeated by ``counts[b]``; its quantile is the ``ceil((1 - alpha)(M + 1))``-th
    smallest (``+inf`` past ``M``), the rule of ``audit.conformal.conformal_quantile``.
    """
    values = np.asarray(values, dtype=float)
    m = values.size
    q = math.ceil((1 - alpha) * (m + 1) - 1e-9)
    if q > m:
        return np.full(counts.shape[0], np.inf)
    order = np.argsort(values, kind="stable")
    cum = np.cumsum(counts[:, order], axis=1)  # [B, M] resampled counts at or below each sorted value
    idx = (cum >= q).argmax(axis=1)
    return values[order][idx]


def margin_draws(gammas: np.ndarray, predicted: np.ndarray, realized: np.ndarray, counts: np.ndarray,
                 slack: float = 1e-9) -> np.ndarray:
    """The validation-tuned margin of each cluster-bootstrap resample.

    Args:
        gammas: ``[G]`` candidates.
        predicted, realized: ``[G, M]`` per-instance sums of predicted and realized failure at
            each candidate.
        counts: ``[B, M]`` resample multiplicities.

    Returns:
        ``[B]`` the largest gamma whose resampled predicted sum reaches the realized sum (NaN
        where none does).
    """
    gammas = np.asarray(gammas, dtype=float)
    ok = counts @ np.asarray(predicted, float).T >= counts @ np.asarray(realized, float).T - slack  # [B, G]
    best = np.where(ok, gammas[None, :], -np.inf).max(axis=1)
    return np.where(np.isfinite(best), best, np.nan)
