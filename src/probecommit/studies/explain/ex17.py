"""The ex17 helper's steps (E126, E127), run by ``Explain.run``: Table III's original arm under the aim
tie-break readings with each commit's optimism split into its parts, and what T36's k = 1 AUC asks of the
cover schedule's first tap.

E126 reads only the insertion study's stored random test run (beliefs recomputed from its taps, aims' outcomes
from its engine cache): it runs in a process of its own (``Explain.aside``). E127 reads E106's stored rows and
the paper's-schedule runs' instances, after ``ex13.surprise``. Both store the rows their keys come from, so
``verify`` recomputes every key (``recompute``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd

from probecommit.studies.explain import ex17_band, ex17_tiebreak

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex17_tiebreak", "ex17_band")
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = {"ex17_tiebreak": ex17_tiebreak.STORED, "ex17_band": ex17_band.STORED}
#: The draws E106 reads, in its order.
DRAWS = ("b_test", "b_cal", "a", "pool_0", "pool_1")


def _paper_optimism() -> list[float]:
    from probecommit.studies.paper_values import value

    return [value(f"tab:audit.optimism_original.{k}") for k in ex17_tiebreak.BUDGETS]


def paper_t36() -> tuple[int, float, float]:
    """The paper's T36 trajectories (escaped + covered), escapes and k = 1 AUC."""
    from probecommit.studies.paper_values import value

    escaped = value("T36-surprise.escaped")
    return int(escaped + value("T36-surprise.covered")), float(escaped), value("T36-surprise.auc_k1")


def tiebreak(job: Any) -> None:
    """E126 on Table III's random test run."""
    job.progress("explain: Table III's original arm under the aim tie-break readings", 0, 1)
    rows = ex17_tiebreak.commit_rows(job.load("B_test_random"))
    job.stored[ex17_tiebreak.STORED] = rows
    job.res["ex17_tiebreak"].update(ex17_tiebreak.keys(rows, _paper_optimism(), job.boot))


def band(job: Any, paper_schedule: dict[str, Any], first_tap: float) -> None:
    """E127 from E106's stored rows and the paper's-schedule runs' truths (``first_tap``: the schedule's first)."""
    from probecommit.studies.explain import ex13_surprise
    from probecommit.studies.explain.ex13 import POOL_RUN

    job.progress("explain: what T36's k = 1 AUC asks of the first tap", 0, 1)
    surprise = job.stored.get(ex13_surprise.STORED)
    if surprise is None or not len(surprise):
        return
    runs = [run for run in paper_schedule.values() if hasattr(run, "instances")]
    pool = job.runs / POOL_RUN
    instances = [run.instances for run in runs]
    if (pool / "instances.parquet").is_file():
        instances.append(pd.read_parquet(pool / "instances.parquet"))
    config = runs[0].config
    m = config.model
    inputs = {"first_tap": float(first_tap), "x_low": float(m.prior_low[0]), "x_high": float(m.prior_high[0]),
              "c_low": float(m.prior_low[1]), "c_high": float(m.prior_high[1]),
              "sim_offset": float(config.simulator.boundary_offset)}
    rows = ex17_band.band_rows(surprise, instances, inputs)
    job.stored[ex17_band.STORED] = rows
    job.res["ex17_band"].update(ex17_band.keys(rows, *paper_t36(), DRAWS))


def recompute(folder: Path, results: dict[str, Any], boot: dict[str, Any]) -> dict[str, tuple[Any, str]]:
    """``{"<group>.<key>": (value, stored file)}`` of every key these steps publish, from the stored rows."""
    out: dict[str, tuple[Any, str]] = {}
    for group, name, summary in (
            ("ex17_tiebreak", ex17_tiebreak.STORED, lambda r: ex17_tiebreak.keys(r, _paper_optimism(), boot)),
            ("ex17_band", ex17_band.STORED, lambda r: ex17_band.keys(r, *paper_t36(), DRAWS))):
        if (folder / name).is_file() and results.get(group):
            for key, v in summary(pd.read_parquet(folder / name)).items():
                out[f"{group}.{key}"] = (v, name)
    return out
