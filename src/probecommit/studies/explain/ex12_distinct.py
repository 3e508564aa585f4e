"""Table III's original arm under a random schedule drawn without replacement (E100; ex12, issue #36;
rule declared in ``docs/decisions.md``, "ex12").

Our random schedule draws each tap i.i.d. uniform over the probe grid, with replacement, so a budget
of k taps touches fewer than k distinct positions, and a repeated position tells the belief nothing
new about the hole. The first occurrences of an i.i.d. uniform sequence are, in order, a uniformly
random ordered subset of the grid: a schedule drawn without replacement. So the budget-k row of that
schedule is, for each stored episode, the row at the tap where its k-th distinct position first
appears; an episode that never reaches k distinct positions has none. Everything is read from stored
episode and probe tables (E17's fresh draws and the frozen Split B random test run): no engine runs.

Every key of the ``ex12_distinct`` group is :func:`summary` of the stored rows (:data:`STORED`), so
verify recomputes them from the very rows the step stores.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pandas as pd

#: The stored per-(draw, episode, budget) rows, beside results.json.
STORED = "ex12_distinct_rows.parquet"
#: Result group.
GROUP = "ex12_distinct"
#: Table III's budgets that 8 taps drawn with replacement from 9 positions reach often enough (k = 8
#: needs all 8 distinct: 0.9 % of episodes).
BUDGETS = (1, 2, 3, 5)
#: A draw's cell counts only with at least this many eligible clusters (docs/decisions.md, "ex12").
MIN_CLUSTERS = 40
#: The frozen draw's label (published beside the fresh draws, not in their range).
FROZEN = "frozen"
_KEY = ["instance_id", "repeat"]


def distinct_rows(episodes: pd.DataFrame, probes: pd.DataFrame, budgets: Sequence[int] = BUDGETS) -> pd.DataFrame:
    """Per episode and budget k, the stored row at the tap where the k-th distinct position first appears.

    Args:
        episodes: A run's episode table (one method), a row per ``instance_id, repeat, k``.
        probes: Its probe table, a row per ``instance_id, repeat, j`` with the position ``u``.

    Returns:
        ``instance_id, repeat, k`` (the distinct budget), ``tap`` (the stored budget read),
        ``covered, predicted, realized``; episodes short of k distinct positions have no row at k.
    """
    p = probes.sort_values([*_KEY, "j"])
    first = ~p.duplicated([*_KEY, "u"])
    p = p.loc[first, [*_KEY, "j"]].copy()
    p["k"] = p.groupby(_KEY).cumcount() + 1
    p = p[p["k"].isin(list(budgets))].rename(columns={"j": "tap"})
    cols = [*_KEY, "k", "covered", "predicted", "realized"]
    stored = episodes[cols].rename(columns={"k": "tap"})
    out = p.merge(stored, on=[*_KEY, "tap"], how="inner", validate="one_to_one")
    return out[[*_KEY, "k", "tap", "covered", "predicted", "realized"]].reset_index(drop=True)


def cells(rows: pd.DataFrame, repeats: int) -> pd.DataFrame:
    """Per budget: cluster coverage over clusters with all ``repeats`` episodes present, optimism over
    those same episodes (mean realized minus mean predicted), and the number of such clusters."""
    out = []
    for k, at in rows.groupby("k"):
        n = at.groupby("instance_id")["covered"].transform("size")
        full = at[n == repeats]
        cluster = full.groupby("instance_id")["covered"].all()
        out.append({"k": int(k), "clusters": int(cluster.size),
                    "cluster_coverage": float(cluster.mean()) if cluster.size else np.nan,
                    "optimism": float(full["realized"].mean() - full["predicted"].mean()) if len(full) else np.nan})
    return pd.DataFrame(out)


def summary(stored: pd.DataFrame, budgets: Sequence[int] = BUDGETS,
            min_clusters: int = MIN_CLUSTERS) -> dict[str, Any]:
    """The group's keys from the stored rows (``draw`` column: fresh draw labels and :data:`FROZEN`).

    Per cell ``<metric>.k<k>``: ``.min/.max/.mean`` over the fresh draws (NaN when a draw has fewer
    than ``min_clusters`` eligible clusters at that budget) and ``.frozen``; ``clusters.k<k>.min``;
    ``draws``.
    """
    out: dict[str, Any] = {}
    repeats = int(stored["repeat"].nunique())  # every repeat has a budget-1 row
    per_draw = {d: cells(g, repeats).set_index("k") for d, g in stored.groupby("draw", sort=True)}
    fresh = [d for d in per_draw if d != FROZEN]
    out["draws"] = len(fresh)
    for k in budgets:
        counts = [int(per_draw[d]["clusters"].get(k, 0)) for d in fresh]
        out[f"clusters.k{k}.min"] = min(counts) if counts else 0
        thin = not counts or min(counts) < min_clusters
        for metric in ("cluster_coverage", "optimism"):
            values = np.array([per_draw[d][metric].get(k, np.nan) for d in fresh], dtype=float)
            for stat, f in (("min", np.min), ("max", np.max), ("mean", np.mean)):
                out[f"{metric}.k{k}.{stat}"] = float("nan") if thin else float(f(values))
            if FROZEN in per_draw:
                out[f"{metric}.k{k}.frozen"] = float(per_draw[FROZEN][metric].get(k, np.nan))
    return out


def _run_rows(run: Path, draw: str) -> pd.DataFrame:
    episodes = pd.read_parquet(run / "episodes.parquet", columns=["instance_id", "repeat", "k", "method", "covered",
                                                                   "predicted", "realized"])
    episodes = episodes[episodes["method"] == "probe_robust"]
    rows = distinct_rows(episodes, pd.read_parquet(run / "probes.parquet", columns=[*_KEY, "j", "u"]))
    rows.insert(0, "draw", draw)
    return rows


def run(explain: Any) -> None:
    """The explain step: re-index E17's fresh draws and the frozen test run, store the rows, publish keys."""
    explain.progress("explain: Table III's original arm without replacement (E100)", 0, 1)
    runs_root = Path(explain.runs)
    count = explain.cfg["fresh_draws_quick" if explain.quick else "fresh_draws"]
    names = [f"analytic_draw_{i:02d}" for i in range(int(count))]
    frames = [_run_rows(runs_root / n, n) for n in names if (runs_root / n / "probes.parquet").is_file()]
    frozen = Path(explain.ins) / "B_test_random"
    if (frozen / "probes.parquet").is_file():
        frames.append(_run_rows(frozen, FROZEN))
    if not frames:
        return
    stored = pd.concat(frames, ignore_index=True)
    explain.stored[STORED] = stored
    explain.res[GROUP].update(summary(stored))
