"""T14's re-split statistics over twelve fresh pools (E205; ex35, issue #36; rule declared in ``docs/decisions.md``,
"ex35", before any new pool's number was computed).

Why: E56 asked whether the paper's re-split statistics (level mean, held-out cluster coverage, margin optimistic)
are ordinary values of one pool of our process, over 3 fresh pools (its declared 5 cut for load). [min, max] over n
exchangeable pools holds one more pool with probability (n - 1) / (n + 1): 0.50 at 3, 0.85 at the project's
standard 12 (E17). E205 is E56 at 12 pools, E56's rule unchanged: its first pools are E56's stored rows (the same
function on the same split names), the rest run here by E56's own :func:`ex5_calibration.fresh_pool_rows`.
Every key of the group is :func:`summary` of the stored rows (:data:`STORED`), so verify recomputes them.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pandas as pd

from probecommit.studies.explain import ex5_calibration
from probecommit.studies.paper_values import RESPLIT_STATS, value as paper_value

#: The stored rows (one per fresh pool, ``ex5_calibration.fresh_pool_row``'s), beside results.json.
STORED = "ex35_pools_rows.parquet"
#: Result group.
GROUP = "ex35_pools"
#: The statistics the rule judges, with the paper's value each is compared to and its scale to a fraction.
TESTED = {stat: (key, scale) for _, stat, key, scale in RESPLIT_STATS}


def paper_fraction(stat: str) -> float:
    """The paper's value of a tested statistic on the rows' scale (the margin's 64 % as 0.64)."""
    key, scale = TESTED[stat]
    return float(paper_value(key)) * scale


def summary(rows: pd.DataFrame) -> dict[str, float]:
    """E205's keys: E56's per-statistic min, max and mean over the pools (``ex5_calibration.pool_keys``), and beside
    them each tested statistic's SD over pools, the pools at or above the paper's value, whether the paper's value
    lies in [min, max] (the rule, 1 = holds), and the range's prediction level (n - 1) / (n + 1)."""
    out = ex5_calibration.pool_keys(rows)
    n = len(rows)
    out["prediction_level"] = float((n - 1) / (n + 1))
    for stat in TESTED:
        v, paper = rows[stat].to_numpy(float), paper_fraction(stat)
        out[f"{stat}.sd"] = float(v.std(ddof=1)) if n > 1 else float("nan")
        out[f"{stat}.at_least_paper"] = int((v >= paper).sum())
        out[f"{stat}.holds"] = int(v.min() <= paper <= v.max())
    return out


def pool_rows(job: Any, count: int) -> pd.DataFrame:
    """Pools ``0 .. count - 1``: E56's stored rows first (its step ran before, in this job), then the rest, each
    pool in a process of its own (its run and re-split tables leave with it)."""
    from probecommit.runner.aside import in_own_process
    from probecommit.studies.explain.ex15_readings import _stored_part
    from probecommit.studies.explain.study import COVER_SCHEDULE

    e56 = _stored_part(job, ex5_calibration.STORED, "fresh_pool")
    e56 = [] if e56 is None else [e56.sort_values("index").head(count)]
    done = len(e56[0]) if e56 else 0
    if e56 and not np.array_equal(e56[0]["index"].to_numpy(int), np.arange(done)):
        raise ValueError("E56's stored fresh pools are not pools 0 .. n - 1")
    fresh = [in_own_process(ex5_calibration.fresh_pool_rows, job.p, COVER_SCHEDULE, job.runs, i + 1, job.workers, i)
             for i in range(done, count)]
    return pd.concat([*e56, *fresh], ignore_index=True)


def run(job: Any) -> None:
    """The explain step (set aside after ex5's, whose stored fresh-pool rows it reads): stored rows and keys."""
    count = int(job.cfg["ex35_pools_quick" if job.quick else "ex35_pools"])
    if count < 1:
        return
    job.progress(f"explain: the re-split study over {count} fresh pools (E205)", 0, 1)
    rows = pool_rows(job, count)
    job.stored[STORED] = rows
    job.res[GROUP].update(summary(rows))


__all__: Sequence[str] = ("run", "summary", "pool_rows", "paper_fraction", "TESTED", "STORED", "GROUP")
