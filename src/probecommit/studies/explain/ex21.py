"""The ex21 helper's step (E150, E151), run by ``Explain.run``: E106's five paper's-schedule draws replayed from
their stored taps under the stated filter, the unstated weight and jitter-timing readings, and the first
resampling's jitter removed (``ex21_band``). No engine run. It stores the rows its keys come from, so ``verify``
recomputes every key (``recompute``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.studies.explain import ex21_band, stored

#: Result groups this step fills (added to ``Explain.res``).
GROUPS = ("ex21_band",)
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex21_band": ex21_band.STORED}
#: The paper's-schedule runs ``runs.schedule_runs`` writes, by the part ``rows_of`` reads.
PAPER_RUNS = {"test": "B_test_cover_paper_schedule", "cal": "B_cal_cover_paper_schedule", "A": "A_cover_paper_schedule"}


def _draw_rows(beliefs: Any, loaded: Any, final_k: int, inner: float, outer: float,
               trajectory_rows: Any = ex21_band.trajectory_rows, readings: Any = ex21_band.READINGS) -> pd.DataFrame:
    """Every reading's rows of one run, with the run's stored final-budget escape beside each trajectory (another
    step's ``trajectory_rows`` and ``readings``: ex24's)."""
    e = loaded.episodes
    e = e[(e["method"] == "probe_robust") & (e["status"] == "ok") & (e["k"] == final_k)]
    stored = e[["instance_id", "repeat", "escaped"]].astype({"instance_id": str, "repeat": "int64"})
    stored = stored.rename(columns={"escaped": "stored_escaped_final"})
    parts = [trajectory_rows(beliefs, r, final_k, inner, outer) for r in readings]
    rows = pd.concat(parts, ignore_index=True).merge(stored, on=["instance_id", "repeat"], how="left",
                                                     validate="many_to_one")
    return rows.assign(stored_escaped_final=rows["stored_escaped_final"].eq(True))


def rows_of(paper_schedule: dict[str, Any], pool: Any, final_k: int, outer: float, **how: Any) -> pd.DataFrame:
    """The stored rows: Split B test and calibration, Split A, and the re-split pool's two halves (E106's draws);
    ``how``: ``_draw_rows``' ``trajectory_rows`` and ``readings`` for another step's replay (ex24)."""
    from probecommit.runner.replay import RunBeliefs
    from probecommit.tasks.insertion.model import TIP_RADIUS_MM

    sources = [("b_test", paper_schedule["test"]), ("b_cal", paper_schedule["cal"]), ("a", paper_schedule["A"])]
    if pool is not None:
        sources.append(("pool", pool))
    parts = []
    for draw, loaded in sources:
        rows = _draw_rows(RunBeliefs.of(loaded, chunk_instances=None), loaded, final_k, -TIP_RADIUS_MM, outer, **how)
        if draw == "pool":
            order = loaded.instances.sort_values("instance_index")["instance_id"].astype(str).to_numpy()
            first = set(order[: len(order) // 2])
            rows = rows.assign(draw=np.where(rows["instance_id"].isin(first), "pool_0", "pool_1"))
        parts.append(rows if draw == "pool" else rows.assign(draw=draw))
    return pd.concat(parts, ignore_index=True)


def run(job: Any) -> None:
    """E150 and E151 on the paper's-schedule runs and the re-split pool's run (none: four draws), read from the
    explain target's run folders (stored inputs only: the step runs in a process of its own)."""
    from probecommit.runner.replay import load_run
    from probecommit.studies.explain.ex13 import POOL_RUN

    job.progress("explain: T36's band trajectories under the unstated weight and jitter-timing readings", 0, 1)
    paper = {part: load_run(job.runs / name) for part, name in PAPER_RUNS.items()}
    pool_dir = job.runs / POOL_RUN
    pool = load_run(pool_dir) if (pool_dir / "episodes.parquet").is_file() else None
    offset = float(paper["test"].config.simulator.boundary_offset)
    rows = rows_of(paper, pool, int(job.p.budgets["cover"]), offset)
    job.stored[ex21_band.STORED] = rows
    job.res["ex21_band"].update(ex21_band.keys(rows, **job.boot))


def recompute(folder: Path, results: dict[str, Any], boot: dict[str, Any]) -> dict[str, tuple[Any, str]]:
    """``{"<group>.<key>": (value, stored file)}`` of every key this step publishes, from the stored rows."""
    return stored.recompute_bootstrapped(folder, results, "ex21_band", ex21_band.STORED,
                                         lambda rows: ex21_band.keys(rows, **boot))
