"""T14's "margin stays optimistic in 64 % of splits" as a count of splits (E132; ex18, issue #36; rule declared in
``docs/decisions.md``, "ex18", "E132").

Given a pool, the re-split study's splits are independent random halves, so the number of splits whose held-out
half finds the tuned margin optimistic is Binomial(splits, p_pool); the paper's 64 % is one such count over its 50
splits. A point tolerance on the difference of two such shares is about one standard deviation of that
difference, so this step compares the counts as counts: Fisher's exact test (two-sided) of ours against the
paper's, the Clopper-Pearson interval of ours, per pool and margin reading. It reads only E118's and E119's stored
per-split rows (no commit re-executed); its own rows (:data:`STORED`) are those rows' columns it reads, so verify
recomputes every key with :func:`summary`.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pandas as pd

#: The stored per-(pool, split) rows, beside results.json.
STORED = "ex18_share_rows.parquet"
#: Result group.
GROUP = "ex18_share"
#: The tested pool (E119's literal Split B pool); the frozen pool is published beside it.
LITERAL_POOL, FROZEN_POOL = "B_union_cover", "B_pool_cover"
#: The columns kept: the level (t_5), the coverage over budgets against it (E118's a3), the study's failure.
KEPT = ("level_a1", "coverage_a3", "c5_failure")
#: Margin readings: name -> how a split's row says "optimistic" (E118's C5/B0 and C15/B1..B3).
READINGS = ("c5", "c15_k5", "c15_mean", "c15_any")


def rows_from(ex15_rows: Sequence[pd.DataFrame | None]) -> pd.DataFrame:
    """Per (pool, split): the kept columns and one 0/1 column per margin reading (NaN where not stored), from
    E118's and E119's stored rows (pools other than the two named are left out)."""
    frames = []
    for rows in ex15_rows:
        if rows is None or not len(rows):
            continue
        at = rows[rows["pool"].isin((LITERAL_POOL, FROZEN_POOL))]
        if not len(at) or "c5_optimistic" not in at or at["c5_optimistic"].isna().all():
            continue
        opt = sorted((c for c in at.columns if c.startswith("c15_optimism_k")), key=lambda c: int(c.rsplit("k", 1)[1]))
        out = at[["pool", "index", *KEPT]].copy()
        out["c5"] = at["c5_optimistic"].astype(float)
        e = at[opt].to_numpy(float) if opt else np.full((len(at), 1), np.nan)
        known = ~np.isnan(e).any(axis=1)
        for name, hit in (("c15_k5", e[:, -1] > 0), ("c15_mean", e.mean(axis=1) > 0), ("c15_any", (e > 0).any(axis=1))):
            out[name] = np.where(known, hit.astype(float), np.nan)
        frames.append(out)
    if not frames:
        return pd.DataFrame(columns=["pool", "index", *KEPT, *READINGS])
    return pd.concat(frames, ignore_index=True).drop_duplicates(["pool", "index"]).reset_index(drop=True)


def paper_count(splits: int) -> int:
    """The paper's count of optimistic splits: its percent of ``splits`` (64 % of 50 = 32)."""
    from probecommit.studies.paper_values import value

    return int(round(float(value("T14-resplits.margin_optimistic_percent")) * splits / 100.0))


def count_keys(hits: int, splits: int, paper: int) -> dict[str, float]:
    """One reading's count, share, 95 % Clopper-Pearson interval and Fisher's exact two-sided p-value against
    ``paper`` of ``splits`` (the 2 x 2 table optimistic / not, ours / paper)."""
    from scipy.stats import binomtest, fisher_exact

    ci = binomtest(hits, splits).proportion_ci(0.95, method="exact")
    p = fisher_exact([[hits, splits - hits], [paper, splits - paper]], alternative="two-sided").pvalue
    return {"optimistic": float(hits), "share": hits / splits, "cp_lo": float(ci.low), "cp_hi": float(ci.high),
            "fisher_p": float(p), "sd": float(np.sqrt(hits / splits * (1 - hits / splits) / splits))}


def summary(rows: pd.DataFrame) -> dict[str, Any]:
    """Per pool (``<pool>.``): ``splits``, the kept columns' means (``level``, ``coverage_a3``, ``failure``) and per
    margin reading ``<reading>.{optimistic, share, cp_lo, cp_hi, fisher_p, sd}``; ``paper.optimistic``, the
    paper's count over the literal pool's splits."""
    out: dict[str, Any] = {}
    for pool, at in rows.groupby("pool", sort=True):
        n = int(len(at))
        out[f"{pool}.splits"] = n
        out.update({f"{pool}.level": float(at["level_a1"].mean()), f"{pool}.coverage_a3": float(at["coverage_a3"].mean()),
                    f"{pool}.failure": float(at["c5_failure"].mean())})
        paper = paper_count(n)
        if pool == LITERAL_POOL:
            out["paper.optimistic"] = float(paper)
        for reading in READINGS:
            col = at[reading].dropna() if reading in at else pd.Series(dtype=float)
            if len(col) == n:
                out.update({f"{pool}.{reading}.{k}": v for k, v in count_keys(int(col.sum()), n, paper).items()})
    return out


def run(explain: Any) -> None:
    """The explain step (last in ``steps``: E119's rows come from a process of its own, so it waits for the steps
    set aside): stored rows and keys of the ``ex18_share`` group (milliseconds)."""
    from probecommit.studies.explain import ex15_readings, ex15_union

    explain.progress("explain: the margin's optimistic share as a count of splits (E132)", 0, 1)
    explain.wait_aside()  # E118's (aside) and E119's (background) rows are merged into ``stored``
    rows = rows_from([explain.stored.get(ex15_union.STORED), explain.stored.get(ex15_readings.STORED)])
    if len(rows):
        explain.stored[STORED] = rows
        explain.res[GROUP].update(summary(rows))


__all__: Sequence[str] = ("run", "summary", "rows_from", "count_keys", "paper_count")
