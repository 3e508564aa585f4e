"""T14's re-split sentence read every way it admits (E118; ex15, issue #36; rules declared in
``docs/decisions.md``, "ex15: T14's re-split sentence read every way it admits").

The paper's sentence ("the calibrated level varies (0.75 +- 0.25) while failure (0.328 +- 0.025) and held-out
cluster coverage (0.857) do not; the margin stays optimistic in 64 % of splits") names no budget. Our study reads
every quantity at the final budget. Per split of the insertion study's re-splits of a pool this module computes,
from stored tables only (no commit re-executed), the level and held-out coverage under four readings:

* ``a1``: the final budget's t_K and coverage at K (the study's reading);
* ``a2``: every budget's t_k and coverage at k against t_k, averaged over the budgets;
* ``a3``: t_K, coverage at every budget against it, averaged;
* ``a4``: t_K, the share of held-out clusters whose scores at every budget at once are at most t_K;

and, where stored, the two calibrations' failure and held-out optimism: the study's (k = K alone,
``insertion/results/resplits.parquet``) and the paper's margin rule over budgets 1..K (E55's calibrations of
the same splits, stored by ex5 and ex9), whose failure at K is the held-out uncalibrated failure plus the full
adjustment's paired difference.

Every key of the ``ex15_readings`` group is :func:`summary` of the stored rows (:data:`STORED`).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pandas as pd

from probecommit.audit.conformal import conformal_quantile, instance_scores

#: The stored per-(pool, split) rows, beside results.json.
STORED = "ex15_readings_rows.parquet"
#: Result group.
GROUP = "ex15_readings"
#: The pool of T14's comparison (tested); the others are published beside it.
FROZEN_POOL = "B_pool_cover"
#: The literal "Split B calibration + test" pools: name -> (runs folder key, calibration run, test run).
UNIONS = (("B_union_cover", "ins", "B_cal_cover", "B_test_cover"),
          ("B_union_cover_paper_schedule", "runs", "B_cal_cover_paper_schedule", "B_test_cover_paper_schedule"),
          ("B_union_random", "ins", "B_cal_random", "B_test_random"))
#: The level/coverage readings.
READINGS = ("a1", "a2", "a3", "a4")


def split_row(table: pd.DataFrame, failed: pd.Series, cal: np.ndarray, test: np.ndarray,
              alpha: float) -> dict[str, float]:
    """One split's levels and held-out coverages under the four readings (``table``: s_rep by instance x budget,
    the last column the final budget K; ``failed``: each instance's mean uncalibrated failure at K)."""
    budgets = list(table.columns)
    last = budgets[-1]
    t = {k: conformal_quantile(table.loc[cal, k].to_numpy(float), alpha) for k in budgets}
    held = table.loc[test]
    at = {k: float(np.mean(held[k].to_numpy(float) <= t[k])) for k in budgets}
    under_last = [float(np.mean(held[k].to_numpy(float) <= t[last])) for k in budgets]
    return {"level_a1": float(t[last]), "coverage_a1": at[last],
            "level_a2": float(np.mean([t[k] for k in budgets])), "coverage_a2": float(np.mean(list(at.values()))),
            "coverage_a3": float(np.mean(under_last)),
            "coverage_a4": float(np.mean(held.max(axis=1).to_numpy(float) <= t[last])),
            "base_failure": float(failed.loc[test].mean())}


def pool_rows(pool: str, episodes: pd.DataFrame, alpha: float, count: int, seed: int) -> pd.DataFrame:
    """The readings on one pool's re-splits (the insertion study's halves), every stored budget."""
    from probecommit.studies.explain.ex5_calibration import split_halves

    probe = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok")]
    table = instance_scores(probe, None).dropna()
    table = table[sorted(table.columns)]
    last = probe[probe["k"] == table.columns[-1]]
    failed = last.groupby("instance_id")["realized"].mean().reindex(table.index)
    rows = [{"pool": pool, "index": n, "budgets": int(table.shape[1]), **split_row(table, failed, cal, test, alpha)}
            for n, (cal, test) in enumerate(split_halves(table.index.to_numpy(), count, seed))]
    return pd.DataFrame(rows)


def margin_columns(rows: pd.DataFrame, study: pd.DataFrame | None, e55: pd.DataFrame | None) -> pd.DataFrame:
    """``rows`` of one pool with the stored calibrations joined by split index: the study's (``c5_failure``,
    ``c5_optimistic``) and the paper's margin rule over budgets (``c15_difference``, ``c15_optimism_k<k>``)."""
    out = rows.copy()
    if study is not None and len(study):
        s = study.set_index("split")
        out["c5_failure"] = out["index"].map(s["failure"]).astype(float)
        out["c5_optimistic"] = out["index"].map(s["margin_optimistic"].astype(float))
    if e55 is not None and len(e55):
        e = e55.set_index("index")
        out["c15_difference"] = out["index"].map(e["difference"]).astype(float)
        for col in sorted(c for c in e.columns if c.startswith("optimism_k")):
            out[f"c15_{col}"] = out["index"].map(e[col]).astype(float)
    return out


def _margin_keys(at: pd.DataFrame) -> dict[str, float]:
    """The two calibrations' failure and optimistic shares over the splits that have them."""
    out: dict[str, float] = {}
    if "c5_failure" in at and at["c5_failure"].notna().any():
        c5 = at.dropna(subset=["c5_failure"])
        out.update({"c5.splits": float(len(c5)), "c5.failure": float(c5["c5_failure"].mean()),
                    "c5.b0": float(c5["c5_optimistic"].mean())})
    opt = [c for c in at.columns if c.startswith("c15_optimism_k")]
    if opt and "c15_difference" in at and at["c15_difference"].notna().any():
        c15 = at.dropna(subset=["c15_difference", *opt])
        e = c15[sorted(opt, key=lambda c: int(c.rsplit("k", 1)[1]))].to_numpy(float)
        out.update({"c15.splits": float(len(c15)),
                    "c15.failure": float((c15["base_failure"] + c15["c15_difference"]).mean()),
                    "c15.b1": float(np.mean(e[:, -1] > 0)), "c15.b2": float(np.mean(e.mean(axis=1) > 0)),
                    "c15.b3": float(np.mean((e > 0).any(axis=1)))})
    return out


def summary(rows: pd.DataFrame) -> dict[str, Any]:
    """Per pool (``<pool>.``): ``splits``, each reading's level mean and SD and coverage mean
    (``a<n>.level``, ``a<n>.level_sd``, ``a<n>.coverage``; a3/a4 share a1's level), and the calibrations'
    ``c5.*``/``c15.*`` failure and optimistic shares where stored."""
    out: dict[str, Any] = {}
    for pool, at in rows.groupby("pool", sort=True):
        out[f"{pool}.splits"] = int(len(at))
        for r in READINGS:
            level = at["level_a2" if r == "a2" else "level_a1"]
            out[f"{pool}.{r}.level"] = float(level.mean())
            out[f"{pool}.{r}.level_sd"] = float(level.std(ddof=1)) if len(at) > 1 else float("nan")
            out[f"{pool}.{r}.coverage"] = float(at[f"coverage_{r}"].mean())
        out.update({f"{pool}.{k}": v for k, v in _margin_keys(at).items()})
    return out


def _study_table(explain: Any) -> pd.DataFrame | None:
    path = explain.root / "insertion" / "results" / "resplits.parquet"
    return pd.read_parquet(path) if path.is_file() else None


def _stored_part(explain: Any, name: str, part: str, pool: str | None = None) -> pd.DataFrame | None:
    """Rows of another step's stored table (ex5's or ex9's, run before this step), or None."""
    rows = explain.stored.get(name)
    if rows is None or "part" not in rows:
        return None
    sub = rows[rows["part"] == part]
    if pool is not None and "pool" in sub:
        sub = sub[sub["pool"] == pool]
    return sub.dropna(axis=1, how="all") if len(sub) else None


def _pools(explain: Any) -> list[tuple[str, pd.DataFrame]]:
    """(name, episodes) of every pool present: the frozen pool, the paper-schedule pools, the Split B unions."""
    from probecommit.runner.replay import load_run
    from probecommit.studies.explain.ex9_calibration import pools

    out = []
    for name, folder in ((FROZEN_POOL, explain.ins / FROZEN_POOL), *((n, explain.runs / n) for n in pools(explain.runs))):
        if (folder / "episodes.parquet").is_file():
            out.append((name, load_run(folder).episodes))
    for name, where, cal, test in UNIONS:
        base = explain.ins if where == "ins" else explain.runs
        if all((base / r / "episodes.parquet").is_file() for r in (cal, test)):
            out.append((name, pd.concat([load_run(base / cal).episodes, load_run(base / test).episodes],
                                        ignore_index=True)))
    return out


def run(explain: Any) -> None:
    """The explain step (after ex5's and ex9's, whose stored calibrations it joins): stored rows and keys."""
    explain.progress("explain: the re-split sentence under every reading (E118)", 0, 1)
    from probecommit.studies.explain import ex5_calibration, ex9_calibration

    p, r = explain.p, explain.p.resplits
    frames = []
    for name, episodes in _pools(explain):
        rows = pool_rows(name, episodes, p.alpha, int(r["count"]), int(r["seed"]))
        if name == FROZEN_POOL:
            e55 = _stored_part(explain, ex5_calibration.STORED, "resplit_cost")
            opt = _stored_part(explain, ex9_calibration.STORED, "resplit_optimism", FROZEN_POOL)
            if e55 is not None and opt is not None:
                e55 = e55[["index", "difference"]].merge(opt.drop(columns=["part", "pool"]), on="index")
            rows = margin_columns(rows, _study_table(explain), e55)
        else:
            rows = margin_columns(rows, None, _stored_part(explain, ex9_calibration.STORED, "cost", name))
        frames.append(rows)
    if frames:
        rows = pd.concat(frames, ignore_index=True)
        explain.stored[STORED] = rows
        explain.res[GROUP].update(summary(rows))


def readings_inside(values: dict[str, float], paper: dict[str, float], tol: dict[str, float],
                    pool: str = FROZEN_POOL) -> list[str]:
    """The readings ``a<n>/<c>.<b>`` whose failure, level, coverage and optimistic share are all within ``tol``
    of ``paper`` (keys ``failure``, ``level``, ``coverage``, ``share``); ``values`` holds the group's keys."""
    out = []
    for a in READINGS:
        for c, b in (("c5", "b0"), ("c15", "b1"), ("c15", "b2"), ("c15", "b3")):
            got = {"failure": values.get(f"{pool}.{c}.failure"), "level": values.get(f"{pool}.{a}.level"),
                   "coverage": values.get(f"{pool}.{a}.coverage"), "share": values.get(f"{pool}.{c}.{b}")}
            if all(v is not None and np.isfinite(v) and abs(v - paper[q]) <= tol[q] for q, v in got.items()):
                out.append(f"{a}/{c}.{b}")
    return out


__all__: Sequence[str] = ("run", "summary", "pool_rows", "split_row", "margin_columns", "readings_inside")
