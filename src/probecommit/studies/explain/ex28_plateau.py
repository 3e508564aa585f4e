"""T14's held-out coverage and level by their mechanism: the W = 1 plateau as one tie (E186; ex28, issue #36; rule
declared in ``docs/decisions.md``, "ex28").

Why: over random halves of one pool the mean held-out coverage of ``s_rep <= t`` is exactly q / (M + 1) unless
scores tie at t (E80). The only tie our score can put where a threshold lands is the plateau the paper names: a
truth inside the hull but spanned only by zero-weight particles scores W = 1, one value for every such cluster,
which the float round-off of the cumulative sum splits into 1 and 1 - ulp. This step removes the round-off
(:data:`PLATEAU_TOL`) and counts, per split of the insertion study's re-splits of each stored pool, the level, the
held-out coverage with ties counted covered and without, and whether the level sits on the plateau. It reads stored
episode tables only (no commit re-executed); every key of the group is :func:`summary` of its rows (:data:`STORED`).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pandas as pd

from probecommit.audit.conformal import conformal_quantile, instance_scores

#: The stored per-(pool, split) rows, beside results.json.
STORED = "ex28_plateau_rows.parquet"
#: Result group.
GROUP = "ex28_plateau"
#: A score this close to 1 is on the plateau (the cumulative sum's round-off is a few ulps).
PLATEAU_TOL = 1e-9
#: The per-pool facts repeated on each of its rows (so that :func:`summary` needs the rows alone).
POOL_COLUMNS = ("plateau_share", "beyond_share", "tie_max")


def snapped(scores: np.ndarray) -> np.ndarray:
    """Worst-repeat scores with the plateau's round-off removed: within :data:`PLATEAU_TOL` of 1 is exactly 1."""
    s = np.asarray(scores, float)
    return np.where(np.abs(s - 1.0) <= PLATEAU_TOL, 1.0, s)


def pool_facts(s: np.ndarray) -> dict[str, float]:
    """A pool's snapped scores: the plateau's share, the share beyond the hull, and the largest score below the
    plateau that two clusters share (the 1/N grain's ties; 0 when none)."""
    below = s[s < 1.0]
    values, counts = np.unique(below, return_counts=True)
    tied = values[counts > 1]
    return {"plateau_share": float(np.mean(s == 1.0)), "beyond_share": float(np.mean(s > 1.0)),
            "tie_max": float(tied.max()) if len(tied) else 0.0}


def split_row(s: pd.Series, cal: np.ndarray, test: np.ndarray, alpha: float) -> dict[str, float]:
    """One split: the level t_K of the calibration half's snapped scores, the held-out coverage with ties counted
    covered (``s <= t``) and strictly (``s < t``), the held-out share tied at t, and whether t is on the plateau."""
    t = conformal_quantile(s.loc[cal].to_numpy(float), alpha)
    held = s.loc[test].to_numpy(float)
    return {"level": float(t), "coverage_le": float(np.mean(held <= t)), "coverage_lt": float(np.mean(held < t)),
            "tied": float(np.mean(held == t)), "on_plateau": float(t == 1.0)}


def pool_rows(pool: str, episodes: pd.DataFrame, alpha: float, count: int, seed: int) -> pd.DataFrame:
    """The rows of one pool's re-splits (the insertion study's halves) at its final stored budget."""
    from probecommit.studies.explain.ex5_calibration import split_halves

    probe = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok")]
    table = instance_scores(probe, None).dropna()
    last = int(max(table.columns))
    s = pd.Series(snapped(table[last].to_numpy(float)), index=table.index)
    facts = pool_facts(s.to_numpy())
    rows = [{"pool": pool, "index": n, "budget": last, **facts, **split_row(s, cal, test, alpha)}
            for n, (cal, test) in enumerate(split_halves(table.index.to_numpy(), count, seed))]
    return pd.DataFrame(rows)


def pool_keys(at: pd.DataFrame) -> dict[str, Any]:
    """One pool's keys: ``splits``, ``budget``, its facts (:data:`POOL_COLUMNS`), the level's mean and SD (``level``,
    ``level_sd``), the coverages (``coverage_le``, ``coverage_lt``, their difference ``tie_gain``), the share of
    splits with the level on the plateau (``on_plateau``) and the mean held-out share tied (``tied``)."""
    out: dict[str, Any] = {"splits": int(len(at)), "budget": int(at["budget"].iloc[0])}
    out.update({c: float(at[c].iloc[0]) for c in POOL_COLUMNS})
    out["level"] = float(at["level"].mean())
    out["level_sd"] = float(at["level"].std(ddof=1)) if len(at) > 1 else float("nan")
    out.update({c: float(at[c].mean()) for c in ("coverage_le", "coverage_lt", "on_plateau", "tied")})
    out["tie_gain"] = out["coverage_le"] - out["coverage_lt"]
    return out


def summary(rows: pd.DataFrame) -> dict[str, Any]:
    """Per pool (``<pool>.``, :func:`pool_keys`); over the pools at the cover budget (``cover.``): their count
    (``pools``), the range of the level and of both coverages (``<q>_min``, ``<q>_max``), the largest plateau share
    and tie gain; ``pools_holding``, the number of them where E186's declared rule (:func:`holds`) passes, and
    ``holds`` (1 when any does)."""
    from probecommit.studies.paper_values import value

    per = {pool: pool_keys(at) for pool, at in rows.groupby("pool", sort=True)}
    out: dict[str, Any] = {f"{pool}.{k}": v for pool, keys in per.items() for k, v in keys.items()}
    cover = {pool: keys for pool, keys in per.items() if keys["budget"] == COVER_BUDGET}
    out["cover.pools"] = float(len(cover))
    for q in ("level", "coverage_le", "coverage_lt"):
        got = [keys[q] for keys in cover.values()]
        out[f"cover.{q}_min"], out[f"cover.{q}_max"] = (min(got), max(got)) if got else (float("nan"),) * 2
    for q in ("plateau_share", "tie_gain"):
        out[f"cover.{q}_max"] = max((keys[q] for keys in cover.values()), default=float("nan"))
    paper = {q: float(value(f"T14-resplits.{q}")) for q in ("level_mean", "level_sd", "heldout_cluster_coverage")}
    passing = [pool for pool in cover if holds(out, pool, paper)]
    out["pools_holding"] = float(len(passing))
    out["holds"] = float(bool(passing))
    return out


#: The cover schedule's final budget: the pools the rule is judged on.
COVER_BUDGET = 5
#: The rule's tolerances (the claim's own): level mean, the level SD's floor below the paper's, coverage.
LEVEL_TOL, SD_TOL, COVERAGE_TOL = 0.1, 0.1, 0.05


def holds(values: dict[str, Any], pool: str, paper: dict[str, float]) -> bool:
    """E186's rule on one pool: level mean within :data:`LEVEL_TOL` of the paper's, level SD at least the paper's
    less :data:`SD_TOL` ("varies"), tie-counted coverage within :data:`COVERAGE_TOL` of the paper's."""
    return bool(abs(values[f"{pool}.level"] - paper["level_mean"]) <= LEVEL_TOL
                and values[f"{pool}.level_sd"] >= paper["level_sd"] - SD_TOL
                and abs(values[f"{pool}.coverage_le"] - paper["heldout_cluster_coverage"]) <= COVERAGE_TOL)


def run(explain: Any) -> None:
    """The explain step (set aside with ex15's, whose pools it reads): stored rows and keys (about a second)."""
    from probecommit.studies.explain.ex15_readings import _pools

    explain.progress("explain: the W = 1 plateau as one tie (E186)", 0, 1)
    p, r = explain.p, explain.p.resplits
    frames = [pool_rows(name, episodes, p.alpha, int(r["count"]), int(r["seed"])) for name, episodes in _pools(explain)]
    if frames:
        rows = pd.concat(frames, ignore_index=True)
        explain.stored[STORED] = rows
        explain.res[GROUP].update(summary(rows))


__all__: Sequence[str] = ("run", "summary", "pool_rows", "split_row", "pool_facts", "pool_keys", "snapped", "holds")
