"""Cluster bootstrap, paired differences, exact sign-flip test and rank AUC.

Every interval here is a percentile interval from a cluster bootstrap over
instances: a resample draws ``M`` instances with replacement and keeps each
instance's repeats (and budgets) together, because repeats of one instance share
its truth and are not independent. Resamples are represented as a count matrix
``W[B, M]`` (how often instance ``m`` appears in resample ``b``), so any statistic
that is a ratio of per-instance sums is one matrix product, with no Python loop
over resamples.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
import pandas as pd

#: Defaults used everywhere in the audit (recorded in docs/decisions.md).
DEFAULT_RESAMPLES = 2000
DEFAULT_SEED = 0
DEFAULT_LEVEL = 0.95

#: Fewest clusters an interval is given on (one cluster resamples to itself: zero width).
MIN_INTERVAL_CLUSTERS = 2
#: Below this many clusters an interval is given but flagged as unreliable.
FEW_CLUSTERS = 10


def few_clusters_note(n_clusters: int, what: str = "the intervals") -> str | None:
    """The warning for a bootstrap over few clusters (None when there are enough)."""
    if n_clusters < MIN_INTERVAL_CLUSTERS:
        return (f"{what} rest on {n_clusters} cluster(s) (instances): a bootstrap needs at least "
                f"{MIN_INTERVAL_CLUSTERS}, so no interval is given (shown as '–')")
    if n_clusters < FEW_CLUSTERS:
        return (f"{what} rest on only {n_clusters} clusters (instances); a cluster bootstrap under "
                f"{FEW_CLUSTERS} clusters is unreliable (intervals too narrow)")
    return None


#: Keys that identify one episode; paired comparisons join on them.
EPISODE_KEYS = ("instance_id", "repeat", "k")


@dataclass(frozen=True)
class Interval:
    """A point estimate with its cluster-bootstrap percentile interval.

    Attributes:
        estimate: Statistic on the original sample.
        lo: Lower percentile bound.
        hi: Upper percentile bound.
        n_clusters: Number of clusters (instances) resampled.
        resamples: Number of bootstrap resamples.
        level: Nominal coverage of the interval.
    """

    estimate: float
    lo: float
    hi: float
    n_clusters: int = 0
    resamples: int = DEFAULT_RESAMPLES
    level: float = DEFAULT_LEVEL

    def __str__(self) -> str:
        return f"{self.estimate:+.3f} [{self.lo:+.3f}, {self.hi:+.3f}]"

    def as_tuple(self) -> tuple[float, float, float]:
        return (self.estimate, self.lo, self.hi)


def _rng(seed: int | np.random.Generator | None) -> np.random.Generator:
    if isinstance(seed, np.random.Generator):
        return seed
    return np.random.default_rng(seed)


#: Elements of a bootstrap's per-resample work held at once (draws of a block of resamples, or
#: their episode weights in the AUC): 2^20 float64 or int64 values are 8 MB.
BOOTSTRAP_BLOCK_ELEMENTS = 1 << 20


def resample_counts(n_clusters: int, resamples: int = DEFAULT_RESAMPLES,
                    seed: int | np.random.Generator | None = DEFAULT_SEED) -> np.ndarray:
    """Cluster multiplicities of ``resamples`` bootstrap draws.

    Args:
        n_clusters: ``M``, the number of clusters.
        resamples: ``B``, the number of bootstrap resamples.
        seed: Integer seed or a Generator.

    Returns:
        ``[B, M]`` counts, whole numbers held as float64; each row sums to ``M``. They are
        multiplied into float sums (``counts @ x``), which would otherwise copy an integer matrix
        to float64 at each product: 47 MB beside the counts for 3072 clusters x 2000 resamples.
    """
    if n_clusters < 1:
        raise ValueError("cluster bootstrap needs at least one cluster")
    if resamples < 1:
        raise ValueError("resamples must be positive")
    from probecommit.process.memory import check_fits

    check_fits(8.0 * resamples * n_clusters, f"a cluster bootstrap of {n_clusters} clusters x {resamples} resamples",
               "the number of resamples (--resamples)")
    rng = _rng(seed)
    counts = np.empty((resamples, n_clusters), dtype=float)
    # Drawn and counted a block of rows at a time, so the draws never take more than a block
    # beside the result: consecutive draws continue the generator's stream (the same numbers as
    # one [B, M] draw, tested). One bincount per block: row b's indices shifted into [b*M, (b+1)*M).
    rows = max(1, BOOTSTRAP_BLOCK_ELEMENTS // n_clusters)
    for start in range(0, resamples, rows):
        block = min(rows, resamples - start)
        flat = rng.integers(0, n_clusters, size=(block, n_clusters))
        flat += (np.arange(block) * n_clusters)[:, None]
        counts[start:start + block] = np.bincount(flat.ravel(), minlength=block * n_clusters).reshape(block, n_clusters)
    return counts


def percentile_interval(draws: np.ndarray, level: float = DEFAULT_LEVEL) -> tuple[float, float]:
    """Percentile interval of bootstrap draws, ignoring NaN draws (empty resamples)."""
    draws = np.asarray(draws, dtype=float)
    finite = draws[np.isfinite(draws)]
    if finite.size == 0:
        return (math.nan, math.nan)
    tail = 100.0 * (1.0 - level) / 2.0
    lo, hi = np.percentile(finite, [tail, 100.0 - tail])
    return (float(lo), float(hi))


def _ratio(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1.0), np.nan)


def bootstrap_ratio(numerators: np.ndarray, denominators: np.ndarray, *,
                    resamples: int = DEFAULT_RESAMPLES, seed: int | np.random.Generator | None = DEFAULT_SEED,
                    level: float = DEFAULT_LEVEL, counts: np.ndarray | None = None) -> Interval:
    """Cluster bootstrap of ``sum(num) / sum(den)`` from per-cluster sums.

    With ``den`` the per-cluster episode counts this is the episode mean (a
    ratio estimator, so clusters with fewer valid episodes weigh less); with
    ``den = 1`` it is the mean over clusters.

    Args:
        numerators: ``[M]`` per-cluster sums.
        denominators: ``[M]`` per-cluster counts (or weights).
        resamples: Bootstrap resamples ``B``.
        seed: Seed or Generator (ignored when ``counts`` is given).
        level: Interval level.
        counts: Optional precomputed ``[B, M]`` multiplicities, to share draws
            across several statistics of one sample.

    Returns:
        The estimate and its percentile interval.
    """
    num = np.asarray(numerators, dtype=float)
    den = np.asarray(denominators, dtype=float)
    if counts is None:
        counts = resample_counts(num.shape[0], resamples, seed)
    estimate = float(_ratio(num.sum(), den.sum()))
    if int(np.count_nonzero(den > 0)) < MIN_INTERVAL_CLUSTERS:
        # One cluster resamples to itself: a zero-width interval would claim certainty it does not have.
        return Interval(estimate, math.nan, math.nan, num.shape[0], counts.shape[0], level)
    draws = _ratio(counts @ num, counts @ den)
    lo, hi = percentile_interval(draws, level)
    return Interval(estimate, lo, hi, num.shape[0], counts.shape[0], level)


def cluster_sums(values: np.ndarray, clusters: Sequence) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-cluster sums and counts of finite ``values``.

    Returns:
        ``(cluster_labels, sums, counts)``, clusters in sorted label order.
    """
    values = np.asarray(values, dtype=float)
    labels, inverse = np.unique(np.asarray(clusters), return_inverse=True)
    ok = np.isfinite(values)
    sums = np.bincount(inverse[ok], weights=values[ok], minlength=labels.size)
    counts = np.bincount(inverse[ok], minlength=labels.size).astype(float)
    return labels, sums, counts


def cluster_bootstrap_mean(values: np.ndarray, clusters: Sequence, *, resamples: int = DEFAULT_RESAMPLES,
                           seed: int | np.random.Generator | None = DEFAULT_SEED,
                           level: float = DEFAULT_LEVEL) -> Interval:
    """Mean of episode ``values`` with a cluster-bootstrap percentile interval.

    Args:
        values: ``[E]`` per-episode values (NaN entries are ignored).
        clusters: ``[E]`` cluster label (instance id) of each episode.
        resamples: Bootstrap resamples.
        seed: Integer seed or Generator.
        level: Interval level.

    Returns:
        The episode mean and its interval.
    """
    _, sums, counts = cluster_sums(values, clusters)
    return bootstrap_ratio(sums, counts, resamples=resamples, seed=seed, level=level)


# ----------------------------------------------------------------------------- paired


@dataclass(frozen=True)
class PairedDifference:
    """Paired difference ``treatment - baseline`` on identical episodes.

    Attributes:
        baseline_mean: Mean of the baseline arm over the paired episodes.
        treatment_mean: Mean of the treatment arm.
        difference: ``treatment_mean - baseline_mean`` with its interval.
        p_sign_flip: Two-sided sign-flip p-value over cluster mean differences.
        n_pairs: Paired episodes.
        n_clusters: Paired clusters.
    """

    baseline_mean: float
    treatment_mean: float
    difference: Interval
    p_sign_flip: float
    n_pairs: int
    n_clusters: int


def pair_episodes(baseline: pd.DataFrame, treatment: pd.DataFrame, value: str = "realized",
                  keys: Sequence[str] = EPISODE_KEYS, strict: bool = True) -> pd.DataFrame:
    """Join two episode tables on identical episodes.

    Args:
        baseline: Episode table of the baseline arm.
        treatment: Episode table of the treatment arm.
        value: Column compared.
        keys: Columns identifying one episode (instance, repeat, budget).
        strict: Raise when the two tables do not hold the same episodes.

    Returns:
        DataFrame with the key columns, ``baseline``, ``treatment`` and ``diff``.

    Raises:
        ValueError: Duplicate keys in an arm, or (strict) unmatched episodes.
    """
    keys = list(keys)
    a = baseline[keys + [value]].rename(columns={value: "baseline"})
    b = treatment[keys + [value]].rename(columns={value: "treatment"})
    for name, t in (("baseline", a), ("treatment", b)):
        dup = t.duplicated(keys)
        if dup.any():
            first = t.loc[dup, keys].iloc[0].to_dict()
            raise ValueError(f"{name} arm has duplicate episodes for keys {keys}, e.g. {first}; "
                             "select one method/variant before pairing")
    joined = a.merge(b, on=keys, how="outer", indicator=True)
    unmatched = joined["_merge"] != "both"
    if strict and unmatched.any():
        n_a = int((joined["_merge"] == "left_only").sum())
        n_b = int((joined["_merge"] == "right_only").sum())
        raise ValueError(f"paired comparison needs identical episodes: {n_a} baseline-only and "
                         f"{n_b} treatment-only episodes on keys {keys}")
    joined = joined.loc[~unmatched].drop(columns="_merge")
    joined = joined.dropna(subset=["baseline", "treatment"])
    joined["diff"] = joined["treatment"].astype(float) - joined["baseline"].astype(float)
    return joined.reset_index(drop=True)


def paired_bootstrap(baseline: pd.DataFrame, treatment: pd.DataFrame, value: str = "realized", *,
                     keys: Sequence[str] = EPISODE_KEYS, cluster: str = "instance_id",
                     resamples: int = DEFAULT_RESAMPLES, seed: int | np.random.Generator | None = DEFAULT_SEED,
                     level: float = DEFAULT_LEVEL, strict: bool = True) -> PairedDifference:
    """Paired difference of ``value`` (treatment minus baseline) with a paired cluster bootstrap.

    Both arms are resampled with the *same* instance draws (the pair is the
    unit), so the interval reflects only the within-episode change.

    Args:
        baseline: Baseline episode table.
        treatment: Treatment episode table (same episodes).
        value: Column compared, ``realized`` failure by default.
        keys: Episode identity columns.
        cluster: Cluster column (instance).
        resamples: Bootstrap resamples.
        seed: Seed or Generator.
        level: Interval level.
        strict: Require identical episode sets.

    Returns:
        The paired difference, its interval and an exact sign-flip p-value.
    """
    pairs = pair_episodes(baseline, treatment, value, keys, strict)
    if pairs.empty:
        raise ValueError("no paired episodes to compare")
    labels, dsum, n = cluster_sums(pairs["diff"].to_numpy(), pairs[cluster].to_numpy())
    diff = bootstrap_ratio(dsum, n, resamples=resamples, seed=seed, level=level)
    p = sign_flip_test(dsum / n, seed=seed)
    return PairedDifference(float(pairs["baseline"].mean()), float(pairs["treatment"].mean()), diff, p,
                            len(pairs), labels.size)


#: Sign draws held at once by the Monte Carlo sign-flip test.
SIGN_BLOCK_ELEMENTS = 1 << 21


def sign_flip_test(cluster_differences: np.ndarray, *, max_exact: int = 20, resamples: int = 100_000,
                   seed: int | np.random.Generator | None = DEFAULT_SEED) -> float:
    """Two-sided sign-flip (randomization) test of zero mean over clusters.

    Under the null each cluster's mean difference is symmetric about zero, so
    flipping its sign leaves the law unchanged. The statistic is
    ``|sum_i d_i|``; the p-value is the fraction of the ``2^M`` sign patterns
    whose statistic is at least the observed one (ties count, within a relative
    1e-12). Clusters with ``d_i = 0`` are dropped: they contribute nothing
    under any sign, so dropping them leaves the exact p-value unchanged.

    Args:
        cluster_differences: ``[M]`` per-cluster mean differences.
        max_exact: Enumerate all patterns when at most this many nonzero
            clusters remain; otherwise a Monte Carlo estimate with the
            ``(1 + hits) / (1 + draws)`` correction.
        resamples: Monte Carlo draws for large ``M``.
        seed: Seed for the Monte Carlo path.

    Returns:
        The p-value in ``(0, 1]``.
    """
    d = np.asarray(cluster_differences, dtype=float)
    d = d[np.isfinite(d) & (d != 0.0)]
    if d.size == 0:
        return 1.0
    observed = abs(d.sum())
    tol = 1e-12 * max(1.0, np.abs(d).sum())
    if d.size <= max_exact:
        hits = 0
        total = 0
        # Enumerate in chunks of at most 2^12 patterns of the leading clusters
        # against all patterns of the rest, to bound memory.
        head = min(d.size, 12)
        head_signs = np.array(list(itertools.product((1.0, -1.0), repeat=head)))  # [2^h, h]
        head_sums = head_signs @ d[:head]
        tail = d[head:]
        for tail_signs in itertools.product((1.0, -1.0), repeat=tail.size):
            s = head_sums + (np.dot(tail_signs, tail) if tail.size else 0.0)
            hits += int(np.count_nonzero(np.abs(s) >= observed - tol))
            total += s.size
        return hits / total
    rng = _rng(seed)
    # Draw the [resamples, M] signs in blocks of rows (about 16 MB each; all of them at
    # once is 600 MB at M = 768): consecutive draws continue the generator's stream, so
    # the signs, and the p-value, are those of a single draw.
    # The signs are ``rng.choice((-1.0, 1.0), size)``'s, drawn as that draws them (its indices,
    # ``rng.integers(0, 2, size)``: the same stream, tested) and mapped 0 -> -1, 1 -> +1 by arithmetic
    # instead of a gather: a third of the time, the same float matrix, so the same sums.
    rows = max(1, SIGN_BLOCK_ELEMENTS // d.size)
    hits = 0
    for start in range(0, resamples, rows):
        signs = rng.integers(0, 2, size=(min(rows, resamples - start), d.size)).astype(float)
        signs *= 2.0
        signs -= 1.0
        hits += int(np.count_nonzero(np.abs(signs @ d) >= observed - tol))
    return (1 + hits) / (1 + resamples)


# ----------------------------------------------------------------------------- AUC


def rank_auc(scores: np.ndarray, labels: np.ndarray) -> float:
    """Mann–Whitney rank AUC: ``P(score_pos > score_neg) + P(tie) / 2``.

    Args:
        scores: ``[E]`` scores, higher meaning "more likely positive".
        labels: ``[E]`` booleans (positive class, e.g. escaped).

    Returns:
        The AUC, or NaN when one class is empty.
    """
    return float(_weighted_auc(np.asarray(scores, dtype=float), np.asarray(labels, dtype=bool),
                               np.ones((1, len(scores))))[0])


def _weighted_auc(scores: np.ndarray, labels: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """AUC per row of episode ``weights[B, E]``; ties between scores count one half."""
    order = np.argsort(scores, kind="stable")
    s = scores[order]
    pos = labels[order]
    w = weights[:, order]
    starts = np.flatnonzero(np.r_[True, s[1:] != s[:-1]])  # tie groups of equal scores
    wp = np.add.reduceat(np.where(pos, w, 0.0), starts, axis=1)  # [B, G]
    wn = np.add.reduceat(np.where(pos, 0.0, w), starts, axis=1)
    neg_below = np.cumsum(wn, axis=1) - wn
    num = np.sum(wp * (neg_below + 0.5 * wn), axis=1)
    den = wp.sum(axis=1) * wn.sum(axis=1)
    return _ratio(num, den)


def cluster_bootstrap_auc(scores: np.ndarray, labels: np.ndarray, clusters: Sequence, *,
                          resamples: int = DEFAULT_RESAMPLES, seed: int | np.random.Generator | None = DEFAULT_SEED,
                          level: float = DEFAULT_LEVEL) -> Interval:
    """Rank AUC with a cluster-bootstrap percentile interval.

    A resampled instance brings all its episodes, positive and negative alike,
    as integer weights; resamples with an empty class are dropped (NaN).

    Only a NaN score (one the data leave undefined) is left out. An infinite score is a rank
    like any other: ``+inf`` (e.g. a surprise where no particle predicted what was read) ranks
    above every finite score, ties with other ``+inf``; dropping it would remove exactly the most
    surprised episodes from the AUC while the caller still counts them.

    Args:
        scores: ``[E]`` scores.
        labels: ``[E]`` booleans.
        clusters: ``[E]`` cluster labels.
        resamples: Bootstrap resamples.
        seed: Seed or Generator.
        level: Interval level.

    Returns:
        The AUC and its interval.
    """
    scores = np.asarray(scores, dtype=float)
    labels = np.asarray(labels, dtype=bool)
    ok = ~np.isnan(scores)
    scores, labels = scores[ok], labels[ok]
    names, inverse = np.unique(np.asarray(clusters)[ok], return_inverse=True)
    estimate = rank_auc(scores, labels)
    if scores.size == 0 or names.size < MIN_INTERVAL_CLUSTERS:
        return Interval(estimate if scores.size else math.nan, math.nan, math.nan, names.size, resamples, level)
    counts = resample_counts(names.size, resamples, seed)
    # Each resample's AUC is computed from its own row of episode weights: a block of rows at a
    # time, so the [B, E] weights (0.5 GB at B = 2000, E = 30720) never exist at once.
    rows = max(1, BOOTSTRAP_BLOCK_ELEMENTS // scores.size)
    draws = np.concatenate([_weighted_auc(scores, labels, counts[start:start + rows][:, inverse])
                            for start in range(0, resamples, rows)])
    lo, hi = percentile_interval(draws, level)
    return Interval(estimate, lo, hi, names.size, resamples, level)
