"""The ex24 helper's step (E168-E170), run by ``Explain.run``: E106's five paper's-schedule draws replayed from their
stored taps with the first tap's jitter tail removed alone, with the jitter read as a variance, and post-stratified to
the design's exposure to the first tap's band (``ex24_band``). No engine run; it reads only stored runs, so it runs in
a process of its own (``Explain.aside``). It stores the rows its keys come from, so ``verify`` recomputes every key.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd

from probecommit.studies.explain import ex24_band, stored

#: Result groups this step fills (added to ``Explain.res``).
GROUPS = ("ex24_band",)
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex24_band": ex24_band.STORED}


def band_inputs(loaded: Any, first_tap: float) -> dict[str, float]:
    """The first tap's band inputs of a paper's-schedule run (its prior box, ``r`` and the simulator's delta)."""
    from probecommit.tasks.insertion.model import TIP_RADIUS_MM

    m, cfg = loaded.config.model, loaded.config
    return {"first_tap": float(first_tap), "x_low": float(m.prior_low[0]), "x_high": float(m.prior_high[0]),
            "c_low": float(m.prior_low[1]), "c_high": float(m.prior_high[1]), "tip_radius": TIP_RADIUS_MM,
            "sim_offset": float(cfg.simulator.boundary_offset)}


def rows_of(paper: dict[str, Any], pool: Any, final_k: int, first_tap: float) -> pd.DataFrame:
    """Every reading's rows of E106's draws (``ex21.rows_of`` with this step's replay), with the band inputs."""
    from probecommit.studies.explain import ex21

    offset = float(paper["test"].config.simulator.boundary_offset)
    rows = ex21.rows_of(paper, pool, final_k, offset, trajectory_rows=ex24_band.trajectory_rows,
                        readings=ex24_band.READINGS)
    return rows.assign(**band_inputs(paper["test"], first_tap))


def run(job: Any) -> None:
    """E168-E170 on the paper's-schedule runs and the re-split pool's run (none: four draws), read from the explain
    target's run folders."""
    from probecommit.runner.replay import load_run
    from probecommit.studies.explain.ex13 import POOL_RUN
    from probecommit.studies.explain.ex21 import PAPER_RUNS
    from probecommit.studies.explain.study import COVER_SCHEDULE

    job.progress("explain: T36's first-tap jitter tail alone, the jitter as a variance, the band's exposure", 0, 1)
    paper = {part: load_run(job.runs / name) for part, name in PAPER_RUNS.items()}
    pool_dir = job.runs / POOL_RUN
    pool = load_run(pool_dir) if (pool_dir / "episodes.parquet").is_file() else None
    rows = rows_of(paper, pool, int(job.p.budgets["cover"]), COVER_SCHEDULE[0])
    job.stored[ex24_band.STORED] = rows
    job.res["ex24_band"].update(ex24_band.keys(rows, **job.boot))


def recompute(folder: Path, results: dict[str, Any], boot: dict[str, Any]) -> dict[str, tuple[Any, str]]:
    """``{"<group>.<key>": (value, stored file)}`` of every key this step publishes, from the stored rows."""
    return stored.recompute_bootstrapped(folder, results, "ex24_band", ex24_band.STORED,
                                         lambda rows: ex24_band.keys(rows, **boot))
