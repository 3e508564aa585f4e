"""Prequential surprise and how well it ranks final-budget escapes (paper Sec. VI).

The surprise of a probe is ``-log p(y_j | y_{1:j-1})``, its predictive density
before assimilation; an episode at budget ``k`` aggregates the maximum over the
probes seen, ``max_{j <= k}``. The runner writes it as ``max_surprise``; this
module recomputes it from per-probe log predictive densities when needed and
measures its rank AUC for "the truth is outside the hull at the final budget".
"""

from __future__ import annotations

from typing import Iterable

import numpy as np
import pandas as pd

from probecommit.audit.io import ok_episodes
from probecommit.audit.stats import (
    DEFAULT_LEVEL,
    DEFAULT_RESAMPLES,
    DEFAULT_SEED,
    cluster_bootstrap_auc,
)


def max_surprise(log_predictive: np.ndarray) -> np.ndarray:
    """Running maximum of ``-log`` predictive density over the probes seen.

    Args:
        log_predictive: ``[E, K]`` log predictive density of probe ``j`` before
            it is assimilated (``ParticleFilter.log_predictive``).

    Returns:
        ``[E, K]``; column ``k-1`` is the surprise of an episode at budget ``k``.
    """
    return np.maximum.accumulate(-np.asarray(log_predictive, dtype=float), axis=-1)


def final_escape(episodes: pd.DataFrame, final_k: int | None = None) -> pd.Series:
    """Whether each trajectory ``(instance_id, repeat)`` escapes the hull at the final budget."""
    df = ok_episodes(episodes)
    final_k = int(df["k"].max()) if final_k is None else int(final_k)
    last = df.loc[df["k"] == final_k]
    if last.empty:
        raise ValueError(f"no ok episodes at the final budget k={final_k}")
    return last.set_index(["instance_id", "repeat"])["escaped"].astype(bool)


def surprise_auc(episodes: pd.DataFrame, *, budgets: Iterable[int] | None = None, final_k: int | None = None,
                 column: str = "max_surprise", resamples: int = DEFAULT_RESAMPLES, seed: int = DEFAULT_SEED,
                 level: float = DEFAULT_LEVEL) -> pd.DataFrame:
    """Rank AUC of the surprise at each budget for final-budget escape.

    Args:
        episodes: One method/variant's episode table with ``max_surprise``.
        budgets: Budgets at which the surprise is read (default: all ``k >= 1``).
        final_k: The final budget defining the label (default: the largest).
        column: Surprise column.
        resamples: Cluster-bootstrap resamples.
        seed: Bootstrap seed.
        level: Interval level.

    Returns:
        One row per budget: ``k``, ``n_escaped``, ``n_covered`` (not escaped),
        ``auc``, ``auc_lo``, ``auc_hi``.
    """
    df = ok_episodes(episodes)
    if column not in df.columns:
        raise ValueError(f"episode table has no '{column}' column")
    label = final_escape(df, final_k)
    budgets = sorted(int(k) for k in df["k"].unique() if k >= 1) if budgets is None else sorted(budgets)
    rows = []
    for k in budgets:
        at = df.loc[df["k"] == k].set_index(["instance_id", "repeat"])
        joined = at[[column]].join(label.rename("_esc"), how="inner").dropna(subset=[column])
        y = joined["_esc"].to_numpy(bool)
        iv = cluster_bootstrap_auc(joined[column].to_numpy(float), y,
                                   joined.index.get_level_values("instance_id").to_numpy(),
                                   resamples=resamples, seed=seed, level=level)
        rows.append({"k": k, "n_escaped": int(y.sum()), "n_covered": int((~y).sum()),
                     "auc": iv.estimate, "auc_lo": iv.lo, "auc_hi": iv.hi})
    return pd.DataFrame(rows)
