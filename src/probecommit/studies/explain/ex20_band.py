"""Table III's original arm at the design's exposure to the misread band (E144..E146; docs/decisions.md, "ex20").

Why: the original model's error lives in one band. A tap with ``hg(c) - r <= |u - x_hole| < hg(c) + delta`` reads
the pocket in the simulator and the plate top in the model; a trajectory none of whose taps hit that band is read
by an exact hard-constraint model (sigma = 0.5 mm against a 15 mm step), one that hit it is pulled up to 2.1 mm
toward the tap, which lowers coverage and raises optimism. Whether a trajectory hits the band is fixed by the
design alone (its truth and its probe positions), and the probability that it does is exact under the paper's
design (x ~ U[-10, 10], c ~ U[0.7, 1.3], every tap uniform over the nine positions). A test draw that hits the
band less often than the design is milder exactly where the original model is optimistic: this step
post-stratifies the draw's optimism (per trajectory) and cluster coverage (per instance) on band exposure with
the design's exact probabilities, under Table III's cluster bootstrap. No engine run and no belief recomputed:
the stored episodes and taps of the insertion study's random test run, and of the explain target's fresh draws.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

#: The stored rows (one per draw, trajectory and budget) every key is summarized from.
STORED = "ex20_band_rows.parquet"
#: Table III's budgets.
BUDGETS = (1, 2, 3, 5, 8)
#: The frozen draw's label in the rows (the insertion study's run of that name).
FROZEN = "B_test_random"
#: Midpoint-rule cells over the prior box (x, c) for the design probabilities (declared in decisions.md).
CELLS = (4000, 600)
#: The design constants each row carries (so verify recomputes the exact probabilities from the rows alone).
DESIGN = ("x_low", "x_high", "c_low", "c_high", "r", "delta", "repeats")
#: Table III's interval level.
LEVEL = 0.95


def in_band(u: np.ndarray, x: np.ndarray, c: np.ndarray, r: float, delta: float) -> np.ndarray:
    """Whether a tap at ``u`` lies in the misread band of truth ``(x, c)``: the simulator reads the pocket
    (``|u - x| < hg(c) + delta``) and the original model the top (``|u - x| >= hg(c) - r``): ex14's band test
    (``ex14_escape.in_band``) at the truth's half-gap."""
    from probecommit.studies.explain.ex14_escape import in_band as band_test
    from probecommit.tasks.insertion.model import half_gap

    return band_test(u, x, half_gap(np.asarray(c, dtype=float)), -r, delta)


def design_probabilities(positions: Sequence[float], design: Mapping[str, float], budgets: Sequence[int] = BUDGETS,
                         cells: tuple[int, int] = CELLS, fixed: float | None = None) -> dict[int, tuple[float, float]]:
    """``{k: (p_k, P_k)}``: the probability that a trajectory's first k taps hit the band (``p_k``) and that
    any of an instance's repeats does (``P_k``), under a uniform prior box and taps uniform and independent over
    ``positions`` (midpoint rule on ``cells``). ``fixed``: the first of the k taps is at that position in every
    trajectory and the other k - 1 are random (ex34's design; a fixed tap misses the band in every repeat alike)."""
    nx, nc = cells
    x = design["x_low"] + (np.arange(nx) + 0.5) * (design["x_high"] - design["x_low"]) / nx
    c = design["c_low"] + (np.arange(nc) + 0.5) * (design["c_high"] - design["c_low"]) / nc
    xx, cc = np.meshgrid(x, c, indexing="ij")
    b = np.zeros_like(xx)
    for u in positions:
        b += in_band(u, xx, cc, design["r"], design["delta"])
    miss = 1.0 - b / len(positions)  # a tap misses the band
    reps = int(design["repeats"])
    if fixed is None:
        return {int(k): (float(np.mean(1.0 - miss ** k)), float(np.mean(1.0 - miss ** (reps * k)))) for k in budgets}
    first = 1.0 - in_band(fixed, xx, cc, design["r"], design["delta"])  # the fixed tap misses the band
    return {int(k): (float(np.mean(1.0 - first * miss ** (k - 1))), float(np.mean(1.0 - first * miss ** (reps * (k - 1)))))
            for k in budgets}


def band_rows(episodes: pd.DataFrame, probes: pd.DataFrame, instances: pd.DataFrame, draw: str,
              design: Mapping[str, float], budgets: Sequence[int] = BUDGETS) -> pd.DataFrame:
    """One row per trajectory and budget of the original arm: realized, predicted, covered, escaped and ``hit``
    (any of the first k taps in the band of the trajectory's truth); the design constants ride along."""
    ep = episodes[(episodes["method"] == "probe_robust") & (episodes["variant"] == "deployed")
                  & episodes["k"].isin(list(budgets))]
    truth = instances.set_index("instance_id")[["true_x_hole", "true_c"]]
    taps = probes.join(truth, on="instance_id")
    taps = taps.assign(band=in_band(taps["u"].to_numpy(float), taps["true_x_hole"].to_numpy(float),
                                    taps["true_c"].to_numpy(float), design["r"], design["delta"]))
    taps = taps.sort_values(["instance_id", "repeat", "j"])
    taps["hit_by"] = taps.groupby(["instance_id", "repeat"])["band"].cummax()
    hit = taps.set_index(["instance_id", "repeat", "j"])["hit_by"]
    keys = pd.MultiIndex.from_arrays([ep["instance_id"], ep["repeat"], ep["k"]])
    out = pd.DataFrame({"draw": draw, "instance_id": ep["instance_id"].astype(str).to_numpy(),
                        "repeat": ep["repeat"].to_numpy(np.int64), "k": ep["k"].to_numpy(np.int64),
                        "realized": ep["realized"].to_numpy(float), "predicted": ep["predicted"].to_numpy(float),
                        "covered": ep["covered"].to_numpy(bool), "escaped": ep["escaped"].to_numpy(bool),
                        "hit": hit.reindex(keys).to_numpy(bool)})
    for name in DESIGN:
        out[name] = float(design[name])
    return out


def _strata_sums(rows: pd.DataFrame) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per instance (in a fixed order): trajectories and summed optimism with and without a band hit, whether
    the instance is covered in every repeat, and whether any repeat hit the band."""
    opt = rows["realized"] - rows["predicted"]
    g = rows.assign(opt=opt, n1=rows["hit"].astype(float), s1=np.where(rows["hit"], opt, 0.0),
                    n0=(~rows["hit"]).astype(float), s0=np.where(rows["hit"], 0.0, opt))
    per = g.groupby("instance_id", sort=True).agg(n1=("n1", "sum"), s1=("s1", "sum"), n0=("n0", "sum"),
                                                 s0=("s0", "sum"), cov=("covered", "all"), hit=("hit", "any"))
    return (per[["n1", "s1", "n0", "s0"]].to_numpy(float), per["cov"].to_numpy(float), per["hit"].to_numpy(float),
            per.index.to_numpy())


def _standardized(sums: np.ndarray, cov: np.ndarray, hit: np.ndarray, p: float, big_p: float,
                  weights: np.ndarray) -> tuple[float, float]:
    """The post-stratified optimism and cluster coverage for instance weights ``weights`` (a bootstrap's counts,
    or ones); NaN where a stratum is empty."""
    n1, s1, n0, s0 = (weights @ sums[:, i] for i in range(4))
    opt = p * s1 / n1 + (1 - p) * s0 / n0 if n1 > 0 and n0 > 0 else float("nan")
    w1, w0 = weights @ hit, weights @ (1 - hit)
    cc = (big_p * (weights @ (cov * hit)) / w1 + (1 - big_p) * (weights @ (cov * (1 - hit))) / w0
          if w1 > 0 and w0 > 0 else float("nan"))
    return float(opt), float(cc)


def _interval(values: np.ndarray) -> tuple[float, float]:
    """The percentile interval of a bootstrap's values (NaN resamples, an empty stratum, left out)."""
    if np.isnan(values).all():
        return float("nan"), float("nan")
    tail = (1 - LEVEL) / 2 * 100
    lo, hi = np.nanpercentile(values, [tail, 100 - tail])
    return float(lo), float(hi)


def frozen_keys(rows: pd.DataFrame, probabilities: Mapping[int, tuple[float, float]], resamples: int,
                seed: int) -> dict[str, Any]:
    """Per budget of the frozen draw: band shares (trajectories, instances) against the design's, the strata's
    optimism (all and covered), the raw and post-stratified optimism and cluster coverage with their cluster
    bootstrap intervals (the same instance resamples at every budget)."""
    out: dict[str, Any] = {}
    ids = np.sort(rows["instance_id"].unique())
    rng = np.random.default_rng(seed)
    draws = np.stack([np.bincount(rng.integers(len(ids), size=len(ids)), minlength=len(ids)) for _ in range(resamples)])
    opt_all = []
    for k, at in rows.groupby("k", sort=True):
        p, big_p = probabilities[int(k)]
        sums, cov, hit, _ = _strata_sums(at)
        opt = at["realized"] - at["predicted"]
        h = at["hit"].to_numpy(bool)
        cv = at["covered"].to_numpy(bool)
        e, c = _standardized(sums, cov, hit, p, big_p, np.ones(len(hit)))
        boot = np.array([_standardized(sums, cov, hit, p, big_p, w.astype(float)) for w in draws])
        s = f".k{int(k)}"
        out.update({f"p_design{s}": p, f"p_design_instance{s}": big_p, f"share{s}": float(h.mean()),
                    f"share_instance{s}": float(hit.mean()), f"n_hit{s}": int(h.sum()),
                    f"gap_hit{s}": float(opt[h].mean()) if h.any() else float("nan"),
                    f"gap_free{s}": float(opt[~h].mean()) if (~h).any() else float("nan"),
                    f"covered_gap_hit{s}": float(opt[h & cv].mean()) if (h & cv).any() else float("nan"),
                    f"covered_gap_free{s}": float(opt[~h & cv].mean()) if (~h & cv).any() else float("nan"),
                    f"optimism{s}": float(opt.mean()), f"cluster_coverage{s}": float(cov.mean()),
                    f"optimism_std{s}": e, f"cluster_coverage_std{s}": c})
        out[f"optimism_std_lo{s}"], out[f"optimism_std_hi{s}"] = _interval(boot[:, 0])
        out[f"cluster_coverage_std_lo{s}"], out[f"cluster_coverage_std_hi{s}"] = _interval(boot[:, 1])
        opt_all.append(e)
    out["mean_abs_optimism_std"] = float(np.mean(np.abs(opt_all)))
    out["mean_abs_optimism"] = float(np.mean([abs(out[f"optimism.k{k}"]) for k in sorted(rows["k"].unique())]))
    return out


def draw_keys(rows: pd.DataFrame, probabilities: Mapping[int, tuple[float, float]], k: int = 8) -> dict[str, Any]:
    """Beside the rule, over the fresh draws at budget ``k``: band share, raw and post-stratified optimism
    (min, max and SD over draws)."""
    share, raw, std = [], [], []
    for _, d in rows[rows["k"] == k].groupby("draw", sort=True):
        sums, cov, hit, _ = _strata_sums(d)
        share.append(float(d["hit"].mean()))
        raw.append(float((d["realized"] - d["predicted"]).mean()))
        std.append(_standardized(sums, cov, hit, *probabilities[k], np.ones(len(hit)))[0])
    out: dict[str, Any] = {"count": len(share)}
    for name, v in (("share", share), ("optimism", raw), ("optimism_std", std)):
        v = np.asarray(v, dtype=float)
        out.update({f"{name}.min.k{k}": float(np.nanmin(v)), f"{name}.max.k{k}": float(np.nanmax(v)),
                    f"{name}.sd.k{k}": float(np.nanstd(v, ddof=1)) if len(v) > 1 else float("nan")})
    return out


def keys(rows: pd.DataFrame, boot: Mapping[str, int]) -> dict[str, Any]:
    """Every key of the step from its stored rows: the frozen draw's (``frozen.*``) and the fresh draws'
    (``draws.*``, present when any fresh draw is stored)."""
    from probecommit.tasks.insertion.model import InsertionModel

    positions = [float(u) for u in np.asarray(InsertionModel.probe_grid, dtype=float).reshape(-1)]
    first = rows.iloc[0]
    probabilities = design_probabilities(positions, {n: float(first[n]) for n in DESIGN},
                                         sorted(int(k) for k in rows["k"].unique()))
    out = {f"frozen.{n}": v for n, v in frozen_keys(rows[rows["draw"] == FROZEN], probabilities,
                                                   int(boot["resamples"]), int(boot["seed"])).items()}
    fresh = rows[rows["draw"] != FROZEN]
    if len(fresh) and 8 in probabilities:
        out.update({f"draws.{n}": v for n, v in draw_keys(fresh, probabilities).items()})
    return out
