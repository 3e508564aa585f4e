"""The re-split study (Sec. V-B, 50 re-splits of Split B's 192-instance cover pool) under the paper's
cover schedule, on the same instances and tap-noise streams as ours.

The insertion study's re-splits (``studies.insertion``) run on our frozen schedule; the paper's
schedule changes which trajectories escape (E13), hence the fixed-budget level t_5 and its
held-out coverage. The same splits (the protocol's seed) are calibrated here on the paper's
schedule's pool.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.runner.calibration import calibrate
from probecommit.runner.replay import LoadedRun, RunBeliefs
from probecommit.studies.protocol import Protocol


def pool_config(protocol: Protocol, schedule: list[float]) -> Any:
    """The re-split pool's run config (split ``B_pool_cover``, twice Split B's count) under ``schedule``."""
    p = protocol.model_copy(update={"cover_schedule": [float(u) for u in schedule]})
    cfg = p.run_config("B_pool_cover_paper_schedule", "B", "B_pool_cover", "cover")
    return cfg.model_copy(update={"instances": cfg.instances.model_copy(update={"count": p.instances["B"].count * 2})})


def _subset(loaded: LoadedRun, ids: np.ndarray, beliefs: RunBeliefs) -> LoadedRun:
    """``loaded`` restricted to ``ids`` with beliefs taken from the whole run's (as the insertion study's
    ``subset_run``, which lives a layer above)."""
    keep = set(ids)
    pick = lambda frame: frame[frame.instance_id.isin(keep)].reset_index(drop=True)  # noqa: E731
    return LoadedRun(loaded.path, loaded.config, pick(loaded.instances), pick(loaded.probes), pick(loaded.episodes),
                     loaded.engine_cache, loaded.manifest, beliefs.restrict(keep))


def resplit_table(pool: LoadedRun, alpha: float, count: int, seed: int, k: int, boot_seed: int) -> pd.DataFrame:
    """Per split: the level t_k, set+margin failure, held-out cluster coverage and whether the margin is
    optimistic at ``k`` (the insertion study's re-split rows, same permutations)."""
    ids = pool.instances["instance_id"].to_numpy()
    rng = np.random.default_rng(seed)
    beliefs = RunBeliefs.of(pool, chunk_instances=None, budgets=[k])
    rows = []
    for n in range(count):
        perm = rng.permutation(len(ids))
        half = len(ids) // 2
        res = calibrate(_subset(pool, ids[perm[:half]], beliefs), _subset(pool, ids[perm[half:]], beliefs),
                        alpha=alpha, budgets=[k], resamples=50, seed=boot_seed + n)
        t3 = res.table3
        cost = res.cost[res.cost["setting"] == "set calibration + margin"]
        rows.append({"split": n, "level": float(res.thresholds[k]), "failure": float(cost["failure"].iloc[0]),
                     "heldout_cluster_coverage": float(t3["cluster_coverage_calibrated"].iloc[0]),
                     "margin_optimistic": bool(t3["optimism_calibrated"].iloc[0] > 0), "gamma": res.margin.gamma})
    return pd.DataFrame(rows)


def summary(table: pd.DataFrame) -> dict[str, float]:
    """The re-split study's summary keys (as the insertion study's ``resplits``)."""
    return {"level_mean": float(table.level.mean()), "level_sd": float(table.level.std(ddof=1)),
            "failure_mean": float(table.failure.mean()), "heldout_cluster_coverage": float(table.heldout_cluster_coverage.mean()),
            "margin_optimistic_fraction": float(table.margin_optimistic.mean()), "gamma_mean": float(table.gamma.mean()),
            "splits": int(len(table))}


def run(protocol: Protocol, schedule: list[float], runs: Path, workers: int) -> dict[str, float]:
    """The pool under ``schedule`` (run once into ``runs``) and its re-split summary."""
    from probecommit.runner.replay import load_run
    from probecommit.runner.study import run_study

    path = runs / "B_pool_cover_paper_schedule"
    run_study(pool_config(protocol, schedule), path, workers=workers, threads=1)
    r = protocol.resplits
    return summary(resplit_table(load_run(path), protocol.alpha, int(r["count"]), int(r["seed"]), protocol.budgets["cover"],
                                 protocol.bootstrap.seed))
