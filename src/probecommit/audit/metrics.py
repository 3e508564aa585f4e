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


#: Per-instance sums of one group and budget (``instance_sums``), in report order.
SUM_COLUMNS = ("n", "covered", "escaped", "realized", "predicted", "n_repeats", "n_failed")


def instance_sums(episodes: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The audit's sufficient statistics: per group, budget and instance, sums over its episodes.

    Every sum is a ``np.bincount`` over one instance's rows in table order, so the sums
    of a table split between instances (whole instances in each part, rows in order)
    are those of the whole table: :func:`audit_table` of a table equals
    :func:`audit_from_sums` of its parts' sums concatenated.

    Args:
        episodes: A validated episode table.

    Returns:
        ``(sums, failed)``: ``sums`` has the group columns, ``k``, ``instance_id`` and
        :data:`SUM_COLUMNS` (ok episodes counted, summed and their repeats counted; failed
        rows counted in ``n_failed``), one row per group, budget and instance with any row;
        ``failed`` holds the group columns, ``k``, ``instance_id`` and ``repeat`` of the
        failed rows.
    """
    groups = group_columns(episodes)
    keys = groups + ["k"]
    failed = (episodes["status"].astype(str).eq("failed").to_numpy() if "status" in episodes.columns
              else np.zeros(len(episodes), bool))
    ids = episodes["instance_id"].to_numpy().astype(str)
    values = {name: episodes[name].to_numpy(bool).astype(float) for name in ("covered", "escaped")}
    values |= {name: episodes[name].to_numpy(float) for name in ("realized", "predicted")}
    repeat = episodes["repeat"].to_numpy()
    gkeys, parts = [], []
    # Positions of each group's rows, in table order (groupby's indices keep it).
    for gkey, pos in (episodes.groupby(keys).indices.items() if len(episodes) else ()):
        names, idx = np.unique(ids[pos], return_inverse=True)
        fk = failed[pos]
        ok, oi, m = pos[~fk], idx[~fk], names.size
        gkeys.append(gkey if isinstance(gkey, tuple) else (gkey,))
        parts.append({"instance_id": names, "n": np.bincount(oi, minlength=m).astype(float),
                      **{column: np.bincount(oi, weights=values[column][ok], minlength=m) for column in values},
                      "n_repeats": _distinct_counts(oi, repeat[ok], m), "n_failed": np.bincount(idx[fk], minlength=m)})
    columns = keys + ["instance_id", *SUM_COLUMNS]
    if not parts:
        sums = pd.DataFrame(columns=columns)
    else:  # one frame of every group's rows, as the groups' own frames concatenated would be
        sizes = [part["instance_id"].size for part in parts]
        sums = pd.DataFrame({**{key: np.repeat(np.asarray([g[j] for g in gkeys]), sizes) for j, key in enumerate(keys)},
                             **{name: np.concatenate([part[name] for part in parts]) for name in parts[0]}})
    return sums[columns], episodes.loc[failed, keys + ["instance_id", "repeat"]].reset_index(drop=True)


def _distinct_counts(group: np.ndarray, values: np.ndarray, m: int) -> np.ndarray:
    """How many distinct ``values`` (NaN not counted) each group ``0..m-1`` has (``int64 [m]``)."""
    if values.dtype.kind == "f":
        group, values = group[~np.isnan(values)], values[~np.isnan(values)]
    order = np.lexsort((values, group))
    group, values = group[order], values[order]
    first = np.ones(group.size, dtype=bool)
    first[1:] = (group[1:] != group[:-1]) | (values[1:] != values[:-1])
    return np.bincount(group[first], minlength=m).astype(np.int64)


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
    return audit_from_sums(*instance_sums(episodes), budgets=budgets, resamples=resamples, seed=seed, level=level)


def audit_from_sums(sums: pd.DataFrame, failed: pd.DataFrame, *, budgets=None, resamples: int = DEFAULT_RESAMPLES,
                    seed: int = DEFAULT_SEED, level: float = DEFAULT_LEVEL) -> pd.DataFrame:
    """:func:`audit_table` from :func:`instance_sums` (of a table, or of its parts concatenated).

    Args:
        sums: The per-instance sums.
        failed: The failed rows' keys.
        budgets: Budgets to report (all present when None).
        resamples: Cluster-bootstrap resamples.
        seed: Bootstrap seed (the same draws for every group).
        level: Interval level.

    Returns:
        The table :func:`audit_table` returns.
    """
    groups = [c for c in sums.columns if c not in ("k", "instance_id", *SUM_COLUMNS)]
    # Groups with no ok row at all (our runner's "rollout" rows for trajectories
    # whose probing failed) are not audited; their trajectories are missing from
    # every budget of every group, so they add to each row's failed count.
    ok_rows = sums.groupby(groups, sort=True)["n"].sum() if groups else pd.Series([sums["n"].sum()])
    dead_keys = [key if isinstance(key, tuple) else (key,) for key, n in ok_rows.items() if n == 0]
    n_dead = 0
    if dead_keys and groups:
        dead = failed.set_index(groups).index.isin(dead_keys)
        n_dead = len(failed.loc[dead, ["instance_id", "repeat"]].drop_duplicates())
    elif dead_keys:
        n_dead = len(failed[["instance_id", "repeat"]].drop_duplicates())
    if budgets is not None:
        sums = sums.loc[sums["k"].isin(list(budgets))]
    rows = []
    grouped = list(sums.groupby(groups, sort=True)) if groups else [((), sums)]
    for gkey, g in grouped:
        gkey = gkey if isinstance(gkey, tuple) else (gkey,)
        if g["n"].sum() == 0:
            continue
        names = np.unique(g["instance_id"].to_numpy().astype(str))
        counts = resample_counts(names.size, resamples, seed)
        for k, gk in g.groupby("k", sort=True):
            present = gk["n"].to_numpy() > 0
            row = dict(zip(groups, gkey))
            row.update(k=int(k), n_episodes=int(gk["n"].sum()), n_instances=int(present.sum()),
                       n_repeats=int(gk["n_repeats"].max()) if present.any() else 0,
                       n_failed=int(gk["n_failed"].sum()) + n_dead)
            if not present.any():
                rows.append(row)
                continue
            at = np.searchsorted(names, gk["instance_id"].to_numpy().astype(str))
            s = {}
            for column in ("n", "covered", "escaped", "realized", "predicted"):
                s[column] = np.zeros(names.size)
                s[column][at] = gk[column].to_numpy(float)
            # An instance counts for cluster coverage when it has episodes here; it is
            # covered when every one of them is.
            s["present"] = (s["n"] > 0).astype(float)
            s["all_covered"] = ((s["n"] > 0) & (s["covered"] == s["n"])).astype(float)
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
