"""The calibration items' experiments (E55..E57; ex5, issue #36): Sec. V-B's cost of calibration and
re-splits, and Table III's optimism cells (rules declared in ``docs/decisions.md``, "ex5").

* **E55, the cost of the full adjustment over re-splits** (T13). Table IV's paired difference (set
  calibration + margin minus none, cover, final budget) on one 96/96 split is one draw; the 50
  re-splits of the insertion study's 192-instance MuJoCo pool (its split seed) give the spread of
  the estimate and of the zero verdict under the same design.
* **E56, the re-split study over fresh pools** (T14). The re-split means are statistics of one pool;
  fresh 192-instance pools of Split B's generator in MuJoCo, under the paper's cover schedule,
  each re-split exactly as the insertion study does, give their spread over pools.
* **E57, a capture window narrower than the model's** (Table III's optimism, T12). E17's fresh
  draws (same split names, instances and tap streams) rerun on the analytic scene with MuJoCo's
  tap boundary and the realized window ``s * w(c)``; each draw calibrated on the next (E19).

Every key of the ``ex5_calibration`` group is :func:`summary` of the stored rows
(:data:`STORED`), so verify recomputes them from the very rows the step stores.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pandas as pd

from probecommit.process.memory import large_arrays_apart, trim_heap
from probecommit.runner.calibration import calibrate
from probecommit.runner.config import config_data, parse_config
from probecommit.runner.replay import LoadedRun, RunBeliefs, load_run
from probecommit.studies.paper_values import value as paper_value

#: The rows every key is computed from (one row per re-split, fresh pool or calibration pair).
STORED = "ex5_calibration_rows.parquet"
#: Table III's budgets and the cells E57 compares (the optimism cells of both arms).
AUDIT_K = (1, 2, 3, 5, 8)
CELLS = tuple(f"optimism.{arm}.k{k}" for arm in ("original", "calibrated") for k in AUDIT_K)
#: The pool statistics E56 compares (``resplits.summary``'s names).
POOL_STATS = ("level_mean", "heldout_cluster_coverage", "margin_optimistic_fraction", "failure_mean", "gamma_mean")


# ----------------------------------------------------------------------------- E55: cost over re-splits


def split_halves(ids: np.ndarray, count: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """The re-split study's halves (calibration, test): the same draws as ``studies.insertion.resplit_table``."""
    rng = np.random.default_rng(seed)
    half = len(ids) // 2
    return [(ids[p[:half]], ids[p[half:]]) for p in (rng.permutation(len(ids)) for _ in range(count))]


def resplit_costs(pool: LoadedRun, alpha: float, count: int, seed: int, budgets: Sequence[int], resamples: int,
                  boot_seed: int) -> pd.DataFrame:
    """Table IV's full-adjustment paired difference on each re-split (calibrated on one half over ``budgets``,
    measured on the other at the last budget): one row per split with ``difference, lo, hi, gamma`` and the
    held-out calibrated optimism at each budget, ``optimism_k<k>``."""
    beliefs = RunBeliefs.of(pool, chunk_instances=None, budgets=list(budgets))
    halves = split_halves(pool.instances["instance_id"].to_numpy(), count, seed)
    with large_arrays_apart():  # each split's halves and commits on pages of their own, not heap fragments
        return pd.DataFrame([_split_cost(pool, beliefs, n, cal_ids, test_ids, alpha, budgets, resamples, boot_seed)
                             for n, (cal_ids, test_ids) in enumerate(halves)])


def _split_cost(pool: LoadedRun, beliefs: RunBeliefs, n: int, cal_ids: np.ndarray, test_ids: np.ndarray, alpha: float,
                budgets: Sequence[int], resamples: int, boot_seed: int) -> dict[str, Any]:
    """:func:`resplit_costs`'s row of split ``n``; its copies go back before the next split's (issue 42, target 4)."""
    from probecommit.studies.insertion import subset_run

    res = calibrate(subset_run(pool, cal_ids, beliefs), subset_run(pool, test_ids, beliefs), alpha=alpha,
                    budgets=list(budgets), resamples=resamples, seed=boot_seed + n)
    diff = res.cost_differences
    full = diff[(diff["baseline"] == "no calibration") & (diff["treatment"] == "set calibration + margin")].iloc[0]
    # each budget's held-out calibrated optimism (ex9's E83 reads it; E55's keys do not)
    held_out = {f"optimism_k{int(r['k'])}": float(r["optimism_calibrated"]) for r in res.table3.to_dict("records")}
    row = {"part": "resplit_cost", "index": n, "difference": float(full["difference"]), "lo": float(full["lo"]),
           "hi": float(full["hi"]), "gamma": float(res.margin.gamma), **held_out}
    del res, diff, full
    trim_heap()
    return row


def cost_keys(rows: pd.DataFrame) -> dict[str, float]:
    """E55's keys: the split estimates' spread and the share of splits whose interval lies above zero."""
    est = rows["difference"].to_numpy(float)
    return {"splits": int(len(rows)), "estimate.mean": float(est.mean()), "estimate.min": float(est.min()),
            "estimate.max": float(est.max()), "estimate.p025": float(np.percentile(est, 2.5)),
            "estimate.p975": float(np.percentile(est, 97.5)),
            "share_above_zero": float((rows["lo"].to_numpy(float) > 0).mean()),
            "share_below_zero": float((rows["hi"].to_numpy(float) < 0).mean()),
            "gamma.mean": float(rows["gamma"].mean())}


# ----------------------------------------------------------------------------- E56: fresh pools


def fresh_pool_row(protocol: Any, schedule: list[float], runs: Path, i: int, workers: int) -> dict[str, Any]:
    """Fresh pool ``i`` (split ``pool_draw_<i>``, the frozen pool's config under ``schedule``), re-split as the
    insertion study does: ``resplits.summary``'s statistics."""
    from probecommit.runner.study import run_study
    from probecommit.studies.explain.resplits import summary
    from probecommit.studies.insertion import resplit_table

    p = protocol.model_copy(update={"cover_schedule": [float(u) for u in schedule]})
    r, name = protocol.resplits, f"pool_draw_{i:02d}"
    cfg = p.run_config(f"{name}_paper_schedule", "B", name, "cover")
    cfg = cfg.model_copy(update={"instances": cfg.instances.model_copy(update={"count": p.instances["B"].count * 2})})
    path = runs / f"{name}_paper_schedule"
    run_study(cfg, path, workers=workers, threads=1)
    table = resplit_table(load_run(path), protocol.alpha, int(r["count"]), int(r["seed"]), protocol.budgets["cover"],
                          protocol.bootstrap.seed)
    return {"part": "fresh_pool", "index": i, **{k: float(v) for k, v in summary(table).items()}}


def fresh_pool_rows(protocol: Any, schedule: list[float], runs: Path, count: int, workers: int,
                    first: int = 0) -> pd.DataFrame:
    """Fresh pools ``first .. count - 1`` (:func:`fresh_pool_row`), one row each: E56 runs the first ``count``, ex35's
    E205 the ones after E56's (its rows are E56's stored ones)."""
    return pd.DataFrame([fresh_pool_row(protocol, schedule, runs, i, workers) for i in range(first, count)])


def pool_keys(rows: pd.DataFrame) -> dict[str, float]:
    """E56's keys: each pool statistic's min, max and mean over the fresh pools."""
    out: dict[str, float] = {"pools": int(len(rows))}
    for stat in POOL_STATS:
        v = rows[stat].to_numpy(float)
        out.update({f"{stat}.min": float(v.min()), f"{stat}.max": float(v.max()), f"{stat}.mean": float(v.mean())})
    return out


# ----------------------------------------------------------------------------- E57: capture window


def capture_draws(protocol: Any, runs: Path, scale: float, count: int, workers: int) -> list[Path]:
    """E17's fresh draws (split names ``draw_<i>``) on the analytic scene with MuJoCo's tap boundary and the
    realized capture window ``scale * w(c)``."""
    from probecommit.runner.study import run_study

    out = []
    for i in range(count):
        split = f"draw_{i:02d}"
        name = f"analytic_capture{scale:.2f}_{split}"
        data = config_data(protocol.run_config(name, "B", split, "random"))
        data["simulator"] = {**data["simulator"], "engine": "analytic", "boundary_offset": float(protocol.delta),
                             "capture_scale": float(scale)}
        run_study(parse_config(data), runs / name, workers=workers, threads=1)
        out.append(runs / name)
    return out


def pair_cells(cal: Path | LoadedRun, test: Path | LoadedRun, budgets: Sequence[int], alpha: float) -> dict[str, float]:
    """Table III's optimism cells (both arms), bottom row and the margin on ``test`` calibrated on ``cal``."""
    res = calibrate(cal, test, alpha=alpha, budgets=list(budgets), resamples=2, seed=0, chunk_instances=48)
    out = {"gamma": float(res.margin.gamma)}
    for row in res.table3.to_dict("records"):
        for arm in ("original", "calibrated"):
            out[f"optimism.{arm}.k{int(row['k'])}"] = float(row[f"optimism_{arm}"])
    for arm in ("original", "calibrated"):
        out[f"mean_abs_optimism.{arm}"] = float(res.summary[f"mean_abs_optimism_{arm}"])
    return out


def scale_rows(protocol: Any, paths: Sequence[Path], scale: float, budgets: Sequence[int]) -> pd.DataFrame:
    """One scale's rows, one per pair: draw ``i`` tested under a calibration on draw ``i + 1`` (cyclic, as E19).
    Each draw's beliefs are computed once for both pairs it is in, at ``budgets`` only (no other is read)."""
    from probecommit.studies.explain.shared_beliefs import SharedBeliefs, cyclic_pairs

    shared = SharedBeliefs(budgets)
    with large_arrays_apart():  # two whole-run traces held: the pairs' arrays leave no holes in the heap
        _, pairs = cyclic_pairs(list(paths), lambda cal, test: pair_cells(shared.run(cal, budgets),
                                                                           shared.run(test, budgets), budgets,
                                                                           protocol.alpha), shared)
    if len(paths) == 1:  # calibrated on itself, as ``paths[(i + 1) % 1]`` is
        pairs = [pair_cells(paths[0], paths[0], budgets, protocol.alpha)]
    return pd.DataFrame([{"part": "capture", "index": i, "scale": float(scale), **cells} for i, cells in enumerate(pairs)])


def capture_rows(protocol: Any, runs: Path, scales: Sequence[float], count: int, budgets: Sequence[int],
                 workers: int) -> pd.DataFrame:
    """Every scale's rows (:func:`scale_rows`). Each scale's draws, then its pairs, run in a process of their own
    (issue 42, target 4): the draws' runs and the pairs' two whole-run traces leave with them (one process
    holding every scale's reached 553 MB)."""
    from probecommit.runner.aside import in_own_process

    parts = []
    for scale in scales:
        paths = in_own_process(capture_draws, protocol, runs, float(scale), count, workers)
        parts.append(in_own_process(scale_rows, protocol, paths, float(scale), list(budgets)))
    return pd.concat(parts, ignore_index=True)


def _inside(lo: float, hi: float, key: str) -> bool:
    return lo <= paper_value(key) <= hi


def capture_keys(rows: pd.DataFrame) -> dict[str, float]:
    """E57's keys: each cell's range per scale, and the scale the declared rule picks.

    ``best`` is the largest scale at which every paper optimism cell and the paper's random margin lie within
    the pairs' ranges (``best_meets_rule`` 1); when none does, the scale with the most of them inside (ties:
    the larger scale) with ``best_meets_rule`` 0, so the keys resolve and the experiment says it failed.
    """
    out: dict[str, float] = {}
    tests = {cell: f"tab:audit.optimism_{cell.split('.')[1]}.{cell.split('.k')[1]}" for cell in CELLS}
    tests["gamma"] = "T03-margin.random"
    scored = []
    for scale, part in rows.groupby("scale", sort=True):
        pre = f"s{scale:.2f}"
        for cell in (*CELLS, "gamma", "mean_abs_optimism.original", "mean_abs_optimism.calibrated"):
            v = part[cell].to_numpy(float)
            out.update({f"{pre}.{cell}.min": float(v.min()), f"{pre}.{cell}.max": float(v.max()),
                        f"{pre}.{cell}.mean": float(v.mean())})
        inside = sum(_inside(out[f"{pre}.{c}.min"], out[f"{pre}.{c}.max"], key) for c, key in tests.items())
        scored.append((inside, float(scale)))
        out[f"{pre}.inside"] = int(inside)
    inside, best = max(scored)
    out.update({"pairs": int((rows["scale"] == best).sum()), "best_scale": best, "best_inside": int(inside),
                "tests": len(tests), "best_meets_rule": int(inside == len(tests))})
    pre = f"s{best:.2f}"
    out.update({key.replace(pre, "best", 1): v for key, v in list(out.items()) if key.startswith(pre + ".")})
    return out


# ----------------------------------------------------------------------------- the step


def resplit_costs_of(pool: Path, *args: Any) -> pd.DataFrame:
    """:func:`resplit_costs` on the frozen pool's run as the job loads it (``Explain.load``), in a process of its
    own (``run``)."""
    return resplit_costs(load_run(pool), *args)


def summary(rows: pd.DataFrame) -> dict[str, float]:
    """Every key of the ``ex5_calibration`` group from the stored rows (the step and verify both call this)."""
    out: dict[str, float] = {}
    for part, keys in (("resplit_cost", cost_keys), ("fresh_pool", pool_keys), ("capture", capture_keys)):
        sub = rows[rows["part"] == part]
        if len(sub):
            out.update({f"{part}.{k}": v for k, v in keys(sub).items()})
    return out


def run(job: Any) -> None:
    """E55..E57 on the root's frozen runs; fills ``job.res["ex5_calibration"]`` and stores the rows."""
    p, cfg, quick = job.p, job.cfg, job.quick
    from probecommit.studies.explain.study import COVER_SCHEDULE

    from probecommit.runner.aside import in_own_process

    # Each part in a process of its own (issue 42, target 4): the pool's whole-run beliefs of the first, the
    # fresh pools' runs and the capture draws' pairs of traces leave with their part (one process held 611 MB).
    job.progress("explain: the cost of calibration over re-splits", 0, 1)
    r = p.resplits
    cost = in_own_process(resplit_costs_of, job.ins / "B_pool_cover", p.alpha, int(r["count"]), int(r["seed"]),
                          list(range(1, p.budgets["cover"] + 1)),
                          cfg["ex5_cost_resamples_quick" if quick else "ex5_cost_resamples"], p.bootstrap.seed)
    job.progress("explain: the re-split study on fresh pools", 0, 1)
    pools = in_own_process(fresh_pool_rows, p, COVER_SCHEDULE, job.runs,
                           cfg["ex5_fresh_pools_quick" if quick else "ex5_fresh_pools"], job.workers)
    job.progress("explain: Table III under a narrower capture window", 0, 1)
    capture = capture_rows(p, job.runs, cfg["ex5_capture_scales_quick" if quick else "ex5_capture_scales"],
                           cfg["ex5_capture_draws_quick" if quick else "ex5_capture_draws"], cfg["random_budgets"],
                           job.workers)
    rows = pd.concat([cost, pools, capture], ignore_index=True)
    job.stored[STORED] = rows
    job.res["ex5_calibration"].update(summary(rows))
