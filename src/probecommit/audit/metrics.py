"""Per-budget audit metrics with cluster-bootstrap intervals (paper Sec. IV, "The audit").

For each budget ``k`` (and each method/variant group when the table has them):

- episode coverage: fraction of episodes whose truth lies in the retained interval;
- cluster coverage: fraction of instances covered in *all* their repeats;
- support escape: fraction of episodes whose truth lies outside the particle hull;
- ``R_k`` (mean realized), ``R̂_k`` (mean predicted) and optimism ``e_k = R_k - R̂_k``.

Failed episodes (``status == "failed"``) are excluded and counted. All intervals of
one group share one set of instance resamples (seeded by ``seed`` alone, so a
group's intervals do not depend on which other groups are in the table), and the
resamples are shared across budgets, so instance ``i`` is drawn together at every
budget.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from probecommit.audit.io import group_columns
from probecommit.audit.stats import (
    DEFAULT_LEVEL,
    DEFAULT_RESAMPLES,
    DEFAULT_SEED,
    bootstrap_ratio,
    resample_counts,
)

#: Metric names in report order, with their column in the output table.
METRICS = ("coverage", "cluster_coverage", "escape", "realized", "predicted", "optimism")


def _instance_sums(g: pd.DataFrame, names: np.ndarray) -> dict[str, np.ndarray]:
    """Per-instance sums and counts aligned with ``names`` (zero where absent)."""
    idx = np.searchsorted(names, g["instance_id"].to_numpy())
    m = names.size

    def total(values) -> np.ndarray:
        return np.bincount(idx, weights=np.asarray(values, dtype=float), minlength=m)

    n = np.bincount(idx, minlength=m).astype(float)
    covered = total(g["covered"].to_numpy(bool))
    return {
        "n": n,
        "covered": covered,
        "escaped": total(g["escaped"].to_numpy(bool)),
        "realized": total(g["realized"]),
        "predicted": total(g["predicted"]),
        # An instance counts for cluster coverage when it has episodes here; it is
        # covered when every one of them is.
        "present": (n > 0).astype(float),
        "all_covered": ((n > 0) & (covered == n)).astype(float),
    }


def audit_table(episodes: pd.DataFrame, *, budgets=None, resamples: int = DEFAULT_RESAMPLES,
                seed: int = DEFAULT_SEED, level: float = DEFAULT_LEVEL) -> pd.DataFrame:
    """The audit metrics per group and budget, each with its bootstrap interval.

    Args:
        episodes: A validated episode table (see :func:`probecommit.audit.io.validate_episodes`).
        budgets: Budgets to report (all present when None).
        resamples: Cluster-bootstrap resamples.
        seed: Bootstrap seed (the same draws for every group).
        level: Interval level.

    Returns:
        One row per (method, variant, k) with ``n_episodes``, ``n_instances``,
        ``n_repeats`` (max repeats per instance), ``n_failed`` and, for each
        metric in :data:`METRICS`, the columns ``<metric>``, ``<metric>_lo``,
        ``<metric>_hi``.
    """
    groups = group_columns(episodes)
    df = episodes
    failed = df["status"].astype(str).eq("failed") if "status" in df.columns else pd.Series(False, index=df.index)
    # Groups with no ok row at all (our runner's "rollout" rows for trajectories
    # whose probing failed) are not audited; their trajectories are missing from
    # every budget of every group, so they add to each row's failed count.
    all_groups = list(df.groupby(groups, sort=True)) if groups else [((), df)]
    dead = [g for _, g in all_groups if failed.loc[g.index].all()]
    n_dead = len(pd.concat([g[["instance_id", "repeat"]] for g in dead]).drop_duplicates()) if dead else 0
    if budgets is not None:
        df = df.loc[df["k"].isin(list(budgets))]
    rows = []
    grouped = list(df.groupby(groups, sort=True)) if groups else [((), df)]
    for gkey, g in grouped:
        gkey = gkey if isinstance(gkey, tuple) else (gkey,)
        if failed.loc[g.index].all():
            continue
        names = np.unique(g["instance_id"].to_numpy().astype(str))
        counts = resample_counts(names.size, resamples, seed)
        for k, gk in g.groupby("k", sort=True):
            fk = failed.loc[gk.index].to_numpy()
            ok = gk.loc[~fk]
            row = dict(zip(groups, gkey))
            row.update(k=int(k), n_episodes=int(len(ok)), n_instances=int(ok["instance_id"].nunique()),
                       n_repeats=int(ok.groupby("instance_id")["repeat"].nunique().max()) if len(ok) else 0,
                       n_failed=int(fk.sum()) + n_dead)
            if len(ok) == 0:
                rows.append(row)
                continue
            s = _instance_sums(ok, names)
            stats = {
                "coverage": bootstrap_ratio(s["covered"], s["n"], counts=counts, level=level),
                "cluster_coverage": bootstrap_ratio(s["all_covered"], s["present"], counts=counts, level=level),
                "escape": bootstrap_ratio(s["escaped"], s["n"], counts=counts, level=level),
                "realized": bootstrap_ratio(s["realized"], s["n"], counts=counts, level=level),
                "predicted": bootstrap_ratio(s["predicted"], s["n"], counts=counts, level=level),
                "optimism": bootstrap_ratio(s["realized"] - s["predicted"], s["n"], counts=counts, level=level),
            }
            for name, iv in stats.items():
                row[name], row[f"{name}_lo"], row[f"{name}_hi"] = iv.estimate, iv.lo, iv.hi
            rows.append(row)
    out = pd.DataFrame(rows)
    cols = groups + ["k", "n_episodes", "n_instances", "n_repeats", "n_failed"]
    cols += [f"{m}{suffix}" for m in METRICS for suffix in ("", "_lo", "_hi")]
    return out.reindex(columns=cols)


def summary_row(audit: pd.DataFrame, nominal: float = 0.8, coverage: str = "cluster_coverage") -> dict[str, float]:
    """Paper Table III bottom row: mean ``|coverage - nominal|`` and mean ``|e_k|`` over budgets."""
    return {
        f"mean_abs_{coverage}_gap": float(np.mean(np.abs(audit[coverage] - nominal))),
        "mean_abs_optimism": float(np.mean(np.abs(audit["optimism"]))),
    }
