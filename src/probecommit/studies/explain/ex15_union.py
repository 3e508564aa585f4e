"""T14 on the literal Split B pool (E119; ex15, issue #36; rule declared in ``docs/decisions.md``, "ex15: T14 on the
literal Split B pool").

The paper's "one 192-instance pool" read literally is Split B's calibration and test halves of the cover protocol
pooled ("96 calibration and 96 test instances per protocol"); our re-split study draws a pool of its own
(``B_pool_cover``). This step pools the frozen runs ``B_cal_cover`` and ``B_test_cover`` (nothing re-run but the
calibrations' commits), re-splits the union with the insertion study's splits and calibrates each split twice:
as our study does (budget 5 alone, ``studies.insertion.resplit_table``) and as E55 does (budgets 1..5 with the
margin searched over them, ``ex5_calibration.resplit_costs``). The per-split readings are E118's
(:mod:`ex15_readings`), so the group's keys are :func:`ex15_readings.summary` of the stored rows (:data:`STORED`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import pandas as pd

from probecommit.studies.explain import ex15_readings

#: The stored per-split rows, beside results.json.
STORED = "ex15_union_rows.parquet"
#: Result group.
GROUP = "ex15_union"
#: The pool's name in the rows and keys, and the frozen runs it pools.
POOL, RUNS = "B_union_cover", ("B_cal_cover", "B_test_cover")
#: Bootstrap resamples of each calibration call: only point estimates are read (failure, the paired difference's
#: estimate, held-out optimism), which no resample count changes.
RESAMPLES = 50

summary = ex15_readings.summary


def union(runs: Sequence[Any]) -> Any:
    """One ``LoadedRun`` holding every table of ``runs`` (disjoint instance ids, one config up to the split
    name), instances in id order (the re-split study's order), so calibrations treat it as one pool."""
    from probecommit.runner.replay import LoadedRun

    def cat(name: str) -> pd.DataFrame:
        return pd.concat([r.table(name) for r in runs], ignore_index=True)

    instances = pd.concat([r.instances for r in runs], ignore_index=True)
    instances = instances.sort_values("instance_id").reset_index(drop=True)
    return LoadedRun(runs[0].path, runs[0].config, instances, cat("probes"), cat("episodes"), cat("engine_cache"),
                     runs[0].manifest)


def union_rows(pool: Any, alpha: float, count: int, seed: int, k: int, boot_seed: int,
               e55: pd.DataFrame | None = None) -> pd.DataFrame:
    """E118's per-split rows of ``pool`` with both calibrations' columns (``c5_*`` and ``c15_*``); ``e55``: the
    pool's :func:`~probecommit.studies.explain.ex5_calibration.resplit_costs` rows when computed already."""
    from probecommit.studies.insertion import resplit_table

    rows = ex15_readings.pool_rows(POOL, pool.episodes, alpha, count, seed)
    study = resplit_table(pool, alpha, count, seed, k, boot_seed)
    if e55 is None:
        e55 = pool_costs(pool, alpha, count, seed, k, boot_seed)
    return ex15_readings.margin_columns(rows, study, e55.drop(columns=["part", "lo", "hi", "gamma"]))


def pool_costs(pool: Any, alpha: float, count: int, seed: int, k: int, boot_seed: int) -> pd.DataFrame:
    """The pool's E55 rows (``resplit_costs`` over budgets 1..k); ``pool``: a ``LoadedRun`` or the runs folder."""
    from probecommit.studies.explain.ex5_calibration import resplit_costs

    pool = _union_of(pool) if isinstance(pool, Path) else pool
    return resplit_costs(pool, alpha, count, seed, list(range(1, k + 1)), RESAMPLES, boot_seed)


def _union_of(runs_dir: Path) -> Any:
    from probecommit.runner.replay import load_run

    return union([load_run(runs_dir / r) for r in RUNS])


def rows_of(runs_dir: Path, alpha: float, count: int, seed: int, k: int, boot_seed: int) -> pd.DataFrame | None:
    """The step's rows from the insertion runs folder (None when a run is missing); picklable arguments only,
    so the step can run in a process of its own. Its re-split costs run in a process of their own too (issue 42,
    target 4): the pool's whole-run beliefs at every budget on top of what the re-split study left took this
    process to 535 MB."""
    from probecommit.runner.aside import in_own_process

    if not all((runs_dir / r / "episodes.parquet").is_file() for r in RUNS):
        return None
    e55 = in_own_process(pool_costs, runs_dir, alpha, count, seed, k, boot_seed)
    return union_rows(_union_of(runs_dir), alpha, count, seed, k, boot_seed, e55)


def run(explain: Any) -> None:
    """The explain step: stored rows and keys of the ``ex15_union`` group, computed in the explain target's process
    of its own beside the later steps (it reads only the insertion study's runs and fills a group nobody else
    fills; its 100 calibrations are minutes of CPU on a loaded machine)."""
    explain.progress("explain: the re-splits of the literal Split B pool (E119, in a process of its own)", 0, 1)
    p = explain.p

    def done(rows: pd.DataFrame | None) -> None:
        if rows is not None:
            explain.stored[STORED] = rows
            explain.res[GROUP].update(summary(rows))

    explain.submit(done, rows_of, explain.ins, float(p.alpha), int(p.resplits["count"]),
                              int(p.resplits["seed"]), int(p.budgets["cover"]), int(p.bootstrap.seed))
