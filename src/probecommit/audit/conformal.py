"""Instance-level conformal thresholds for the coverage score (paper Sec. IV).

At a fixed budget ``k`` instance ``i`` contributes ``s_rep_{i,k} = max_l s_{i,l,k}``
(its worst repeat), so that ``s_rep <= t`` means every repeat is covered. For a
pre-specified budget set ``K`` the simultaneous score is ``S_i = max_{k in K}
s_rep_{i,k}``. With ``M`` exchangeable calibration clusters the threshold is the
``q``-th smallest score, ``q = ceil((1 - alpha)(M + 1))``, and ``+inf`` when
``q = M + 1``; a fresh cluster then has all its repeats (and budgets) covered with
probability at least ``1 - alpha``, marginally.
"""

from __future__ import annotations

import math
from typing import Iterable

import numpy as np
import pandas as pd

from probecommit.audit.io import ok_episodes

#: The paper's level: 1 - alpha = 0.80.
DEFAULT_ALPHA = 0.2

# (1 - alpha)(M + 1) can land a hair above an integer in floating point
# (0.8 * 5 -> 4.000000000000001 for some alpha); this slack keeps ceil() exact.
_CEIL_SLACK = 1e-9


def conformal_rank(n_calibration: int, alpha: float = DEFAULT_ALPHA) -> int:
    """``q = ceil((1 - alpha)(M + 1))``, the rank of the conformal quantile (1-based)."""
    if not 0 < alpha < 1:
        raise ValueError(f"alpha must be in (0, 1), got {alpha!r}")
    if n_calibration < 1:
        raise ValueError("conformal calibration needs at least one calibration score")
    return int(math.ceil((1.0 - alpha) * (n_calibration + 1) - _CEIL_SLACK))


def conformal_quantile(scores: Iterable[float], alpha: float = DEFAULT_ALPHA) -> float:
    """The conformal threshold: the ``q``-th smallest score, ``+inf`` when ``q = M + 1``.

    Args:
        scores: ``M`` calibration scores, one per exchangeable cluster.
        alpha: Miscoverage level (``1 - alpha`` is the target coverage).

    Returns:
        The threshold ``t``; a fresh cluster's score is ``<= t`` with
        probability at least ``1 - alpha``.
    """
    s = np.sort(np.asarray(list(scores) if not isinstance(scores, np.ndarray) else scores, dtype=float))
    if np.isnan(s).any():
        raise ValueError("conformal scores contain NaN")
    q = conformal_rank(s.size, alpha)
    return math.inf if q > s.size else float(s[q - 1])


def _probe_rows(episodes: pd.DataFrame, score: str) -> pd.DataFrame:
    df = ok_episodes(episodes)
    if score not in df.columns:
        raise ValueError(f"episode table has no '{score}' column; the coverage score is needed for calibration")
    if "method" in df.columns and df["method"].nunique() > 1:
        raise ValueError("calibration scores need one method; filter the table first "
                         f"(found {sorted(df['method'].unique())})")
    if "variant" in df.columns and df["variant"].nunique() > 1:
        raise ValueError("calibration scores need one model variant; filter the table first "
                         f"(found {sorted(df['variant'].unique())})")
    bad = df[score].isna()
    if bad.any():
        raise ValueError(f"'{score}' is NaN on {int(bad.sum())} ok episode(s)")
    return df


def instance_scores(episodes: pd.DataFrame, k: int | None = None, score: str = "score_s") -> pd.Series | pd.DataFrame:
    """Worst-repeat score per instance: ``s_rep_{i,k} = max_l s_{i,l,k}``.

    Args:
        episodes: Episode table of one method and variant.
        k: A budget; None returns every budget as columns.
        score: Score column.

    Returns:
        A Series indexed by ``instance_id`` (given ``k``), else a DataFrame
        ``instance_id x k``.
    """
    df = _probe_rows(episodes, score)
    table = df.pivot_table(index="instance_id", columns="k", values=score, aggfunc="max")
    if k is None:
        return table
    if k not in table.columns:
        raise ValueError(f"no episodes at budget k={k}")
    return table[k].dropna()


def simultaneous_scores(episodes: pd.DataFrame, budgets: Iterable[int], score: str = "score_s") -> pd.Series:
    """Budget-simultaneous score ``S_i = max_{k in K} s_rep_{i,k}`` per instance.

    Raises:
        ValueError: An instance lacks a budget of the set (its ``S_i`` would be
            taken over fewer budgets and no longer be simultaneous).
    """
    return worst_budget_scores(instance_scores(episodes, None, score), budgets)


def worst_budget_scores(scores: pd.DataFrame, budgets: Iterable[int]) -> pd.Series:
    """:func:`simultaneous_scores` from the worst-repeat scores ``instance_scores(episodes)``.

    Instances are independent rows of ``scores``, so the scores of a table's parts
    (whole instances each), concatenated, give the whole table's.
    """
    budgets = sorted(int(b) for b in budgets)
    missing = [b for b in budgets if b not in scores.columns]
    if missing:
        raise ValueError(f"no episodes at budget(s) {missing}")
    sub = scores[budgets]
    incomplete = sub.isna().any(axis=1)
    if incomplete.any():
        raise ValueError(f"instance {sub.index[incomplete][0]!r} lacks episodes at some budget of {budgets}")
    return sub.max(axis=1)


def fixed_budget_thresholds(episodes: pd.DataFrame, alpha: float = DEFAULT_ALPHA, budgets: Iterable[int] | None = None,
                            score: str = "score_s") -> dict[int, float]:
    """Per-budget thresholds ``t_k`` from worst-repeat calibration scores."""
    return budget_thresholds(instance_scores(episodes, None, score), alpha, budgets)


def budget_thresholds(scores: pd.DataFrame, alpha: float = DEFAULT_ALPHA,
                      budgets: Iterable[int] | None = None) -> dict[int, float]:
    """:func:`fixed_budget_thresholds` from the worst-repeat scores ``instance_scores(episodes)``."""
    budgets = sorted(scores.columns) if budgets is None else sorted(int(b) for b in budgets)
    return {int(k): conformal_quantile(scores[k].dropna().to_numpy(), alpha) for k in budgets}


def simultaneous_threshold(episodes: pd.DataFrame, budgets: Iterable[int], alpha: float = DEFAULT_ALPHA,
                           score: str = "score_s") -> float:
    """Shared threshold ``t`` from budget-simultaneous calibration scores."""
    return conformal_quantile(simultaneous_scores(episodes, budgets, score).to_numpy(), alpha)


def score_coverage(episodes: pd.DataFrame, thresholds: float | dict[int, float], score: str = "score_s") -> pd.DataFrame:
    """Coverage implied by the score identity, ``s <= t``, per budget.

    This is the conformal event itself (episode and cluster level). The
    coverage we *report* after calibration is measured on the executor's set as
    constructed (the ``covered`` column of the re-executed table); the two
    differ only on the zero-weight plateau at ``t = 1`` (docs/decisions.md).

    Args:
        episodes: Test episode table (one method, variant).
        thresholds: A shared ``t`` or ``{k: t_k}``.
        score: Score column.

    Returns:
        ``k``, ``episode_coverage``, ``cluster_coverage``, ``threshold``.
    """
    df = _probe_rows(episodes, score)
    t = df["k"].map(thresholds) if isinstance(thresholds, dict) else pd.Series(float(thresholds), index=df.index)
    inside = df[score].to_numpy() <= t.to_numpy(dtype=float)
    frame = pd.DataFrame({"k": df["k"].to_numpy(), "instance_id": df["instance_id"].to_numpy(), "inside": inside})
    per_inst = frame.groupby(["k", "instance_id"])["inside"].all().groupby(level=0).mean()
    per_ep = frame.groupby("k")["inside"].mean()
    out = pd.DataFrame({"episode_coverage": per_ep, "cluster_coverage": per_inst}).reset_index()
    out["threshold"] = out["k"].map(thresholds) if isinstance(thresholds, dict) else float(thresholds)
    return out
