"""Table III's three optimism cells no experiment reached, at the design's exposure to the misread band (E162,
E163; docs/decisions.md, "ex23").

Why: ex20 (E144) found Table III's optimism lives in trajectories whose taps hit the misread band, and our test
draw hits it less often than the paper's design does. Two cells stayed uncovered after it:

* E162, original optimism at k = 2: E17's twelve fresh draws of the test generator, each post-stratified to the
  design's exact band probability exactly as E144 post-stratifies the frozen draw (ex20's rows and
  ``_standardized``), so the range over draws is the range of draws at the design's exposure.
* E163, calibrated optimism at k = 2 and 3: the calibrated arm reads band exposure twice, in the calibration
  run (its scores set t_k, its optimism sets the margin) and in the test run. Both are standardized: a weighted
  conformal threshold and a weighted margin search on the calibration run (instance and trajectory weights that
  bring each band stratum to the design's exact share), the test run's calibrated commits re-executed at those
  and post-stratified as E144.

Every key is :func:`keys` of the stored rows (:data:`STORED`), so ``verify`` recomputes them; the rows of the
re-executed commits carry the threshold and margin they were committed at.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from probecommit.studies.explain import ex20_band

#: The stored rows (parts ``draw``, ``score``, ``margin``, ``test``) every key is summarized from.
STORED = "ex23_band_rows.parquet"
#: Table III's budgets.
BUDGETS = ex20_band.BUDGETS


def stratum_weights(hit: np.ndarray, p: float) -> np.ndarray:
    """Weights that bring a sample's band stratum to probability ``p``: ``p / s`` for a hit, ``(1 - p) / (1 - s)``
    otherwise (``s`` the sample's share of hits); ones where a stratum is empty (nothing to reweight)."""
    hit = np.asarray(hit, dtype=bool)
    s = float(hit.mean()) if hit.size else 0.0
    if s <= 0.0 or s >= 1.0:
        return np.ones(hit.size)
    return np.where(hit, p / s, (1.0 - p) / (1.0 - s))


def weighted_threshold(scores: np.ndarray, weights: np.ndarray, rank: int) -> float:
    """The smallest score whose weighted empirical CDF reaches ``rank / M`` (``M`` scores): with equal weights,
    exactly the ``rank``-th smallest score (``audit.conformal.conformal_quantile``); +inf when ``rank > M``."""
    s = np.asarray(scores, dtype=float)
    w = np.asarray(weights, dtype=float)
    if rank > s.size:
        return float("inf")
    order = np.argsort(s, kind="stable")
    cdf = np.cumsum(w[order]) / w.sum()
    level = rank / s.size
    i = int(np.searchsorted(cdf, level - 1e-12, side="left"))
    return float(s[order][min(i, s.size - 1)])


def weighted_margin(rows: pd.DataFrame, probabilities: Mapping[int, tuple[float, float]],
                    grid: Sequence[float]) -> tuple[float, bool]:
    """The largest gamma of ``grid`` (scanned from the largest) whose calibration rows, each weighted to the
    design's band probability at its budget, have weighted mean predicted failure at least the realized one;
    the smallest gamma (and False) when none does. ``rows``: the margin part (``gamma, k, hit, predicted,
    realized``), ok rows only."""
    for gamma in sorted((float(g) for g in grid), reverse=True):
        at = rows[np.isclose(rows["gamma"].to_numpy(float), gamma)]
        if not len(at):
            raise KeyError(f"the weighted margin search needs gamma = {gamma}, whose rows are not stored")
        pred = real = 0.0
        for k, part in at.groupby("k", sort=True):
            w = stratum_weights(part["hit"].to_numpy(bool), probabilities[int(k)][0])
            pred += float(w @ part["predicted"].to_numpy(float))
            real += float(w @ part["realized"].to_numpy(float))
        if pred >= real:
            return gamma, True
    return float(min(grid)), False


def thresholds(scores: pd.DataFrame, probabilities: Mapping[int, tuple[float, float]], rank: int) -> dict[str, dict]:
    """Per budget, the unweighted (``plain``) and band-weighted (``weighted``) thresholds of the calibration run's
    worst-repeat scores (the score part: ``instance_id, k, score, hit`` with ``hit`` the instance's exposure)."""
    plain, weighted, share = {}, {}, {}
    for k, at in scores.groupby("k", sort=True):
        s, h = at["score"].to_numpy(float), at["hit"].to_numpy(bool)
        plain[int(k)] = weighted_threshold(s, np.ones(s.size), rank)
        weighted[int(k)] = weighted_threshold(s, stratum_weights(h, probabilities[int(k)][1]), rank)
        share[int(k)] = float(h.mean())
    return {"plain": plain, "weighted": weighted, "share": share}


def _probabilities(rows: pd.DataFrame) -> dict[int, tuple[float, float]]:
    """ex20's exact design probabilities from the design constants the rows carry."""
    from probecommit.tasks.insertion.model import InsertionModel

    positions = [float(u) for u in np.asarray(InsertionModel.probe_grid, dtype=float).reshape(-1)]
    first = rows.iloc[0]
    return ex20_band.design_probabilities(positions, {n: float(first[n]) for n in ex20_band.DESIGN}, BUDGETS)


def draw_keys(rows: pd.DataFrame, probabilities: Mapping[int, tuple[float, float]]) -> dict[str, Any]:
    """E162: over the fresh draws, per budget, the raw and post-stratified original optimism and the band share
    (min, max, mean)."""
    out: dict[str, Any] = {"count": int(rows["draw"].nunique())}
    for k in sorted(int(b) for b in rows["k"].unique()):
        raw, std, share = [], [], []
        for _, d in rows[rows["k"] == k].groupby("draw", sort=True):
            sums, cov, hit, _ = ex20_band._strata_sums(d)
            share.append(float(d["hit"].mean()))
            raw.append(float((d["realized"] - d["predicted"]).mean()))
            std.append(ex20_band._standardized(sums, cov, hit, *probabilities[k], np.ones(len(hit)))[0])
        for name, v in (("optimism", raw), ("optimism_std", std), ("share", share)):
            v = np.asarray(v, dtype=float)
            out.update({f"{name}.min.k{k}": float(np.nanmin(v)), f"{name}.max.k{k}": float(np.nanmax(v)),
                        f"{name}.mean.k{k}": float(np.nanmean(v))})
    return out


def test_keys(test: pd.DataFrame, probabilities: Mapping[int, tuple[float, float]], resamples: int,
              seed: int) -> dict[str, Any]:
    """E163: per budget, the test run's calibrated optimism under the weighted calibration, raw and
    post-stratified on band hits (E144's estimator and Table III's cluster bootstrap over test instances)."""
    out: dict[str, Any] = {}
    rows = test.assign(covered=True)  # ex20's strata sums need a covered flag; coverage is not summarized here
    ids = np.sort(rows["instance_id"].unique())
    rng = np.random.default_rng(seed)
    draws = np.stack([np.bincount(rng.integers(len(ids), size=len(ids)), minlength=len(ids))
                      for _ in range(resamples)])
    for k, at in rows.groupby("k", sort=True):
        p, big_p = probabilities[int(k)]
        sums, cov, hit, _ = ex20_band._strata_sums(at)
        e, _ = ex20_band._standardized(sums, cov, hit, p, big_p, np.ones(len(hit)))
        boot = np.array([ex20_band._standardized(sums, cov, hit, p, big_p, w.astype(float))[0] for w in draws])
        lo, hi = ex20_band._interval(boot)
        h = at["hit"].to_numpy(bool)
        s = f".k{int(k)}"
        out.update({f"optimism{s}": float((at["realized"] - at["predicted"]).mean()), f"optimism_std{s}": e,
                    f"optimism_std_lo{s}": lo, f"optimism_std_hi{s}": hi, f"share{s}": float(h.mean()),
                    f"p_design{s}": p})
    return out


def keys(rows: pd.DataFrame, boot: Mapping[str, int]) -> dict[str, Any]:
    """Every key of the ``ex23_band`` group from its stored rows: ``draws.*`` (E162) and ``calibrated.*`` (E163)."""
    probabilities = _probabilities(rows)
    out: dict[str, Any] = {}
    draws = rows[rows["part"] == "draw"]
    if len(draws):
        out.update({f"draws.{n}": v for n, v in draw_keys(draws, probabilities).items()})
    scores = rows[rows["part"] == "score"]
    if len(scores):
        out.update({f"calibrated.{n}": v for n, v in calibrated_keys(rows, probabilities, boot).items()})
    return out


def calibrated_keys(rows: pd.DataFrame, probabilities: Mapping[int, tuple[float, float]],
                    boot: Mapping[str, int]) -> dict[str, Any]:
    """E163's keys: the weighted thresholds against the plain ones, the weighted margin, the calibration run's band
    shares, and the test run's calibrated optimism (raw and post-stratified) under them. Checks that the stored
    margin and test rows were committed at the thresholds the stored scores give."""
    scores, margin, test = (rows[rows["part"] == part] for part in ("score", "margin", "test"))
    rank = int(scores["rank"].iloc[0])
    t = thresholds(scores, probabilities, rank)
    grid = sorted(margin["gamma"].unique(), reverse=True)
    gamma, satisfied = weighted_margin(margin, probabilities, grid)
    for part, name in ((margin, "margin"), (test, "test")):
        for k, at in part.groupby("k"):
            if not np.allclose(at["threshold"].to_numpy(float), t["weighted"][int(k)]):
                raise ValueError(f"ex23: the stored {name} rows at k = {k} were not committed at the weighted t_k")
    if not np.allclose(test["gamma"].to_numpy(float), gamma):
        raise ValueError("ex23: the stored test rows were not committed at the weighted margin")
    out: dict[str, Any] = {"gamma": gamma, "gamma_satisfied": int(satisfied), "rank": rank,
                           "calibration_instances": int(scores["instance_id"].nunique())}
    cal_share = margin[np.isclose(margin["gamma"].to_numpy(float), grid[0])]
    for k in sorted(t["plain"]):
        s = f".k{k}"
        out.update({f"t_plain{s}": t["plain"][k], f"t_weighted{s}": t["weighted"][k],
                    f"cal_share_instance{s}": t["share"][k], f"p_design_instance{s}": probabilities[k][1],
                    f"cal_share{s}": float(cal_share.loc[cal_share["k"] == k, "hit"].mean())})
    out.update(test_keys(test, probabilities, int(boot["resamples"]), int(boot["seed"])))
    return out
