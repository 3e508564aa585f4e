"""T14's held-out coverage under the budget-simultaneous level (E101; ex12, issue #36; rule declared in
``docs/decisions.md``, "ex12: T14's held-out coverage under the budget-simultaneous level").

The paper's re-split sentence names "the calibrated level" and its "held-out cluster coverage"; our re-split
study reads the level as the fixed-budget t_5, whose held-out coverage at k = 5 averages q / (M + 1) over
random splits whatever the simulator (E80). The paper has a second level, the budget-simultaneous t over the
cover budgets (S_i = max_k s_rep_{i,k}); a k = 5 coverage against it is at least as high. Per split of the
insertion study's 50 re-splits of a pool: that level on the calibration half and the held-out coverage at
k = 5 against it, from the stored episode tables (no commit re-executed).

Every key of the ``ex12_simultaneous`` group is :func:`summary` of the stored rows (:data:`STORED`).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pandas as pd

from probecommit.audit.conformal import conformal_quantile, instance_scores

#: The stored per-(pool, split) rows, beside results.json.
STORED = "ex12_simultaneous_rows.parquet"
#: Result group.
GROUP = "ex12_simultaneous"
#: The pool of T14's comparison (tested); the paper-schedule pools are published beside it.
FROZEN_POOL = "B_pool_cover"


def split_row(table: pd.DataFrame, cal: np.ndarray, test: np.ndarray, alpha: float, k: int) -> dict[str, float]:
    """One split: the simultaneous level of ``cal`` over ``table``'s budgets (columns), its fixed-budget level
    at ``k``, and the held-out coverage at ``k`` of ``test`` against each (the conformal event ``<=``)."""
    simultaneous = conformal_quantile(table.loc[cal].max(axis=1).to_numpy(float), alpha)
    fixed = conformal_quantile(table.loc[cal, k].to_numpy(float), alpha)
    held = table.loc[test, k].to_numpy(float)
    return {"level": float(simultaneous), "coverage": float(np.mean(held <= simultaneous)),
            "level_fixed": float(fixed), "coverage_fixed": float(np.mean(held <= fixed))}


def pool_rows(pool: str, episodes: pd.DataFrame, alpha: float, count: int, seed: int,
              budgets: Sequence[int]) -> pd.DataFrame:
    """E101's rows of one pool: the re-split study's splits, each calibrated over ``budgets`` (the last is k)."""
    from probecommit.studies.explain.ex5_calibration import split_halves

    table = instance_scores(episodes[episodes["method"] == "probe_robust"], None)[list(budgets)].dropna()
    rows = [{"pool": pool, "index": n, **split_row(table, cal, test, alpha, int(budgets[-1]))}
            for n, (cal, test) in enumerate(split_halves(table.index.to_numpy(), count, seed))]
    return pd.DataFrame(rows)


def summary(rows: pd.DataFrame) -> dict[str, Any]:
    """Per pool (``<pool>.``): ``splits``, the mean and SD over splits of ``level`` and ``coverage`` and the
    means of the fixed-budget ``level_fixed`` and ``coverage_fixed``."""
    out: dict[str, Any] = {}
    for pool, at in rows.groupby("pool", sort=True):
        out[f"{pool}.splits"] = int(len(at))
        for col in ("level", "coverage"):
            out[f"{pool}.{col}.mean"] = float(at[col].mean())
            out[f"{pool}.{col}.sd"] = float(at[col].std(ddof=1)) if len(at) > 1 else float("nan")
        for col in ("level_fixed", "coverage_fixed"):
            out[f"{pool}.{col}.mean"] = float(at[col].mean())
    return out


def run(explain: Any) -> None:
    """The explain step: the frozen cover pool and E80's paper-schedule pools, stored rows and keys."""
    explain.progress("explain: the re-splits under the budget-simultaneous level (E101)", 0, 1)
    from probecommit.runner.replay import load_run
    from probecommit.studies.explain.ex9_calibration import pools

    p = explain.p
    r, k = p.resplits, int(p.budgets["cover"])
    budgets = list(range(1, k + 1))
    frames = []
    for name, folder in ((FROZEN_POOL, explain.ins / FROZEN_POOL), *((n, explain.runs / n) for n in pools(explain.runs))):
        if (folder / "episodes.parquet").is_file():
            frames.append(pool_rows(name, load_run(folder).episodes, p.alpha, int(r["count"]), int(r["seed"]), budgets))
    if frames:
        rows = pd.concat(frames, ignore_index=True)
        explain.stored[STORED] = rows
        explain.res[GROUP].update(summary(rows))
