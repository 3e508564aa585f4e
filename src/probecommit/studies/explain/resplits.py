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

import pandas as pd

from probecommit.studies.insertion import resplit_table
from probecommit.studies.protocol import Protocol


def pool_config(protocol: Protocol, schedule: list[float]) -> Any:
    """The re-split pool's run config (split ``B_pool_cover``, twice Split B's count) under ``schedule``."""
    p = protocol.model_copy(update={"cover_schedule": [float(u) for u in schedule]})
    cfg = p.run_config("B_pool_cover_paper_schedule", "B", "B_pool_cover", "cover")
    return cfg.model_copy(update={"instances": cfg.instances.model_copy(update={"count": p.instances["B"].count * 2})})


def summary(table: pd.DataFrame) -> dict[str, float]:
    """The re-split study's summary keys (as the insertion study's ``resplits``)."""
    return {"level_mean": float(table.level.mean()), "level_sd": float(table.level.std(ddof=1)),
            "failure_mean": float(table.failure.mean()), "heldout_cluster_coverage": float(table.heldout_cluster_coverage.mean()),
            "margin_optimistic_fraction": float(table.margin_optimistic.mean()), "gamma_mean": float(table.gamma.mean()),
            "splits": int(len(table))}


#: The stored re-split rows (one per split; ``summary`` reads them).
STORED = "resplits_paper_schedule.parquet"


def run(protocol: Protocol, schedule: list[float], runs: Path, workers: int) -> pd.DataFrame:
    """The pool under ``schedule`` (run once into ``runs``) and its re-split rows (``summary`` summarizes them)."""
    from probecommit.runner.replay import load_run
    from probecommit.runner.study import run_study

    path = runs / "B_pool_cover_paper_schedule"
    run_study(pool_config(protocol, schedule), path, workers=workers, threads=1)
    r = protocol.resplits
    return resplit_table(load_run(path), protocol.alpha, int(r["count"]), int(r["seed"]), protocol.budgets["cover"],
                         protocol.bootstrap.seed)
